"""The package is typed (``py.typed``): mypy in strict mode finds nothing in it."""

from __future__ import annotations

from pathlib import Path

from mypy import api


def test_the_package_type_checks_strictly(tmp_path: Path) -> None:
    package = Path(__file__).resolve().parent.parent
    out, err, status = api.run([
        "--config-file", str(package / "pyproject.toml"),
        "--cache-dir", str(tmp_path / "mypy-cache"),
        str(package / "dualrep"),
    ])
    assert status == 0, out + err

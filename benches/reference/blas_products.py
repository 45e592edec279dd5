"""The products `layer_rates` times, on the BLAS libraries the peers use: Intel MKL (PyTorch's
CPU matmul) and OpenBLAS (NumPy's), one thread, so that our kernels' fraction of the FMA peak
can be set against what a vendor's sgemm reaches on the same shapes and the same machine.

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
        python3 benches/reference/blas_products.py --seconds 0.3

Each product of one critic layer (`n_in:n_out`, batch 512) in nn.Linear's layout: the forward
`X W^T + b` (addmm), the weight gradient `dZ^T X` and the input gradient `dZ W`. As in
`layer_rates`: the median of single calls, the operands cycled through 8 copies. Prints one
line per layer with microseconds and GFLOP/s (2 n_in n_out batch flops per product); divide by
the FMA peak `layer_rates` prints in the same round for a fraction of it. Then MKL on square
products (64 to 2048 cubed): how near the peak a vendor's sgemm gets on large shapes.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

# One thread for every library, before any of them loads.
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402
import torch  # noqa: E402

COPIES = 8
BATCH = 512


def median_seconds(call: Callable[[int], object], seconds: float) -> float:
    """The median time of single calls of `call(copy)` over `seconds`."""
    times: list[float] = []
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        t = time.perf_counter()
        call(len(times) % COPIES)
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def layer(n_in: int, n_out: int, seconds: float) -> dict[str, float]:
    """Median seconds of each product of one layer, on MKL (torch) and OpenBLAS (numpy)."""
    gen = torch.Generator().manual_seed(n_in * 1000 + n_out)

    def copies(*shape: int) -> list[torch.Tensor]:
        return [torch.randn(*shape, generator=gen) / 10 for _ in range(COPIES)]

    x, w, b = copies(BATCH, n_in), copies(n_out, n_in), copies(n_out)
    dz = copies(BATCH, n_out)
    z, dw, dx = copies(BATCH, n_out), copies(n_out, n_in), copies(BATCH, n_in)
    xn, wn, bn, dzn = ([t.numpy() for t in ts] for ts in (x, w, b, dz))
    zn, dwn, dxn = ([t.numpy() for t in ts] for ts in (z, dw, dx))
    out: dict[str, float] = {}
    with torch.no_grad():
        out["mkl forward"] = median_seconds(
            lambda c: torch.addmm(b[c], x[c], w[c].t(), out=z[c]), seconds
        )
        out["mkl forward (no bias)"] = median_seconds(
            lambda c: torch.mm(x[c], w[c].t(), out=z[c]), seconds
        )
        out["mkl weight grad"] = median_seconds(
            lambda c: torch.mm(dz[c].t(), x[c], out=dw[c]), seconds
        )
        out["mkl input grad"] = median_seconds(
            lambda c: torch.mm(dz[c], w[c], out=dx[c]), seconds
        )
    out["openblas forward"] = median_seconds(
        lambda c: np.add(np.matmul(xn[c], wn[c].T, out=zn[c]), bn[c], out=zn[c]), seconds
    )
    out["openblas weight grad"] = median_seconds(
        lambda c: np.matmul(dzn[c].T, xn[c], out=dwn[c]), seconds
    )
    out["openblas input grad"] = median_seconds(
        lambda c: np.matmul(dzn[c], wn[c], out=dxn[c]), seconds
    )
    return out


def square(n: int, seconds: float) -> float:
    """MKL's GFLOP/s on an `n`-cubed product: how near the peak it gets on large shapes."""
    a, b, c = (torch.randn(n, n) for _ in range(3))
    with torch.no_grad():
        t = median_seconds(lambda _: torch.mm(a, b, out=c), seconds)
    return 2.0 * n**3 / t / 1e9


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=0.3, help="per product")
    args = parser.parse_args()
    torch.set_num_threads(1)
    blas = "mkl" if "BLAS_INFO=mkl" in torch.__config__.show() else "not mkl"
    np_blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]["name"]
    print(f"torch {torch.__version__} ({blas}), numpy {np.__version__} ({np_blas}), 1 thread")
    for n_in, n_out in [(10, 400), (400, 300), (300, 1)]:
        flop = 2.0 * n_in * n_out * BATCH
        times = layer(n_in, n_out, args.seconds)
        cells = " | ".join(
            f"{name} {t * 1e6:7.1f} us {flop / t / 1e9:5.0f} GFLOP/s" for name, t in times.items()
        )
        print(f"{n_in:>4}:{n_out:<4} {cells}")
    sizes = (64, 128, 256, 1024, 2048)
    rates = ", ".join(f"{n}^3 {square(n, args.seconds):.0f}" for n in sizes)
    print(f"mkl square products (GFLOP/s): {rates}")


if __name__ == "__main__":
    main()

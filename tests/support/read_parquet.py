"""Read a dualrep Parquet export with pyarrow, as another tool would, and print what the
Rust test checks as JSON: the row count, the columns and their types, and the table's rows."""

import json
import sys

import pyarrow.parquet as pq


def main(path: str) -> None:
    table = pq.read_table(path)
    print(
        json.dumps(
            {
                "num_rows": table.num_rows,
                "columns": {f.name: str(f.type) for f in table.schema},
                "rows": table.to_pylist(),
            }
        )
    )


if __name__ == "__main__":
    main(sys.argv[1])

"""CSV reader speed: a 1M-row × 8-column raw-samples CSV read by gyropipe's reader
(kind ``samples``: header recognition, units, canonical conventions, contract-typed table)
and by ``pandas.read_csv``, plain and with the unit conversion a pandas user does by hand;
``pyarrow.csv.read_csv`` (the parser ours runs on, told where the header is) for scale.

    .venv/bin/python benchmarks/bench_csv.py [--rows N] [--repeat R]

Prints the best of R runs in ms and each time relative to ours; exits 1 if the tables
disagree.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv

from pipeline.io.csv import read

COLUMNS = {  # header cell → (canonical column, factor to its canonical unit)
    "time [s]": ("time", 1.0),
    "md [ft]": ("md", 0.3048),
    "gyro_x [deg/s]": ("gyro_x", 3600.0),
    "gyro_y [deg/s]": ("gyro_y", 3600.0),
    "gyro_z [deg/s]": ("gyro_z", 3600.0),
    "acc_x [g]": ("acc_x", 9.80665),
    "acc_y [g]": ("acc_y", 9.80665),
    "acc_z [g]": ("acc_z", 9.80665),
}


def make_file(path: Path, rows: int) -> None:
    """A raw log at 100 Hz: MD in ft, rates in deg/s, accelerations in g, full precision."""
    rng = np.random.default_rng(7)
    values = [
        np.arange(rows) / 100.0,
        np.cumsum(rng.uniform(0.0, 0.02, rows)),
        *(rng.normal(0.0, 0.01, rows) for _ in range(3)),
        *(rng.normal(mean, 0.002, rows) for mean in (0.0, 0.0, 1.0)),
    ]
    with path.open("wb") as fh:
        fh.write(b"# raw gyro log, tool SN-7\n")
        fh.write((",".join(COLUMNS) + "\n").encode())
        table = pa.table([pa.array(v) for v in values], names=list(COLUMNS))
        pacsv.write_csv(table, fh, pacsv.WriteOptions(include_header=False))


def ours(path: Path) -> dict[str, np.ndarray]:
    table, _ = read(path, "samples", None)
    return {name: table.column(name).to_numpy() for name, _ in COLUMNS.values()}


def pandas_plain(path: Path) -> pd.DataFrame:
    return pd.read_csv(path, comment="#")


def pandas_units(path: Path) -> dict[str, np.ndarray]:
    """What a pandas user writes: read, then rename and scale each column by hand."""
    frame = pd.read_csv(path, comment="#")
    return {name: frame[cell].to_numpy() * f for cell, (name, f) in COLUMNS.items()}


def pyarrow_plain(path: Path) -> pa.Table:
    return pacsv.read_csv(path, read_options=pacsv.ReadOptions(skip_rows=1))


def best(func: Callable[[Path], Any], path: Path, repeat: int) -> tuple[float, Any]:
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = func(path)
        times.append(time.perf_counter() - start)
    return min(times) * 1e3, result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "samples.csv"
        make_file(path, args.rows)
        size = path.stat().st_size / 1e6
        print(f"{args.rows:,} rows × {len(COLUMNS)} columns, {size:.0f} MB; best of {args.repeat}")
        ms_ours, got = best(ours, path, args.repeat)
        ms_plain, _ = best(pandas_plain, path, args.repeat)
        ms_units, expected = best(pandas_units, path, args.repeat)
        ms_arrow, _ = best(pyarrow_plain, path, args.repeat)
    print(f"{'reader':<34}{'ms':>8}{'× ours':>9}")
    for label, ms in (
        ("gyropipe csv (samples)", ms_ours),
        ("pandas.read_csv", ms_plain),
        ("pandas.read_csv + units by hand", ms_units),
        ("pyarrow.csv.read_csv", ms_arrow),
    ):
        print(f"{label:<34}{ms:>8.0f}{ms / ms_ours:>9.2f}")
    worst = max(float(np.max(np.abs(got[n] - expected[n]))) for n in expected)
    print(f"largest difference to pandas + units: {worst:.3g}")
    return 0 if worst <= 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())

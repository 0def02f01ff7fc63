"""LAS reading speed: the built-in reader against ``lasio.read`` on a 1M-row × 8-curve file.

Writes a LAS 2.0 raw-sensor log (TIME index, DEPT, three accelerometers, three gyros; some
-999.25 nulls) to a temporary directory, reads it with ``lasio.read`` and with the ``las``
reader (kind ``samples``, and kind ``log``: every curve as logged), best of ``--repeat`` runs
each, checks every value and null position is identical, and prints the times and their
ratios. Target: ≥ 10× for both.

    python benchmarks/bench_las.py [--rows 1000000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import timeit
from pathlib import Path

import lasio
import numpy as np

from pipeline.io.las import read_las
from pipeline.io.las_options import LasOptions

CURVES = [
    ("TIME", "S", "elapsed time"),
    ("DEPT", "M", "measured depth"),
    ("GX", "M/S2", "accelerometer x"),
    ("GY", "M/S2", "accelerometer y"),
    ("GZ", "M/S2", "accelerometer z"),
    ("WX", "DEG/HR", "gyro x"),
    ("WY", "DEG/HR", "gyro y"),
    ("WZ", "DEG/HR", "gyro z"),
]
COLUMNS = ["time", "md", "acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z"]
TARGET = 10.0


def write_file(path: Path, rows: int) -> None:
    """A LAS 2.0 file of ``rows`` samples at 100 Hz with fixed-width columns."""
    rng = np.random.default_rng(7)
    time = np.arange(rows) / 100.0
    md = 1000.0 + np.cumsum(rng.uniform(0.0, 0.01, rows))
    acc = rng.normal([0.1, -0.2, 9.8], 0.01, (rows, 3))
    gyro = rng.normal([5.0, -3.0, 12.0], 0.5, (rows, 3))
    data = np.column_stack([time, md, acc, gyro])
    data[rng.integers(0, rows, rows // 1000), 3] = -999.25  # nulls in GY
    header = [
        "~Version",
        " VERS.   2.0 : CWLS log ASCII Standard - version 2.0",
        " WRAP.   NO  : one line per step",
        "~Well",
        f" STRT.S  {time[0]:.2f} : first time",
        f" STOP.S  {time[-1]:.2f} : last time",
        " STEP.S  0.01 : step",
        " NULL.   -999.25 : null value",
        " WELL.   BENCH-1 : well",
        "~Curve",
        *(f" {m:<5}.{u:<7} : {d}" for m, u, d in CURVES),
        "~A",
    ]
    with path.open("w") as fh:
        fh.write("\n".join(header) + "\n")
        np.savetxt(fh, data, fmt=["%10.2f", "%12.4f"] + ["%12.6f"] * 3 + ["%11.5f"] * 3)


def best(fn: object, repeat: int) -> float:
    return min(timeit.repeat(fn, number=1, repeat=repeat))  # type: ignore[arg-type]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    options = LasOptions()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.las"
        write_file(path, args.rows)
        size = path.stat().st_size / 1e6
        ours = best(lambda: read_las(path, "samples", options), args.repeat)
        log = best(lambda: read_las(path, "log", options), args.repeat)
        theirs = best(lambda: lasio.read(str(path)), args.repeat)
        table, _ = read_las(path, "samples", options)
        log_table, _ = read_las(path, "log", options)
        las = lasio.read(str(path))
    same = all(
        np.array_equal(
            table.column(name).to_numpy(zero_copy_only=False),
            las.curves[i].data,
            equal_nan=True,
        )
        and np.array_equal(
            log_table.column(mnemonic).to_numpy(zero_copy_only=False),
            las.curves[i].data,
            equal_nan=True,
        )
        for i, (name, (mnemonic, _, _)) in enumerate(zip(COLUMNS, CURVES, strict=True))
    )
    ratio, log_ratio = theirs / ours, theirs / log
    print(f"file: {args.rows:,} rows x {len(CURVES)} curves, {size:.0f} MB")
    print(f"lasio.read:            {theirs * 1e3:8.0f} ms")
    print(f"gyropipe las, samples: {ours * 1e3:8.0f} ms  {ratio:5.1f}x (target >= {TARGET:g}x)")
    print(f"gyropipe las, log:     {log * 1e3:8.0f} ms  {log_ratio:5.1f}x")
    print(f"values and nulls identical to lasio: {same}")
    return 0 if same and min(ratio, log_ratio) >= TARGET else 1


if __name__ == "__main__":
    sys.exit(main())

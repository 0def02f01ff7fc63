"""LAS reading speed in one run: the built-in reader against ``lasio.read`` and against the
pyarrow floor, on a 1M-row × 8-curve file.

Writes a LAS 2.0 raw-sensor log (TIME index, DEPT, three accelerometers, three gyros,
fixed-width columns; some -999.25 nulls) to a temporary directory and times, interleaved:

* ``lasio.read``;
* the ``las`` reader, kind ``samples`` (canonical columns and units) and kind ``log``
  (every curve as logged);
* the **pyarrow floor**: ``pyarrow.csv.read_csv`` parsing the same ``~A`` data section
  already repacked in memory (one space between values, none at line starts or ends; the
  repacking is not timed), every column as float64, on the readers' threads
  (:func:`~pipeline.io.threads.reader_threads`, or ``--threads N``).
  No reader of the file can beat it by parsing with ``pyarrow.csv``: ours also reads the
  file, checks and rewrites the bytes, and builds the checked table.

Medians of ``--rounds`` interleaved rounds (wall and CPU time), checks every value and null
position is identical to lasio's, and prints the ratios and ``uptime`` before and after.
Targets: lasio / ours ≥ 12, ours / floor ≤ 1.5.

    python benchmarks/bench_las.py [--rows 1000000] [--rounds 3]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import lasio
import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv

from pipeline.io.arrow_text import read_options
from pipeline.io.las import read_las
from pipeline.io.las.options import LasOptions
from pipeline.io.threads import reader_threads, set_reader_threads
from timing import interleaved, table, uptime

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
LASIO_TARGET, FLOOR_TARGET = 12.0, 1.5


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


def repacked(path: Path) -> bytes:
    """The ``~A`` section with one space between values (by Python, untimed)."""
    text = path.read_bytes()
    data = text[text.index(b"\n", text.index(b"~A")) + 1 :]
    return b"\n".join(b" ".join(line.split()) for line in data.splitlines() if line.strip())


def floor(packed: bytes) -> pa.Table:
    names = [c[0] for c in CURVES]
    return pacsv.read_csv(
        pa.BufferReader(packed),
        read_options=read_options(names),
        parse_options=pacsv.ParseOptions(delimiter=" ", quote_char=False, double_quote=False),
        convert_options=pacsv.ConvertOptions(
            column_types=dict.fromkeys(names, pa.float64()), check_utf8=False
        ),
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument(
        "--threads",
        type=int,
        default=None,
        help="the readers' threads (default: every core this process may run on)",
    )
    args = parser.parse_args()
    set_reader_threads(args.threads if args.threads is not None else reader_threads())
    options = LasOptions()
    print(f"before: {uptime()}")
    print(f"readers' threads (ours and the floor; pyarrow's pool): {reader_threads()}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.las"
        write_file(path, args.rows)
        size = path.stat().st_size / 1e6
        packed = repacked(path)
        print(
            f"file: {args.rows:,} rows × {len(CURVES)} curves, {size:.0f} MB "
            f"(data section repacked: {len(packed) / 1e6:.0f} MB); "
            f"median of {args.rounds} interleaved rounds"
        )
        timings = interleaved(
            {
                "gyropipe las, samples": lambda: read_las(path, "samples", options)[0],
                "gyropipe las, log": lambda: read_las(path, "log", options)[0],
                "lasio.read": lambda: lasio.read(str(path)),
                "pyarrow floor (repacked ~A, parse only)": lambda: floor(packed),
            },
            args.rounds,
        )
    print(table(timings, "gyropipe las, samples"))
    ours, log = timings["gyropipe las, samples"], timings["gyropipe las, log"]
    las, low = timings["lasio.read"], timings["pyarrow floor (repacked ~A, parse only)"]
    same = all(
        np.array_equal(
            ours.result.column(name).to_numpy(zero_copy_only=False),
            las.result.curves[i].data,
            equal_nan=True,
        )
        and np.array_equal(
            log.result.column(mnemonic).to_numpy(zero_copy_only=False),
            las.result.curves[i].data,
            equal_nan=True,
        )
        for i, (name, (mnemonic, _, _)) in enumerate(zip(COLUMNS, CURVES, strict=True))
    )
    ratio, log_ratio = las.median / ours.median, las.median / log.median
    above = ours.median / low.median
    print(f"lasio / ours: samples {ratio:.1f}×, log {log_ratio:.1f}× (target ≥ {LASIO_TARGET:g})")
    print(
        f"ours / pyarrow floor: samples {above:.2f}, log {log.median / low.median:.2f} "
        f"(target ≤ {FLOOR_TARGET:g})"
    )
    print(f"values and nulls identical to lasio: {same}")
    print(f"after: {uptime()}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

"""LAS reading speed in one run: the built-in reader against ``lasio.read`` and against the
pyarrow floor, on a 1M-row × 8-curve file.

Writes a LAS 2.0 raw-sensor log (TIME index, DEPT, three accelerometers, three gyros,
fixed-width columns; some -999.25 nulls) to a temporary directory and, at each reader
thread count (``--threads``; by default 1, powers of two and every core this process may
run on: 1 and 2 on two cores), times interleaved:

* the ``las`` reader, kind ``samples`` (canonical columns and units) and kind ``log``
  (every curve as logged);
* the **pyarrow floor**: ``pyarrow.csv.read_csv`` parsing the same ``~A`` data section
  already repacked in memory (one space between values, none at line starts or ends; the
  repacking and the reading of the file are not timed), every column as float64, on the
  same thread count. No reader of the file can beat it by parsing with ``pyarrow.csv``:
  ours also reads the file, checks and rewrites the bytes, and builds the checked table.

Then, at the largest thread count, ``lasio.read`` against both kinds. Medians (wall, and
CPU: this process's user + system time, ``resource.getrusage``); prints each reader's CPU
and wall time over the floor's at every thread count with the load, checks every value
and null position is identical to lasio's, and prints ``uptime`` before and after.
Targets: lasio / ours ≥ 12; ours / floor ≤ 1.2 in CPU on two cores and ≤ 2 in wall on a
many-core machine.

    python benchmarks/bench_las.py [--rows 1000000] [--rounds 7] [--threads 1 2]
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
from pipeline.io.threads import available_cores, set_reader_threads
from timing import floor_lines, interleaved, table, thread_counts, uptime

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
LASIO_TARGET, CPU_TARGET, WALL_TARGET = 12.0, 1.2, 2.0
FLOOR = "pyarrow floor (repacked ~A, parse only)"


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
    parser.add_argument("--rounds", type=int, default=7, help="rounds of ours and the floor")
    parser.add_argument("--lasio-rounds", type=int, default=3, help="rounds with lasio")
    parser.add_argument(
        "--threads",
        type=int,
        nargs="+",
        default=None,
        help="reader thread counts (default: 1, powers of two, every core this process may run on)",
    )
    args = parser.parse_args()
    counts = args.threads or thread_counts(available_cores())
    options = LasOptions()
    print(f"before: {uptime()}")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.las"
        write_file(path, args.rows)
        size = path.stat().st_size / 1e6
        packed = repacked(path)
        print(
            f"file: {args.rows:,} rows × {len(CURVES)} curves, {size:.0f} MB "
            f"(data section repacked: {len(packed) / 1e6:.0f} MB); medians of "
            f"{args.rounds} interleaved rounds at each reader thread count {counts} "
            f"(ours and the floor on that many threads; pyarrow's pool that size)"
        )
        ours = {
            "gyropipe las, samples": lambda: read_las(path, "samples", options)[0],
            "gyropipe las, log": lambda: read_las(path, "log", options)[0],
        }
        for warm_up in ours.values():  # imports and first-use costs, untimed
            warm_up()
        ratios: dict[int, list[float]] = {}
        for count in counts:
            set_reader_threads(count)
            timings = interleaved(ours | {FLOOR: lambda: floor(packed)}, args.rounds)
            print("\n".join(floor_lines(count, timings, FLOOR, list(ours))))
            low = timings[FLOOR]
            ratios[count] = [
                r
                for t in (timings[name] for name in ours)
                for r in (t.cpu_median / low.cpu_median, t.median / low.median)
            ]
        set_reader_threads(counts[-1])
        print(f"\nlasio at {counts[-1]} reader threads, {args.lasio_rounds} interleaved rounds:")
        peers = ours | {"lasio.read": lambda: lasio.read(str(path))}
        timings = interleaved(peers, args.lasio_rounds)
    print(table(timings, "gyropipe las, samples"))
    samples, log = timings["gyropipe las, samples"], timings["gyropipe las, log"]
    las = timings["lasio.read"]
    same = all(
        np.array_equal(
            samples.result.column(name).to_numpy(zero_copy_only=False),
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
    print(
        f"\nlasio / ours: samples {las.median / samples.median:.1f}×, log "
        f"{las.median / log.median:.1f}× (target ≥ {LASIO_TARGET:g})"
    )
    for count, (s_cpu, s_wall, l_cpu, l_wall) in ratios.items():
        print(
            f"ours / pyarrow floor at {count} threads: CPU samples {s_cpu:.2f}, log {l_cpu:.2f} "
            f"(target ≤ {CPU_TARGET:g}); wall samples {s_wall:.2f}, log {l_wall:.2f} "
            f"(target ≤ {WALL_TARGET:g} on a many-core machine)"
        )
    print(f"values and nulls identical to lasio: {same}")
    print(f"after: {uptime()}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

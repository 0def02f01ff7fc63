"""CSV reader speed against the pyarrow floor and pandas' C engine, in one run: a 1M-row ×
8-column raw-samples CSV read by gyropipe's reader (kind ``samples``: header recognition,
units, canonical conventions, contract-typed table) and by ``pandas.read_csv(engine="c")``,
plain and with the unit conversion a pandas user does by hand; for scale,
``pyarrow.csv.read_csv`` with its
defaults and told the columns are float64 without quotes (the parse our reader builds on), and
``polars.read_csv`` (Rust, multi-threaded; the ``bench`` extra) typed the same way. Two
files: (a) one ``#`` title line above a ``name [unit]`` header; (b) a title block of
``key: value`` lines (well metadata, read by ours; skipped by pandas, told how many lines)
above a header of vendor names with units in brackets or parentheses.

    .venv/bin/python benchmarks/bench_csv.py [--rows N] [--rounds R] [--threads 1 2]

The **floor** is ``pyarrow.csv.read_csv`` of the same file told the columns are float64
without quotes (the parse our reader builds on; no header recognition, units, checks or
table). At each reader thread count (``--threads``; by default 1, powers of two and every
core this process may run on: 1 and 2 on two cores) ours and the floor run interleaved,
pyarrow's pool sized to the count; each line gives ours / floor in CPU (this process's
user + system time, ``resource.getrusage``) and in wall, with the load. Then every peer at
the largest count, medians of R interleaved rounds, each as peer / ours (above 1: ours is
faster). Prints ``uptime`` before and after. Targets: ours / floor ≤ 1.2 in CPU on two
cores, ≤ 2 in wall on a many-core machine. Exits 1 if our values differ from pandas + units.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.csv as pacsv

from pipeline.io.csv import read
from pipeline.io.threads import available_cores, set_reader_threads
from timing import floor_lines, interleaved, table, thread_counts, uptime

NAMES = ("time", "md", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z")
FACTORS = (1.0, 0.3048, 3600.0, 3600.0, 3600.0, 9.80665, 9.80665, 9.80665)
HEADERS = {
    "plain": (
        "time [s]",
        "md [ft]",
        *(f"gyro_{a} [deg/s]" for a in "xyz"),
        *(f"acc_{a} [g]" for a in "xyz"),
    ),
    "titled": (
        "Time (s)",
        "Measured Depth [ft]",
        *(f"Rate {a} (deg/s)" for a in "XYZ"),
        *(f"Accel {a} [g]" for a in "XYZ"),
    ),
}
TITLE = (
    "Gyro raw data export",
    "Well: BENCH-1",
    "Company: North Oil",
    "Field: Wildcat",
    "Tool: MEMS gyro",
    "Serial: SN-7",
    "north_reference: true",
    "",
)
CPU_TARGET, WALL_TARGET = 1.2, 2.0
OURS = "gyropipe csv (samples)"
FLOOR = "pyarrow.csv.read_csv (float64, no quotes)"


def make_file(path: Path, rows: int, layout: str) -> int:
    """A raw log at 100 Hz (MD in ft, rates in deg/s, accelerations in g, full precision);
    the number of lines above the header."""
    rng = np.random.default_rng(7)
    values = [
        np.arange(rows) / 100.0,
        np.cumsum(rng.uniform(0.0, 0.02, rows)),
        *(rng.normal(0.0, 0.01, rows) for _ in range(3)),
        *(rng.normal(mean, 0.002, rows) for mean in (0.0, 0.0, 1.0)),
    ]
    title = ("# raw gyro log, tool SN-7",) if layout == "plain" else TITLE
    with path.open("wb") as fh:
        fh.write(("\n".join(title) + "\n" + ",".join(HEADERS[layout]) + "\n").encode())
        data = pa.table([pa.array(v) for v in values], names=list(HEADERS[layout]))
        pacsv.write_csv(data, fh, pacsv.WriteOptions(include_header=False))
    return len(title)


def candidates(path: Path, skip: int, layout: str) -> dict[str, Callable[[], Any]]:
    headers = HEADERS[layout]

    def ours() -> dict[str, np.ndarray]:
        result, _ = read(path, "samples", None)
        return {name: result.column(name).to_numpy() for name in NAMES}

    def pandas_plain() -> pd.DataFrame:
        return pd.read_csv(path, skiprows=skip, engine="c")

    def pandas_units() -> dict[str, np.ndarray]:
        frame = pd.read_csv(path, skiprows=skip, engine="c")
        return {
            name: frame[cell].to_numpy() * f
            for cell, name, f in zip(headers, NAMES, FACTORS, strict=True)
        }

    def pyarrow_plain() -> pa.Table:
        return pacsv.read_csv(path, read_options=pacsv.ReadOptions(skip_rows=skip))

    def pyarrow_typed() -> pa.Table:
        return pacsv.read_csv(
            path,
            read_options=pacsv.ReadOptions(skip_rows=skip),
            parse_options=pacsv.ParseOptions(quote_char=False, double_quote=False),
            convert_options=pacsv.ConvertOptions(column_types=dict.fromkeys(headers, pa.float64())),
        )

    found = {
        OURS: ours,
        'pandas.read_csv(engine="c")': pandas_plain,
        "pandas.read_csv + units by hand": pandas_units,
        "pyarrow.csv.read_csv (defaults)": pyarrow_plain,
        FLOOR: pyarrow_typed,
    }
    try:
        import polars as pl
    except ImportError:  # the bench extra
        return found

    def polars_typed() -> pa.Table:
        schema = dict.fromkeys(headers, pl.Float64)
        return pl.read_csv(path, skip_rows=skip, schema=schema).to_arrow()

    return found | {"polars.read_csv (float64) → Arrow": polars_typed}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=5, help="rounds with every peer")
    parser.add_argument("--floor-rounds", type=int, default=7, help="rounds of ours and the floor")
    parser.add_argument(
        "--threads",
        type=int,
        nargs="+",
        default=None,
        help="reader thread counts (default: 1, powers of two, every core this process may run on)",
    )
    args = parser.parse_args()
    counts = args.threads or thread_counts(available_cores())
    print(f"before: {uptime()}")
    worst, summary = 0.0, []
    with tempfile.TemporaryDirectory() as tmp:
        for layout in ("plain", "titled"):
            path = Path(tmp) / f"{layout}.csv"
            skip = make_file(path, args.rows, layout)
            size = path.stat().st_size / 1e6
            label = "a" if layout == "plain" else "b"
            print(
                f"\n({label}) {layout}: {args.rows:,} rows × {len(NAMES)} columns, {size:.0f} MB, "
                f"{skip} line(s) above the header; ours and the floor, medians of "
                f"{args.floor_rounds} interleaved rounds at each reader thread count {counts} "
                "(pyarrow's pool that size)"
            )
            found = candidates(path, skip, layout)
            pair = {OURS: found[OURS], FLOOR: found[FLOOR]}
            for warm_up in pair.values():  # imports and first-use costs, untimed
                warm_up()
            for count in counts:
                set_reader_threads(count)
                timings = interleaved(pair, args.floor_rounds)
                print("\n".join(floor_lines(count, timings, FLOOR, [OURS])))
                t, low = timings[OURS], timings[FLOOR]
                summary.append(
                    f"({label}) at {count} threads: ours / floor CPU "
                    f"{t.cpu_median / low.cpu_median:.2f} (target ≤ {CPU_TARGET:g}), wall "
                    f"{t.median / low.median:.2f} (target ≤ {WALL_TARGET:g} on a many-core machine)"
                )
            print(f"every peer at {counts[-1]} reader threads, {args.rounds} interleaved rounds:")
            timings = interleaved(found, args.rounds)
            print(table(timings, OURS))
            got = timings[OURS].result
            expected = timings["pandas.read_csv + units by hand"].result
            worst = max(worst, *(float(np.max(np.abs(got[n] - expected[n]))) for n in NAMES))
            ratio = timings['pandas.read_csv(engine="c")'].median / timings[OURS].median
            summary.append(f"({label}) pandas / ours {ratio:.2f} in wall (for scale)")
    print()
    print("\n".join(summary))
    print(f"largest difference to pandas + units: {worst:.3g}")
    print(f"after: {uptime()}")
    return 0 if worst <= 1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())

"""LAS reading speed in one run: the built-in reader against ``lasio.read`` and against the
pyarrow floor, on a 1M-row × 8-curve file.

Writes a LAS 2.0 raw-sensor log (TIME index, DEPT, three accelerometers, three gyros,
fixed-width columns as :data:`FORMATS` lays them out; some -999.25 nulls) to a temporary
directory and, at each reader thread count (``--threads``; by default 1, powers of two and
every core this process may run on: 1 and 2 on two cores), times interleaved:

* the ``las`` reader, kind ``samples`` (canonical columns and units) and kind ``log``
  (every curve as logged);
* the **pyarrow floor**, the least any reader of the file must do: map the file, find
  ``~A``, copy its lines into a buffer held across reads (its allocation and first page
  faults are not counted) with a comma at the one blank byte between each two columns that
  the benchmark laid out (known, not looked for: no check of any kind), the commas written
  in the copy itself (:data:`PATTERN` XORed over the lines), and parse the section, padding
  and all, with ``pyarrow.csv`` as float64 columns on the same thread count, no null
  strings looked for. pyarrow has no delimiter "one or more spaces", so the commas are the
  least rewrite that makes the section parseable; it trims the padding around each value
  itself. Until 2026-12-02 (evening) the floor read the file with ``read()`` (~40 ms of
  kernel copy a read against ~12 ms copied from the map), wrote each comma column in a
  strided pass of its own and let pyarrow compare every cell with its default null
  strings: ~15 % above the least;
* the **old floor**, printed beside it and labelled: ``pyarrow.csv.read_csv`` of the same
  ``~A`` section already repacked in memory by Python (one space between values, none at
  line starts or ends), neither the reading of the file nor the repacking timed. It skips
  work every reader of this file must do: the file is never read and the 27 MB of padding
  (of 99 MB) never parsed; that is why the floor changed (2026-12-02, issue #30);
* ``parse only``: the floor's parse alone, of the section with its commas already in
  memory, so that what the padding costs the parse (this against the old floor) and what
  reading the file and writing the commas cost (the floor against this) can be told apart.

Then, at the largest thread count, ``lasio.read`` against both kinds. Medians (wall, and
CPU: this process's user + system time, ``resource.getrusage``); prints each reader's CPU
and wall time over each floor's at every thread count with the load, checks every value and
null position is identical to lasio's, and prints ``uptime`` before and after.
Targets: lasio / ours ≥ 12; ours / floor ≤ 1.2 in CPU on two cores and ≤ 2 in wall on a
many-core machine.

    python benchmarks/bench_las.py [--rows 1000000] [--rounds 7] [--threads 1 2]
"""

from __future__ import annotations

import argparse
import mmap
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
from timing import Timing, floor_lines, interleaved, table, thread_counts, uptime

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
FORMATS = ["%10.2f", "%12.4f"] + ["%12.6f"] * 3 + ["%11.5f"] * 3
"""One per curve, values right-aligned, one space between columns (``np.savetxt``)."""
WIDTH = sum(int(f[1:].split(".")[0]) + 1 for f in FORMATS)
"""Bytes of each data line, its LF included."""
SEPARATORS = np.cumsum([int(f[1:].split(".")[0]) + 1 for f in FORMATS[:-1]]) - 1
"""The blank byte between each two columns of a data line."""
PATTERN = np.tile(
    np.where(np.isin(np.arange(WIDTH), SEPARATORS), ord(" ") ^ ord(","), 0).astype(np.uint8),
    32768 // WIDTH,
)
"""XOR making a comma of each :data:`SEPARATORS` space of whole lines (32 KiB of them)."""
LASIO_TARGET, CPU_TARGET, WALL_TARGET = 12.0, 1.2, 2.0
FLOOR = "pyarrow floor (file read, commas, parse)"
OLD_FLOOR = "old floor (repacked in memory, parse)"
PARSE = "parse only (~A with commas, in memory)"


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
        np.savetxt(fh, data, fmt=FORMATS)


def repacked(path: Path) -> bytes:
    """The ``~A`` section with one space between values (by Python, untimed)."""
    text = path.read_bytes()
    data = text[text.index(b"\n", text.index(b"~A")) + 1 :]
    return b"\n".join(b" ".join(line.split()) for line in data.splitlines() if line.strip())


def floor(path: Path, buffer: bytearray) -> pa.Table:
    """The file mapped, its ``~A`` lines copied into ``buffer`` with a comma at each
    :data:`SEPARATORS` byte (one pass: :data:`PATTERN` XORed over the lines as they are
    copied) and the section parsed."""
    with path.open("rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as text:
        start = text.find(b"\n", text.find(b"~A")) + 1
        section = np.frombuffer(text, np.uint8, offset=start)
        out = np.frombuffer(buffer, np.uint8, count=section.size)
        whole = section.size // PATTERN.size * PATTERN.size
        tiles = (-1, PATTERN.size)
        np.bitwise_xor(section[:whole].reshape(tiles), PATTERN, out=out[:whole].reshape(tiles))
        np.bitwise_xor(section[whole:], PATTERN[: section.size - whole], out=out[whole:])
        size = section.size
        del section  # the map closes with no view of it left
    return parse(memoryview(buffer)[:size], ",")


def with_commas(path: Path) -> bytes:
    """The ``~A`` section with a comma at each :data:`SEPARATORS` byte (untimed)."""
    text = path.read_bytes()
    grid = np.frombuffer(text, np.uint8, offset=text.index(b"\n", text.index(b"~A")) + 1).copy()
    grid.reshape(-1, WIDTH)[:, SEPARATORS] = ord(",")
    return grid.tobytes()


def parse(section: bytes | memoryview, delimiter: str) -> pa.Table:
    """Every column of the ``~A`` lines ``section`` as float64, nothing checked."""
    names = [c[0] for c in CURVES]
    return pacsv.read_csv(
        pa.BufferReader(pa.py_buffer(section)),
        read_options=read_options(names),
        parse_options=pacsv.ParseOptions(delimiter=delimiter, quote_char=False, double_quote=False),
        convert_options=pacsv.ConvertOptions(
            column_types=dict.fromkeys(names, pa.float64()), null_values=[], check_utf8=False
        ),
    )


def ratio(timings: dict[str, Timing], low: str, kind: str) -> float:
    """Our ``kind``'s median wall time over the floor ``low``'s."""
    return timings[f"gyropipe las, {kind}"].median / timings[low].median


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--rounds", type=int, default=7, help="rounds of ours and the floor")
    parser.add_argument(
        "--lasio-rounds", type=int, default=3, help="rounds with lasio (0: none, no comparison)"
    )
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
        packed, commas = repacked(path), with_commas(path)
        buffer = bytearray(path.stat().st_size)  # the floor's, held: allocated untimed
        print(
            f"file: {args.rows:,} rows × {len(CURVES)} curves, {size:.0f} MB "
            f"(data section {len(commas) / 1e6:.0f} MB, repacked {len(packed) / 1e6:.0f} MB); "
            f"medians of {args.rounds} interleaved rounds at each reader thread count "
            f"{counts} (ours and the floors on that many threads; pyarrow's pool that size)"
        )
        ours = {
            "gyropipe las, samples": lambda: read_las(path, "samples", options)[0],
            "gyropipe las, log": lambda: read_las(path, "log", options)[0],
        }
        floors = {
            FLOOR: lambda: floor(path, buffer),
            OLD_FLOOR: lambda: parse(packed, " "),
            PARSE: lambda: parse(commas, ","),
        }
        for warm_up in (ours | floors).values():  # imports and first-use costs, untimed
            warm_up()
        ratios: dict[int, dict[str, Timing]] = {}
        for count in counts:
            set_reader_threads(count)
            ratios[count] = timings = interleaved(ours | floors, args.rounds)
            print("\n".join(floor_lines(count, timings, FLOOR, list(ours))))
            lines = floor_lines(count, timings, OLD_FLOOR, [*ours, FLOOR, PARSE], "old floor")
            print("\n".join(lines))
        set_reader_threads(counts[-1])
        if args.lasio_rounds:
            print(
                f"\nlasio at {counts[-1]} reader threads, {args.lasio_rounds} interleaved rounds:"
            )
            peers = ours | {"lasio.read": lambda: lasio.read(str(path))}
            with_lasio = interleaved(peers, args.lasio_rounds)
    for count, timings in ratios.items():
        for low in (FLOOR, OLD_FLOOR):
            print(
                f"ours / {low.split(' (')[0]} at {count} threads, CPU median (least of "
                f"{args.rounds}): "
                + ", ".join(
                    f"{name.split(', ')[1]} {t.cpu_median / timings[low].cpu_median:.2f} "
                    f"({min(t.cpu) / min(timings[low].cpu):.2f})"
                    for name, t in timings.items()
                    if name in ours
                )
                + f"; wall samples {ratio(timings, low, 'samples'):.2f}, log "
                f"{ratio(timings, low, 'log'):.2f}"
            )
    print(
        f"(targets against the pyarrow floor: CPU ≤ {CPU_TARGET:g} on two cores, wall ≤ "
        f"{WALL_TARGET:g} on a many-core machine)"
    )
    if not args.lasio_rounds:
        print(f"lasio not run: values not compared\nafter: {uptime()}")
        return 0
    print(table(with_lasio, "gyropipe las, samples"))
    samples, log = with_lasio["gyropipe las, samples"], with_lasio["gyropipe las, log"]
    las = with_lasio["lasio.read"]
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
    print(f"values and nulls identical to lasio: {same}")
    print(f"after: {uptime()}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())

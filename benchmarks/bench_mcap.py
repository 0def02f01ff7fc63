"""MCAP reader speed: per-sample JSON ingest against the mcap library, and gyropipe's
batched Arrow channel in samples per second.

(a) JSON: ``--messages`` per-sample JSON messages (default 1,000,000; zstd chunks as the
    mcap writer makes by default) read by our reader vs ``make_reader(f).iter_messages()``
    plus ``json.loads`` of each message (the values only, no table). Target: ≥ 2×.
(b) Batched: a point survey of the mems-vrg tool (simulated, tiled to ``--samples``,
    default 10,000,000) written by our writer and read back. Target: ≥ 10M samples/s.

One run each (the first read of a process, the file in the page cache), then the best of
``--repeat`` more reads. Exits 1 when a target is missed or a result is wrong.

    python benchmarks/bench_mcap.py [--messages 1000000] [--samples 10000000]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from mcap.reader import make_reader
from mcap.writer import Writer

from pipeline.io.mcap import read_samples, write_samples
from pipeline.io.mcap.options import McapOptions
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.well import WellMetadata

JSON_OPTIONS = McapOptions(
    columns={"time": "t"}, units={"gyro": "deg/h", "acc": "m/s2", "time": "s"}
)
T = TypeVar("T")
SURVEY = SimulationSpec.model_validate(
    {
        "name": "stations",
        "site": {"latitude": 61.25, "date": "2026-11-21"},
        "well": {
            "sections": [
                {"kind": "vertical", "length": 300},
                {"kind": "build", "dls": 2.0, "inc": 30, "azi": 37},
                {"kind": "hold", "to_md": 1500},
            ]
        },
        "tool": {"preset": "mems-vrg"},
        "survey": {"mode": "point", "every": 30, "dwell": 20.0, "speed": 1.0},
    }
)


def timed(func: Callable[[], T], repeat: int) -> tuple[float, float, T]:
    """Time of the first call, best of ``repeat`` more, and the first call's result."""
    start = time.perf_counter()
    result = func()
    first = time.perf_counter() - start
    best = first
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return first, best, result


def bench_json(directory: Path, n: int, repeat: int) -> bool:
    path = directory / "json.mcap"
    rng = np.random.default_rng(1)
    values = rng.normal(size=(n, 6)).tolist()
    keys = ("wx", "wy", "wz", "gx", "gy", "gz")
    start = time.perf_counter()
    with path.open("wb") as fh:
        writer = Writer(fh)
        writer.start()
        channel = writer.register_channel("/imu", "json", 0)
        for i, row in enumerate(values):
            sample = {"t": i / 100, **dict(zip(keys, row, strict=True))}
            writer.add_message(channel, i * 10_000_000, json.dumps(sample).encode(), 0, i)
        writer.finish()  # type: ignore[no-untyped-call]
    print(
        f"(a) {n:,} JSON messages, {path.stat().st_size / 1e6:.0f} MB "
        f"(written in {time.perf_counter() - start:.1f} s)"
    )

    def library() -> list[object]:
        with path.open("rb") as fh:
            return [json.loads(m.data) for _, _, m in make_reader(fh).iter_messages()]

    def ours() -> pa.Table:
        return read_samples(path, "samples", JSON_OPTIONS)[0]

    lib_first, _, _ = timed(library, 0)
    first, best, table = timed(ours, repeat)
    ok = table.num_rows == n and np.array_equal(
        table.column("gyro_y").to_numpy(), np.array(values)[:, 1]
    )
    ratio = lib_first / first
    print(
        f"    mcap iter_messages + json.loads: {lib_first:.2f} s ({lib_first / n * 1e6:.1f} µs/msg)"
    )
    print(
        f"    gyropipe reader: {first:.2f} s first, {best:.2f} s best "
        f"({n / best / 1e6:.2f} M msg/s) -> table"
    )
    print(
        f"    ratio library / ours: {ratio:.1f}x (first run), {lib_first / best:.1f}x (best); "
        f"target >= 2x; values {'ok' if ok else 'WRONG'}"
    )
    return ok and ratio >= 2


def tiled(samples: pa.Table, n: int) -> pa.Table:
    """``samples`` repeated until ``n`` rows, times shifted to stay increasing."""
    copies = -(-n // samples.num_rows)
    period = samples["time"][-1].as_py() + 0.01
    stations = pc.max(samples["station"]).as_py() + 1
    parts = []
    for k in range(copies):
        part = samples.set_column(
            0, samples.schema.field("time"), pc.add(samples["time"], k * period)
        )
        index = part.schema.get_field_index("station")
        part = part.set_column(
            index, part.schema.field("station"), pc.add(part["station"], k * stations)
        )
        parts.append(part)
    return pa.concat_tables(parts).slice(0, n).combine_chunks()


def bench_batched(directory: Path, n: int, repeat: int) -> bool:
    table = tiled(simulate(SURVEY).samples, n)
    path = directory / "samples.mcap"
    start = time.perf_counter()
    write_samples(table, path, WellMetadata(well="bench"))
    print(
        f"(b) {n:,} samples × {table.num_columns} columns (mems-vrg point survey), "
        f"{path.stat().st_size / 1e6:.0f} MB, written in {time.perf_counter() - start:.1f} s"
    )
    first, best, result = timed(lambda: read_samples(path, "samples", McapOptions())[0], repeat)
    ok = result.equals(table, check_metadata=True)
    rate = n / first / 1e6
    print(
        f"    gyropipe reader: {first:.2f} s first ({rate:.1f} M samples/s), "
        f"{best:.2f} s best ({n / best / 1e6:.1f} M samples/s); target >= 10 M/s; "
        f"round trip {'exact' if ok else 'WRONG'}"
    )
    return ok and rate >= 10


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--messages", type=int, default=1_000_000)
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        passed = bench_batched(Path(tmp), args.samples, args.repeat)
        passed &= bench_json(Path(tmp), args.messages, args.repeat)
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())

"""Peak memory of a run against the survey's length (issue #20, bounded memory).

Simulates the same point survey at two lengths — ``examples/plans/j-well.yaml`` shortened
to about 15 stations (1×) and lengthened to ``--factor`` times as many stations (8×) — and
runs each through ``pipelines/point-gyro.yaml`` without its report stage, as ``gyropipe
run`` in a process of its own, measuring that process's peak resident memory with the OS's
accounting (``/usr/bin/time -v``, "Maximum resident set size"; without it, the
``ru_maxrss`` of the child as ``resource.getrusage(RUSAGE_CHILDREN)`` reports it in a fresh
wrapper process). Prints per survey: samples, raw size (the samples in Arrow, MiB), the
Parquet file, peak RSS, wall time; the ratio of the long survey's peak to the short one's
(target of issue #20: ≤ 1.2); and the floor (``gyropipe validate`` of the same pipeline:
interpreter, libraries, plugins). The machine's load (``uptime``) is printed before and after.

What streams in this pipeline: the raw samples, from the Parquet reader (a row group at a
time) through ``position_readings`` (a station at a time) and ``validity_checks``
(magnetometer means in one pass); the readings, stations, trajectory and QC tables are
small whole tables.

Continuous cases (``--continuous``): ``examples/plans/j-well-continuous.yaml`` logged from
600 m over 300 m (1×) and 2400 m (8×) through ``pipelines/continuous-gyro.yaml`` without its report;
small wells (4 × the 1× survey) through ``gyropipe batch`` with 2 workers (the
peak of the largest process: the kernel's ``ru_maxrss`` over the process tree); and a
24-hour 100 Hz survey (8.6 ×10⁶ samples) through the shipped pipeline without and with its
report. The 24-hour input is written a piece at a time (:func:`day_survey`: a short slow
survey whose steady moving samples are repeated in time and depth), never held whole.

    python benchmarks/bench_memory.py [--data DIR] [--factor 8] [--continuous] [--day]
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import yaml

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "examples" / "plans" / "j-well.yaml"
SHIPPED = ROOT / "pipelines" / "point-gyro.yaml"
CONTINUOUS_PLAN = ROOT / "examples" / "plans" / "j-well-continuous.yaml"
CONTINUOUS = ROOT / "pipelines" / "continuous-gyro.yaml"
DAY = 86_400.0
"""s of the day-long survey"""
GYROPIPE = [str(Path(sys.executable).parent / "gyropipe")]
SPACING = 90.0
"""m between stations (the plan's)"""
STATIONS = 15
"""stations of the 1× survey"""
MIB = 1 << 20
WRAPPER = """
import resource, subprocess, sys
subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL)
print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
"""
"""Runs a command and prints its peak RSS (KiB): the wrapper's only child."""


def simulate(data: Path, scale: int) -> Path:
    """The samples of the survey ``scale`` times as long (simulated once, then kept)."""
    target = data / f"x{scale}" / "samples.parquet"
    if target.exists():
        return target
    plan = yaml.safe_load(PLAN.read_text())
    plan["name"] = f"memory-x{scale}"
    sections = plan["well"]["sections"]
    sections[-1] = {"kind": "hold", "to_md": SPACING * STATIONS * scale}
    plan["survey"]["dwell"] = 20
    path = data / f"x{scale}.yaml"
    path.write_text(yaml.safe_dump(plan))
    command = [*GYROPIPE, "simulate", str(path), "--out", str(target.parent)]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return target


def pipeline(data: Path, shipped: Path = SHIPPED) -> Path:
    """A shipped pipeline without its report stage."""
    spec = yaml.safe_load(shipped.read_text())
    spec["stages"] = [s for s in spec["stages"] if s["uses"] != "report"]
    path = data / f"{shipped.stem}-no-report.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def simulate_continuous(data: Path, scale: int) -> Path:
    """A continuous survey logged over 300 m × ``scale`` from 600 m, where the well is
    inclined (6.7°: a run between two vertical stops has no azimuth to integrate), simulated
    once. Even the 1× survey is several batches long (7.3 ×10⁴ samples), so the comparison
    is of a few batches against a few batches, not of one batch against several."""
    target = data / f"continuous-x{scale}" / "samples.parquet"
    if target.exists():
        return target
    plan = yaml.safe_load(CONTINUOUS_PLAN.read_text())
    plan["name"] = f"memory-continuous-x{scale}"
    plan["survey"]["start_md"] = 600
    plan["survey"]["end_md"] = 600 + 300 * scale
    plan["well"]["sections"][-1] = {"kind": "hold", "to_md": max(2500, 700 + 300 * scale)}
    path = data / f"continuous-x{scale}.yaml"
    path.write_text(yaml.safe_dump(plan))
    command = [*GYROPIPE, "simulate", str(path), "--out", str(target.parent)]
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    return target


DAY_PLAN = {
    "name": "memory-day-seed",
    "seed": 7,
    "site": {
        "latitude": 61.25,
        "longitude": 73.4,
        "elevation": 54.3,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731, "dip": 78.29, "declination": 17.0},
    },
    "well": {
        "sections": [
            {"kind": "vertical", "length": 50},
            {"kind": "build", "dls": 3.0, "inc": 30, "azi": 40},
            {"kind": "hold", "to_md": 9000},
        ]
    },
    "tool": {"preset": "mems-vrg"},
    "survey": {"mode": "continuous", "start_md": 400, "end_md": 460, "speed": 0.06},
}
"""A slow run (0.06 m/s, 100 Hz) on the hold at 30°: 1000 s of steady logging to repeat."""
BLOCK = (60_000, 70_000)
"""Rows of the seed survey repeated: 100 s of steady logging (6 m) mid-run."""


def day_survey(data: Path) -> Path:
    """A 24-hour 100 Hz continuous survey, written a piece at a time: the seed survey's
    samples up to the end of :data:`BLOCK`, then the block again and again, each copy later
    by the block's duration and deeper by its MD, then the rest of the seed survey (the end
    of the run and the end stop) shifted by all the copies. Only the seed (1.4 ×10⁵ samples)
    and one piece are in memory."""
    target = data / "day" / "samples.parquet"
    if target.exists():
        return target
    seed_dir = data / "day-seed"
    if not (seed_dir / "samples.parquet").exists():
        path = data / "day-seed.yaml"
        path.write_text(yaml.safe_dump(DAY_PLAN))
        command = [*GYROPIPE, "simulate", str(path), "--out", str(seed_dir)]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
    seed = pq.read_table(seed_dir / "samples.parquet")
    lo, hi = BLOCK
    time, md = (seed.column(n).to_numpy() for n in ("time", "md"))
    step_t, step_md = time[hi] - time[lo], md[hi] - md[lo]
    copies = int(np.ceil((DAY - (time[-1] - time[0])) / step_t))
    block = seed.slice(lo, hi - lo)
    target.parent.mkdir(parents=True, exist_ok=True)
    with pq.ParquetWriter(target, seed.schema) as writer:
        writer.write_table(seed.slice(0, hi), row_group_size=ROW_GROUP)
        for k in range(1, copies + 1):
            writer.write_table(_shifted(block, k * step_t, k * step_md))
        writer.write_table(
            _shifted(seed.slice(hi), copies * step_t, copies * step_md), row_group_size=ROW_GROUP
        )
    return target


ROW_GROUP = 65_536


def _shifted(table: pa.Table, dt: float, dmd: float) -> pa.Table:
    """``table`` later by ``dt`` s and deeper by ``dmd`` m."""
    for name, shift in (("time", dt), ("md", dmd)):
        i = table.schema.get_field_index(name)
        column = pa.array(table.column(name).to_numpy() + shift)
        table = table.set_column(i, table.schema.field(i), column)
    return table


def peak_rss(command: list[str]) -> tuple[float, float]:
    """Peak RSS (MiB) and wall time (s) of ``command`` run in a process of its own."""
    t0 = time.perf_counter()
    if Path("/usr/bin/time").exists():
        done = subprocess.run(["/usr/bin/time", "-v", *command], capture_output=True, text=True)
        if done.returncode:
            raise SystemExit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
        found = re.search(r"Maximum resident set size \(kbytes\): (\d+)", done.stderr)
        assert found is not None, done.stderr
        kib = int(found.group(1))
    else:
        done = subprocess.run(
            [sys.executable, "-c", WRAPPER, *command], capture_output=True, text=True, check=True
        )
        kib = int(done.stdout.split()[-1])
    return kib / 1024, time.perf_counter() - t0


def load() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def survey_row(label: str, samples: Path, command: list[str]) -> float:
    """Run ``command`` (a run on ``samples``) and print its row; its peak RSS, MiB."""
    meta = pq.read_metadata(samples)
    width = sum(f.type.bit_width for f in pq.read_schema(samples)) / 8  # fixed-width columns
    raw = meta.num_rows * width / MIB  # the samples in Arrow, nulls' bitmaps aside
    peak, wall = peak_rss(command)
    size = samples.stat().st_size / MIB
    print(f"{label:>22} {meta.num_rows:>10,} {raw:>8.1f} {size:>9.1f} {peak:>9.0f} {wall:>7.1f}")
    return peak


def run_command(pipe: Path, samples: Path, out: Path) -> list[str]:
    shutil.rmtree(out, ignore_errors=True)
    return [*GYROPIPE, "run", str(pipe), "--input", f"samples={samples}", "--out", str(out)]


def point(data: Path, factor: int) -> None:
    pipe = pipeline(data)
    floor, _ = peak_rss([*GYROPIPE, "validate", str(pipe)])
    print(f"floor (gyropipe validate: interpreter, libraries, plugins): {floor:.0f} MiB")
    peaks = []
    for scale in (1, factor):
        samples = simulate(data, scale)
        out = data / f"out-x{scale}"
        peaks.append(survey_row(f"point {scale}×", samples, run_command(pipe, samples, out)))
    print(f"point: peak {factor}× / 1×: {peaks[1] / peaks[0]:.2f} (target ≤ 1.2)")


def continuous(data: Path, factor: int) -> None:
    pipe = pipeline(data, CONTINUOUS)
    peaks = []
    for scale in (1, factor):
        samples = simulate_continuous(data, scale)
        out = data / f"out-continuous-x{scale}"
        label = f"continuous {scale}×"
        peaks.append(survey_row(label, samples, run_command(pipe, samples, out)))
    print(f"continuous: peak {factor}× / 1×: {peaks[1] / peaks[0]:.2f} (target ≤ 1.2)")
    wells = data / "wells"
    wells.mkdir(exist_ok=True)
    small = simulate_continuous(data, 1)
    for i in range(4):
        well = wells / f"W{i}.parquet"
        if not well.exists():
            shutil.copyfile(small, well)
    out = data / "out-batch"
    shutil.rmtree(out, ignore_errors=True)
    command = [*GYROPIPE, "batch", str(pipe), "--inputs", str(wells / "*.parquet")]
    command += ["--out", str(out), "--workers", "2", "--quiet"]
    label = "batch, 4 small wells"
    peak = survey_row(label, small, command)
    print(f"small wells: {peak:.0f} MiB per batch worker (target ≤ 180)")


def day(data: Path) -> None:
    samples = day_survey(data)
    for label, pipe in (("24 h, no report", pipeline(data, CONTINUOUS)), ("24 h", CONTINUOUS)):
        survey_row(label, samples, run_command(pipe, samples, data / "out-day"))
    print("24 h through continuous-gyro.yaml: target ≤ 300 MiB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=Path(tempfile.gettempdir()) / "gp-mem")
    parser.add_argument("--factor", type=int, default=8)
    parser.add_argument("--continuous", action="store_true", help="continuous cases")
    parser.add_argument("--day", action="store_true", help="the 24-hour survey")
    parser.add_argument("--no-point", action="store_true", help="skip the point survey")
    args = parser.parse_args()
    args.data.mkdir(parents=True, exist_ok=True)
    print(f"load before: {load()}")
    print(f"{'survey':>22} {'samples':>10} {'raw MiB':>8} {'file MiB':>9} {'peak MiB':>9} {'s':>7}")
    if not args.no_point:
        point(args.data, args.factor)
    if args.continuous:
        continuous(args.data, args.factor)
    if args.day:
        day(args.data)
    print(f"load after: {load()}")


if __name__ == "__main__":
    main()

"""Peak memory of a point-gyro run against the survey's length (issue #20, bounded memory).

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

    python benchmarks/bench_memory.py [--data DIR] [--factor 8]
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

import pyarrow.parquet as pq
import yaml

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "examples" / "plans" / "j-well.yaml"
SHIPPED = ROOT / "pipelines" / "point-gyro.yaml"
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


def pipeline(data: Path) -> Path:
    """``point-gyro.yaml`` without its report stage."""
    spec = yaml.safe_load(SHIPPED.read_text())
    spec["stages"] = [s for s in spec["stages"] if s["uses"] != "report"]
    path = data / "point-gyro-no-report.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def peak_rss(command: list[str]) -> tuple[float, float]:
    """Peak RSS (MiB) and wall time (s) of ``command`` run in a process of its own."""
    t0 = time.perf_counter()
    if Path("/usr/bin/time").exists():
        done = subprocess.run(
            ["/usr/bin/time", "-v", *command], capture_output=True, text=True, check=True
        )
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=Path(tempfile.gettempdir()) / "gp-mem")
    parser.add_argument("--factor", type=int, default=8)
    args = parser.parse_args()
    args.data.mkdir(parents=True, exist_ok=True)
    print(f"load before: {load()}")
    pipe = pipeline(args.data)
    floor, _ = peak_rss([*GYROPIPE, "validate", str(pipe)])
    print(f"floor (gyropipe validate: interpreter, libraries, plugins): {floor:.0f} MiB")
    print(f"{'survey':>7} {'samples':>10} {'raw MiB':>8} {'file MiB':>9} {'peak MiB':>9} {'s':>6}")
    peaks = []
    for scale in (1, args.factor):
        samples = simulate(args.data, scale)
        meta = pq.read_metadata(samples)
        raw = pq.read_table(samples).nbytes / MIB
        out = args.data / f"out-x{scale}"
        shutil.rmtree(out, ignore_errors=True)
        command = [*GYROPIPE, "run", str(pipe), "--input", f"samples={samples}"]
        peak, wall = peak_rss([*command, "--out", str(out)])
        peaks.append(peak)
        size = samples.stat().st_size / MIB
        row = f"{meta.num_rows:>10,} {raw:>8.1f} {size:>9.1f} {peak:>9.0f} {wall:>6.1f}"
        print(f"{scale:>6}× {row}")
    print(f"peak {args.factor}× / 1×: {peaks[1] / peaks[0]:.2f} (target ≤ 1.2)")
    print(f"load after: {load()}")


if __name__ == "__main__":
    main()

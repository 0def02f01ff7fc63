"""Continuous stage speed: ``integrate_continuous`` of this tree against an older commit's.

Simulates a continuous survey of a single-axis MEMS tool (mems-vrg, 100 Hz, 4.4 km at
1 m/s: ≈ 484,000 samples), compasses its stops once, and runs the stage on those same
inputs in subprocesses: the old commit's code (``--old-rev``, default the main HEAD the
vectorised stage started from, checked out into a temporary detached git worktree, or
``--old-src``: an existing checkout's ``src``) and this tree's, alternately (``--rounds``),
each timing ``--repeat`` calls after one untimed call (the series read to its end where the
stage streams it). Prints the best times, their ratio,
the largest differences of the outputs (deg) and the machine load (``uptime``) before and
after. Exits 1 if the outputs differ by more than 1e-9° or the ratio is under 5.

    python benchmarks/bench_continuous.py [--rounds 2] [--repeat 2] [--old-rev REV] [--target X]

Issue #20 (streamed vs whole-table path): ``--old-rev d175d07 --target 0.9``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

OLD_REV = "877eac6fbebc48401c180a686f8719cf950f82ed"
"""main before the continuous stage was vectorised (issue 19)."""
TARGET = 5.0
TOLERANCE = 1e-9
"""deg"""
LATITUDE = 61.25
SPEC = {
    "name": "bench-continuous",
    "seed": 7,
    "site": {
        "latitude": LATITUDE,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731, "dip": 78.29, "declination": 17.0},
    },
    "well": {
        "sections": [
            {"kind": "vertical", "length": 500},
            {"kind": "build", "dls": 2.0, "inc": 45, "azi": 37},
            {"kind": "hold", "to_md": 5000},
        ]
    },
    "tool": {"preset": "mems-vrg"},
    "survey": {"mode": "continuous", "start_md": 200, "end_md": 4600, "speed": 1.0},
}
OUTPUTS = {
    "series": ("azi", "inc"),
    "stations": ("azi", "inc", "sigma_azi", "sigma_inc"),
}


def worker(folder: Path, repeat: int, name: str) -> None:
    """Run the stage of the ``pipeline`` on ``sys.path`` on the saved inputs; write the
    times (s) and outputs to ``folder``."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from pipeline.continuous import ContinuousOptions, integrate_continuous

    samples = pq.read_table(folder / "samples.parquet")
    stops = pq.read_table(folder / "stops.parquet")
    options = ContinuousOptions()

    def stage() -> dict[str, pa.Table]:
        """The stage's outputs as tables (a streamed series read to its end, as a consumer
        of the stage would)."""
        result = integrate_continuous(samples, stops, LATITUDE, options)
        series = result.series
        return {
            "series": series if isinstance(series, pa.Table) else series.read_all(),
            "stations": result.stations,
        }

    tables = stage()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        tables = stage()
        times.append(time.perf_counter() - start)
    np.savez(
        folder / f"{name}.npz",
        **{f"{t}_{c}": tables[t].column(c).to_numpy() for t, cols in OUTPUTS.items() for c in cols},
    )
    (folder / f"{name}.json").write_text(json.dumps(times))


def prepare(folder: Path) -> int:
    """Simulate the survey and compass its stops (this tree's code); the sample count."""
    import pyarrow.parquet as pq

    from pipeline.gyrocompass.readings import ReadingOptions, position_readings
    from pipeline.gyrocompass.solve import CompassOptions, compass
    from pipeline.sim.simulate import simulate
    from pipeline.sim.spec import SimulationSpec

    samples = simulate(SimulationSpec.model_validate(SPEC)).samples
    readings = position_readings(samples, ReadingOptions(trim_start=0.5, min_dwell=1.0))
    stops, _ = compass(readings, LATITUDE, CompassOptions(noise_floor=0.01))
    pq.write_table(samples, folder / "samples.parquet")
    pq.write_table(stops, folder / "stops.parquet")
    rows: int = samples.num_rows
    return rows


def run(src: Path, folder: Path, repeat: int, name: str) -> list[float]:
    """Times (s) of the stage of the code under ``src``, run in a subprocess."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    args = [sys.executable, __file__, "--worker", str(folder), "--repeat", str(repeat)]
    subprocess.run([*args, "--name", name], env=env, check=True)
    times: list[float] = json.loads((folder / f"{name}.json").read_text())
    return times


def differences(folder: Path) -> dict[str, float]:
    """Largest |new − old| of each output column, deg (azimuths wrapped)."""
    old, new = np.load(folder / "old.npz"), np.load(folder / "new.npz")
    out = {}
    for key in old.files:
        if old[key].shape != new[key].shape:
            out[key] = float("inf")
            continue
        d = new[key] - old[key]
        if key.endswith("_azi"):
            d = (d + 180.0) % 360.0 - 180.0
        same = (old[key] == new[key]) | (np.isnan(old[key]) & np.isnan(new[key]))
        out[key] = float(np.max(np.where(same, 0.0, np.abs(d)), initial=0.0))
    return out


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--old-rev", default=OLD_REV)
    parser.add_argument("--old-src", type=Path, help="src of an old checkout (no worktree)")
    parser.add_argument("--target", type=float, default=TARGET, help="least ratio old/new")
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--name", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.repeat, args.name)
        return 0
    repo = Path(__file__).resolve().parents[1]
    new_src = repo / "src"
    with tempfile.TemporaryDirectory(prefix="bench-continuous-") as tmp:
        folder = Path(tmp)
        old_src = args.old_src
        worktree = folder / "old"
        git = ["git", "-C", str(repo), "worktree"]
        if old_src is None:
            subprocess.run([*git, "add", "--detach", str(worktree), args.old_rev], check=True)
            old_src = worktree / "src"
        try:
            rows = prepare(folder)
            print(f"survey: {rows:,} samples; load before: {uptime()}")
            best = {"old": float("inf"), "new": float("inf")}
            for _ in range(args.rounds):
                for name, src in (("old", old_src), ("new", new_src)):
                    best[name] = min(best[name], *run(src, folder, args.repeat, name))
            load_after = uptime()
            diff = differences(folder)
        finally:
            if args.old_src is None:
                subprocess.run([*git, "remove", "--force", str(worktree)], check=True)
    ratio = best["old"] / best["new"]
    print(f"old ({args.old_src or args.old_rev[:12]}): {best['old']:.3f} s")
    print(f"new (this tree): {best['new']:.3f} s")
    print(f"ratio old/new: {ratio:.2f}x (target >= {args.target:g}x)")
    for key, value in diff.items():
        print(f"max |new - old| {key}: {value:.3g} deg")
    print(f"load after: {load_after}")
    ok = ratio >= args.target and max(diff.values()) <= TOLERANCE
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

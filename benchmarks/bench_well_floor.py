"""One well's CPU in a batch worker against its floor: the point-gyro and continuous-gyro
pipelines (their reports included) beside the least honest computation each survey needs.

Floors (one well, in this process, CPU time = user + system from ``getrusage``):

- **point-gyro**: the 842,201-sample ``samples.parquet`` of ``gyropipe simulate
  examples/plans/j-well.yaml --seed 1`` read with pyarrow (the columns the readings use:
  time, MD, frame angle, gyro, accelerometers, markers; on one thread), and each marked
  stop's trimmed means (``trim_start`` = 1 s) of MD, frame angle and sensors in NumPy;
- **continuous-gyro**: ``j-well-continuous.yaml``'s samples (163,601) decoded likewise, the
  stops' trimmed means (what compassing the tie and closing stops needs; the compass solve
  on those few numbers is not counted), and one vectorised integration: inclination and
  high side from the accelerometers, the azimuth rate from the gyro, integrated along the
  run, inclination and azimuth sampled every 10 m of MD, and the stations' positions by
  minimum curvature (NumPy, whole arrays). Not counted: what the pipeline adds to that
  least computation (the odometer's cubic fit and the tool's acceleration removed, a second
  pass, Heun's method solved by Newton's, the closure, the σ budget).

Floor and worker alternate, well after well, so that a change of the machine's load falls
on both alike.

The worker path: :func:`pipeline.batch.worker.run_well` in this process, set up as a pool
worker is (:func:`~pipeline.batch.worker.worker_init`: BLAS on one thread, pandas deferred,
Arrow's returning allocator; the readers on one thread), each pipeline warmed up by one well
first so that imports and first-call costs are not counted, then ``--runs`` wells timed
(the least of each: on a shared machine other load only adds CPU time — cache and core
sharing — so the least is the closest to the cost itself; the medians beside).

Prints CPU ms of each, the ratio to its floor (targets: point-gyro ≤ 3×, continuous ≤ 6×),
the load average before and after, and where the worker's CPU goes: each stage's call (a
streamed input is decoded and checked in the stage that consumes it: the samples in
``readings``), the SHA-256 of the files ``run.json`` records, and the rest — the runner's
bookkeeping (contract checks of whole tables, persisted tables, ``run.json``) and the
worker's (staging, publish); each stage's wall time (``run.json``) beside it. ``--profile``
prints the top of a cProfile of one more well of each.

    python benchmarks/bench_well_floor.py [--data DIR] [--runs 5] [--profile] [--continuous-km KM]

``--continuous-km``: the continuous survey logged over KM km instead of the example's 1.2
(same speed, rate and tool; the hold lengthened to fit): how the ratio moves with length.
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import io
import os
import pstats
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import yaml
from threadpoolctl import threadpool_limits

import pipeline.runner as runner
from pipeline.batch.worker import WellOutcome, WellTask, run_well
from pipeline.executing import PipelineRef
from pipeline.io.threads import set_reader_threads
from pipeline.lazy_pandas import defer_pandas
from pipeline.spec import load_spec
from pipeline.streams import use_returning_memory_pool

ROOT = Path(__file__).resolve().parents[1]
CASES = {  # pipeline → (simulation plan, floor, target ratio)
    "point-gyro": "j-well",
    "continuous-gyro": "j-well-continuous",
}
TARGETS = {"point-gyro": 3.0, "continuous-gyro": 6.0}
TRIM_S = 1.0
"""the pipelines' ``trim_start``, s"""
SIGNALS = ["gyro_x", "acc_x", "acc_y", "acc_z"]
COLUMNS = ["time", "md", "frame_angle", *SIGNALS, "station", "position"]
"""what the pipelines read of the samples"""
SPACING_M = 10.0
"""the continuous pipeline's output station spacing"""
EARTH_RATE = 15.041  # deg/h
GYROPIPE = [str(Path(sys.executable).parent / "gyropipe")]


def cpu() -> float:
    """CPU time (user + system) of this process so far, s."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f}, {five:.2f}, {fifteen:.2f} ({os.cpu_count()} CPUs)"


def stop_means(path: Path) -> np.ndarray:
    """Point-gyro floor: each marked stop's trimmed means of every sensor column."""
    return trimmed_means(pq.read_table(path, columns=COLUMNS, use_threads=False))


def trimmed_means(table: pa.Table) -> np.ndarray:
    """Each marked stop's (station, position) trimmed means of MD, frame angle and sensors."""
    time_s = table.column("time").to_numpy()
    station = table.column("station").fill_null(-1).to_numpy()
    position = table.column("position").fill_null(-1).to_numpy()
    change = np.flatnonzero((np.diff(station) != 0) | (np.diff(position) != 0)) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [station.size]])
    marked = (station[starts] >= 0) & (position[starts] >= 0)
    skip = round(TRIM_S / (time_s[1] - time_s[0]))
    starts, ends = starts[marked] + skip, ends[marked]
    means = []
    for name in ["md", "frame_angle", *SIGNALS]:
        x = table.column(name).to_numpy()
        total = np.add.reduceat(x, np.stack([starts, ends], axis=1).ravel()[:-1])[::2]
        means.append(total / (ends - starts))
    return np.stack(means, axis=1)


def integrated_azimuth(path: Path) -> np.ndarray:
    """Continuous floor: the stops' trimmed means; inclination and high side from the
    accelerometers, the azimuth rate from the gyro, integrated over time, every
    :data:`SPACING_M` of MD, and the stations' positions (north, east, TVD, m) beside the
    stops' means."""
    table = pq.read_table(path, columns=COLUMNS, use_threads=False)
    means = trimmed_means(table)
    t, md = table.column("time").to_numpy(), table.column("md").to_numpy()
    gx, ax, ay, az = (table.column(n).to_numpy() for n in SIGNALS)
    g = np.sqrt(ax * ax + ay * ay + az * az)
    inc = np.arccos(np.clip(az / g, -1.0, 1.0))
    highside = np.arctan2(ay, -ax)
    rate = (gx - EARTH_RATE * np.cos(inc)) * np.cos(highside) / np.maximum(np.sin(inc), 1e-3)
    steps = 0.5 * (rate[1:] + rate[:-1]) * np.diff(t) / 3600.0
    azimuth = np.concatenate([[0.0], np.cumsum(steps)])
    moving = np.flatnonzero(table.column("station").is_null().to_numpy(zero_copy_only=False))
    along = md[moving]
    stations = np.arange(along.min(), along.max(), SPACING_M)
    at = np.radians([np.interp(stations, along, x[moving]) for x in (np.degrees(inc), azimuth)])
    return np.concatenate([minimum_curvature(stations, *at).ravel(), means.ravel()])


def minimum_curvature(md: np.ndarray, inc: np.ndarray, azi: np.ndarray) -> np.ndarray:
    """Positions (north, east, TVD, m; rows) of stations at ``md`` (m), ``inc`` and ``azi``
    (rad) by minimum curvature, from the first station."""
    i1, i2, a1, a2 = inc[:-1], inc[1:], azi[:-1], azi[1:]
    cos_dogleg = np.cos(i2 - i1) - np.sin(i1) * np.sin(i2) * (1.0 - np.cos(a2 - a1))
    dogleg = np.arccos(np.clip(cos_dogleg, -1.0, 1.0))
    ratio = np.where(dogleg > 1e-9, 2.0 / np.maximum(dogleg, 1e-9) * np.tan(dogleg / 2), 1.0)
    half = np.diff(md) / 2 * ratio
    steps = half * np.stack(
        [
            np.sin(i1) * np.cos(a1) + np.sin(i2) * np.cos(a2),
            np.sin(i1) * np.sin(a1) + np.sin(i2) * np.sin(a2),
            np.cos(i1) + np.cos(i2),
        ]
    )
    return np.concatenate([np.zeros((3, 1)), np.cumsum(steps, axis=1)], axis=1)


FLOORS: dict[str, Callable[[Path], np.ndarray]] = {
    "point-gyro": stop_means,
    "continuous-gyro": integrated_azimuth,
}


class Clock:
    """CPU seconds spent in each stage's call and in hashing, while installed (it wraps
    the runner's ``_call`` and ``sha256_file`` where the run hashes files — the manifest's
    inputs and outputs, the runner's parameter files: this benchmark's instrument only)."""

    def __init__(self) -> None:
        self.spent: dict[str, float] = {}
        call, digest = runner._call, runner.sha256_file

        def timed_call(st: Any, *args: Any) -> Any:
            with self.charged(st.id):
                return call(st, *args)

        def timed_digest(path: Path) -> str:
            with self.charged(HASHING):
                return digest(path)

        runner._call = timed_call  # type: ignore[assignment]
        runner.sha256_file = timed_digest  # type: ignore[assignment]
        try:  # where run.json's content is made (older trees, as bench_well_pair's: runner)
            import pipeline.manifest as manifest
        except ImportError:
            return
        manifest.sha256_file = timed_digest  # type: ignore[assignment]

    @contextmanager
    def charged(self, key: str) -> Iterator[None]:
        start = time.process_time()
        try:
            yield
        finally:
            self.spent[key] = self.spent.get(key, 0.0) + time.process_time() - start


HASHING = "SHA-256 (run.json)"


def timed(fn: Callable[[], object]) -> float:
    start = cpu()
    fn()
    return cpu() - start


def worker_setup() -> None:
    """This process as :func:`~pipeline.batch.worker.worker_init` sets a pool worker up."""
    gc.freeze()
    defer_pandas()
    threadpool_limits(limits=1)
    use_returning_memory_pool()
    set_reader_threads(1)


def task(ref: PipelineRef, samples: Path, out_root: Path, n: int) -> WellTask:
    return WellTask(
        well_id=f"W{n:03d}",
        run_id=n,
        batch_id=1,
        pipeline=ref.digest,
        inputs={"samples": str(samples)},
        well={},
        out_root=str(out_root),
        fingerprint="{}",
    )


def checked(outcome: WellOutcome) -> WellOutcome:
    if outcome.status != "done":
        raise SystemExit(f"well {outcome.well_id} failed: {outcome.error}")
    return outcome


def longer_continuous(data: Path, km: float) -> str:
    """``j-well-continuous.yaml`` logged over ``km`` km from its start (300 m) at its speed,
    the well's hold lengthened to 500 m past the closing stop; written to ``data``, returns
    its name."""
    plan = yaml.safe_load((ROOT / "examples" / "plans" / "j-well-continuous.yaml").read_text())
    end = plan["survey"]["start_md"] + 1000.0 * km
    plan["survey"]["end_md"] = end
    plan["well"]["sections"][-1]["to_md"] = max(plan["well"]["sections"][-1]["to_md"], end + 500)
    plan["name"] = name = f"j-well-continuous-{km:g}km"
    (data / f"{name}.yaml").parent.mkdir(parents=True, exist_ok=True)
    (data / f"{name}.yaml").write_text(yaml.safe_dump(plan, sort_keys=False))
    return name


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, default=Path(tempfile.gettempdir()) / "gyropipe-bench-floor"
    )
    parser.add_argument("--runs", type=int, default=5, help="wells timed per pipeline (least)")
    parser.add_argument("--profile", action="store_true", help="cProfile one more well of each")
    parser.add_argument(
        "--continuous-km",
        type=float,
        help="the continuous survey logged over this many km from 300 m (the example: 1.2)",
    )
    args = parser.parse_args()
    cases = dict(CASES)
    if args.continuous_km is not None:
        cases["continuous-gyro"] = longer_continuous(args.data, args.continuous_km)
    for plan in cases.values():
        target = args.data / plan / "samples.parquet"
        if not target.is_file():
            plan_file = ROOT / "examples" / "plans" / f"{plan}.yaml"
            if not plan_file.is_file():
                plan_file = args.data / f"{plan}.yaml"
            command = [*GYROPIPE, "simulate", str(plan_file), "--seed", "1"]
            subprocess.run([*command, "--out", str(target.parent)], check=True, capture_output=True)
    worker_setup()
    clock = Clock()
    print(f"at start: {load()}")
    results: dict[str, tuple[float, float, WellOutcome, dict[str, float], float]] = {}
    profiles: dict[str, str] = {}
    medians: dict[str, tuple[float, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for i, (name, plan) in enumerate(cases.items()):
            samples = args.data / plan / "samples.parquet"
            floor_fn = FLOORS[name]
            floor_fn(samples)  # warm-up: page cache, first calls
            spec = load_spec(ROOT / "pipelines" / f"{name}.yaml").spec
            assert spec is not None
            ref = PipelineRef(str(ROOT / "pipelines" / f"{name}.yaml"), spec)
            out_root = Path(tmp) / name
            checked(run_well(task(ref, samples, out_root, 0), ref))  # warm-up
            floors, cpus, last = [], [], None
            for n in range(1, args.runs + 1):
                floors.append(timed(lambda: floor_fn(samples)))  # noqa: B023
                clock.spent.clear()
                start = cpu()
                last = checked(run_well(task(ref, samples, out_root, n), ref))
                cpus.append(cpu() - start)
                spent = dict(clock.spent)
            assert last is not None
            medians[name] = (statistics.median(floors), statistics.median(cpus))
            results[name] = (min(floors), min(cpus), last, spent, cpus[-1])
            if args.profile:
                profiler = cProfile.Profile()
                profiler.enable()
                checked(run_well(task(ref, samples, out_root, 100 + i), ref))
                profiler.disable()
                text = io.StringIO()
                stats = pstats.Stats(profiler, stream=text)
                stats.sort_stats("cumulative").print_stats(45)
                stats.sort_stats("tottime").print_stats(30)
                profiles[name] = text.getvalue()
    print(f"at end:   {load()}\n")
    print(f"least of {args.runs} wells each (median); CPU = user + system of this process")
    for name, (floor, worker, *_) in results.items():
        ratio = worker / floor
        verdict = "ok" if ratio <= TARGETS[name] else "OVER"
        floor_m, worker_m = medians[name]
        print(
            f"{name:16} floor {floor * 1e3:4.0f} ms ({floor_m * 1e3:4.0f})   worker "
            f"{worker * 1e3:4.0f} ms ({worker_m * 1e3:4.0f})   → {ratio:4.2f}× "
            f"({worker_m / floor_m:4.2f}×; target ≤ {TARGETS[name]:g}×: {verdict})"
        )
    for name, (_, _, outcome, spent, total) in results.items():
        walls = {s["id"]: s["wall_time_s"] for s in outcome.manifest["stages"]}
        print(f"\n{name}: the last timed well, ms        CPU    wall")
        for key in [*walls, HASHING]:
            wall = f"{walls[key] * 1e3:7.1f}" if key in walls else f"{'':7}"
            print(f"  {key:34} {spent.get(key, 0.0) * 1e3:7.1f} {wall}")
        rest = total - sum(spent.values())
        print(f"  {'the rest: runner and worker':34} {rest * 1e3:7.1f}")
        print(f"  {'whole task':34} {total * 1e3:7.1f} {outcome.wall_time_s * 1e3:7.1f}")
    for name, text in profiles.items():
        print(f"\n===== cProfile: {name} =====\n{text}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Batch processing: 40 simulated continuous 100 Hz wells through ``continuous-gyro.yaml``
(its processing stages; report stages, if any, are left out).

Measures, in one run:

1. local process pool, 2 workers vs 1 (target ≥ 1.8× on an idle machine; the load average
   before and after is printed: on a busy 2-core machine no speed-up is possible);
2. Dask ``LocalCluster`` (2 single-threaded worker processes on 127.0.0.1, started by the
   batch) vs the process pool: wall time, cluster start-up, and the overhead per well;
3. the per-well engine overhead of the batch (input hashing for the fingerprint, ledger
   claim and record, staging, ``batch.json``, publish with fsync) as a share of the stages'
   processing time (target ≤ 5 %), with the runner's own bookkeeping beside it;
4. peak resident memory per worker (the kernel's ``ru_maxrss``, as ``/usr/bin/time -v``
   reports it; cross-checked with ``/usr/bin/time -v gyropipe run`` on the largest well) vs
   the well's raw samples in Arrow (target ≤ 3×), and the same for a one-hour survey.

The wells are ``examples/plans/j-well-continuous.yaml`` with seeds 1…40 and the continuous
run shortened from 300–1500 m to 300–(700…1090) m (400–790 s of logging at 1 m/s, 4–8 ×10⁴
samples each instead of 1.6 ×10⁵) so that the whole benchmark takes a few minutes on 2 cores.

    python benchmarks/bench_batch.py [--data DIR] [--wells 40] [--repeat 2]
"""

from __future__ import annotations

import argparse
import io
import os
import re
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pyarrow.parquet as pq
import yaml

from pipeline.batch.executors import DaskExecutor, LocalExecutor
from pipeline.batch.fingerprint import PlanIdentity
from pipeline.batch.jobs import WellJob
from pipeline.batch.ledger import Ledger
from pipeline.batch.policy import Mode, decide
from pipeline.batch.progress import JsonLines
from pipeline.batch.records import RunRow
from pipeline.batch.run import BatchOptions, BatchReport, run_batch
from pipeline.batch.worker import WellOutcome, peak_rss_bytes
from pipeline.executing import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from pipeline.well import WellMetadata

ROOT = Path(__file__).resolve().parents[1]
PLAN = ROOT / "examples" / "plans" / "j-well-continuous.yaml"
SHIPPED = ROOT / "pipelines" / "continuous-gyro.yaml"
PIPELINE = Path(tempfile.gettempdir()) / "gyropipe-bench-batch-continuous.yaml"
GYROPIPE = [str(Path(sys.executable).parent / "gyropipe")]


def simulate(data: Path, wells: int) -> None:
    """Write the shortened plans and simulate them (``gyropipe simulate``, 2 at a time)."""
    base = yaml.safe_load(PLAN.read_text())
    jobs = []
    for i in range(wells):
        target = data / f"W{i + 1:02d}" / "samples.parquet"
        if target.exists():
            continue
        plan = {**base, "name": f"w{i + 1:02d}", "seed": i + 1}
        plan["survey"] = {**base["survey"], "end_md": 700 + 10 * i}
        path = data / f"W{i + 1:02d}.yaml"
        path.write_text(yaml.safe_dump(plan))
        jobs.append([*GYROPIPE, "simulate", str(path), "--out", str(target.parent)])
    hour = data / "HOUR" / "samples.parquet"
    if not hour.exists():
        plan = {**base, "name": "hour", "seed": 99}
        plan["well"] = {
            "sections": [*base["well"]["sections"][:2], {"kind": "hold", "to_md": 4000}]
        }
        plan["survey"] = {**base["survey"], "start_md": 200, "end_md": 3485}
        (data / "HOUR.yaml").write_text(yaml.safe_dump(plan))
        jobs.append([*GYROPIPE, "simulate", str(data / "HOUR.yaml"), "--out", str(hour.parent)])
    if jobs:
        print(f"simulating {len(jobs)} wells …", flush=True)
        with ThreadPoolExecutor(2) as pool:
            for done in pool.map(
                lambda a: subprocess.run(a, capture_output=True, check=True), jobs
            ):
                del done


def batch(
    jobs: list[WellJob],
    out: Path,
    executor: str,
    workers: int,
    pipeline: Path = PIPELINE,
    scheduler: str | None = None,
) -> tuple[float, BatchReport]:
    registry = load_registry()
    plan = build_plan(load_spec(pipeline), registry)
    options = BatchOptions(out_dir=out, workers=workers, executor=executor, scheduler=scheduler)
    t0 = time.perf_counter()
    report = run_batch(plan, registry, jobs, options, JsonLines(io.StringIO()))
    wall = time.perf_counter() - t0
    bad = [r for r in report.results if r.status != "done"]
    if bad:
        raise SystemExit(f"{executor}/{workers}: {bad[0].well} {bad[0].status}: {bad[0].detail}")
    return wall, report


def runs_of(out: Path) -> list[RunRow]:
    """The latest run of every well of a batch output directory."""
    ledger = Ledger(out / "ledger.sqlite")
    try:
        return ledger.latest_runs()
    finally:
        ledger.close()


def startup(kind: str, ref: PipelineRef) -> float:
    """Seconds to start and stop an executor with 2 workers and no task."""
    t0 = time.perf_counter()
    executor = DaskExecutor(2, ref, None) if kind == "dask" else LocalExecutor(2, ref)
    executor.close(cancel=False)
    return time.perf_counter() - t0


def executor_overhead(scratch: Path, n: int) -> tuple[float, float]:
    """Wall seconds per well of ``n`` tiny wells (the bundled station listing, a few ms of
    stages) on 2 workers, both warm: a process pool forked from a process that has run a
    well, and a Dask LocalCluster that has run the batch once; the difference is the
    per-task cost of Dask. Best of 3 each."""
    from distributed import LocalCluster

    spec = yaml.safe_load((ROOT / "pipelines" / "survey.yaml").read_text())
    spec["stages"] = [st for st in spec["stages"] if not st["uses"].startswith("report")]
    survey = scratch / "survey.yaml"
    survey.write_text(yaml.safe_dump(spec, sort_keys=False))
    listing = (ROOT / "examples" / "stations-j-well.csv").read_text()
    jobs = []
    for i in range(n):
        path = scratch / "tiny" / f"T{i:02d}.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(listing)
        jobs.append(WellJob(path.stem, {"stations": path}, WellMetadata()))
    # warm this process (lazy imports of the CSV reader) so the pool's forks start warm too
    registry = load_registry()
    run_plan(
        build_plan(load_spec(survey), registry),
        registry,
        inputs=dict(jobs[0].inputs),
        out_dir=scratch / "tiny-in-process",
    )
    t_pool = min(batch(jobs, scratch / f"tiny-pool-{i}", "local", 2, survey)[0] for i in range(3))
    with LocalCluster(
        n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        address = cluster.scheduler_address
        batch(jobs, scratch / "tiny-warm-up", "dask", 2, survey, address)
        t_dask = min(
            batch(jobs, scratch / f"tiny-dask-{i}", "dask", 2, survey, address)[0] for i in range(3)
        )
    return t_pool / n, t_dask / n


def coordinator_cost(jobs: list[WellJob], scratch: Path) -> float:
    """Mean seconds per well the batch process spends on a well: fingerprint (hashing the
    inputs), ledger claim and record — the same calls the batch makes, on a scratch ledger."""
    registry = load_registry()
    plan = build_plan(load_spec(PIPELINE), registry)
    identity = PlanIdentity.of(plan, registry)
    ledger = Ledger(scratch / "ledger.sqlite")
    batch_row = ledger.start_batch("bench", str(PIPELINE), plan.digest, scratch, {})
    t0 = time.perf_counter()
    for job in jobs:
        fingerprint, _ = identity.fingerprint(job)
        claim = ledger.claim(
            job.well_id,
            batch_row,
            fingerprint,
            {},
            scratch / job.well_id,
            lambda state, f=fingerprint: decide(
                Mode(), state, f, batch_id=batch_row.id, batch_started=0.0, resume_since=None
            ),
        )
        ledger.finish(WellOutcome(job.well_id, claim.run_id, "done"))  # type: ignore[union-attr]
    cost = (time.perf_counter() - t0) / len(jobs)
    ledger.close()
    return cost


def time_v_max_rss(samples: Path, out: Path) -> int:
    """Maximum resident set size (bytes) of ``gyropipe run`` on one well, by /usr/bin/time -v."""
    run = subprocess.run(
        [
            "/usr/bin/time",
            "-v",
            *GYROPIPE,
            "run",
            str(PIPELINE),
            "--input",
            str(samples),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    kib = re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr)
    assert kib is not None, run.stderr
    return int(kib.group(1)) * 1024


def uptime() -> str:
    """The machine's load as ``uptime`` states it (the batch's speed-up depends on it)."""
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, default=Path(tempfile.gettempdir()) / "gyropipe-bench-batch"
    )
    parser.add_argument("--wells", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=2, help="best of N batch timings")
    args = parser.parse_args()
    data: Path = args.data
    data.mkdir(parents=True, exist_ok=True)
    spec = yaml.safe_load(SHIPPED.read_text())  # the processing stages, without reports
    spec["stages"] = [st for st in spec["stages"] if not st["uses"].startswith("report")]
    PIPELINE.write_text(yaml.safe_dump(spec, sort_keys=False))
    simulate(data, args.wells)
    jobs = [
        WellJob(
            f"W{i + 1:02d}", {"samples": data / f"W{i + 1:02d}" / "samples.parquet"}, WellMetadata()
        )
        for i in range(args.wells)
    ]
    n = len(jobs)
    print(f"{n} wells, {os.cpu_count()} CPUs; at start: {uptime()}")

    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp)
        load_registry()  # as batch() does: local workers fork from this process
        baseline = peak_rss_bytes()
        t1s, t2s, tds = [], [], []
        for i in range(args.repeat):  # interleaved, best of each: other load comes and goes
            t1s.append(batch(jobs, scratch / f"local1-{i}", "local", 1)[0])
            t2s.append(batch(jobs, scratch / f"local2-{i}", "local", 2)[0])
            tds.append(batch(jobs, scratch / f"dask2-{i}", "dask", 2)[0])
        t1, t2, td = min(t1s), min(t2s), min(tds)
        print(f"after the batch timings: {uptime()}")
        plan = build_plan(load_spec(PIPELINE), load_registry())
        ref = PipelineRef(str(PIPELINE), plan.spec)
        start_local, start_dask = startup("local", ref), startup("dask", ref)
        tiny_pool, tiny_dask = executor_overhead(scratch, n)
        coordinator = coordinator_cost(jobs, scratch / "coordinator")
        runs1 = runs_of(scratch / f"local1-{t1s.index(t1)}")
        runs2 = runs_of(scratch / f"local2-{t2s.index(t2)}")
        biggest = max(jobs, key=lambda j: j.inputs["samples"].stat().st_size)
        rss_time_v = time_v_max_rss(biggest.inputs["samples"], scratch / "time-v")
        hour = WellJob("HOUR", {"samples": data / "HOUR" / "samples.parquet"}, WellMetadata())
        hour_baseline = peak_rss_bytes()
        batch([hour], scratch / "hour", "local", 1)
        (hour_run,) = runs_of(scratch / "hour")

    b1, b2 = (sum(r.wall_time_s or 0.0 for r in runs) for runs in (runs1, runs2))
    print(
        f"\n1. local pool: 1 worker {t1:6.1f} s, 2 workers {t2:6.1f} s → speed-up "
        f"{t1 / t2:.2f}× (target ≥ 1.8× idle); busy time in the workers {b1:.1f} s (1 worker) vs "
        f"{b2:.1f} s (2 workers: {b2 / b1 - 1:+.0%} from sharing 2 cores); wall / (busy / 2) = "
        f"{t2 / (b2 / 2):.2f} (1.00 = no scheduling loss)"
    )
    print(
        f"2. dask LocalCluster, 2 workers: {td:6.1f} s = {td / t2:.2f}× the pool (cluster start-up "
        f"{start_dask:.2f} s vs pool {start_local:.2f} s, and each new worker process imports "
        f"gyropipe on its first task) → {(td - t2) / n * 1e3:+.0f} ms/well over the pool"
    )
    print(
        f"   tiny wells, warm cluster: {tiny_dask * 1e3:.0f} ms/well vs pool "
        f"{tiny_pool * 1e3:.0f} ms/well → Dask per-task overhead "
        f"{(tiny_dask - tiny_pool) * 1e3:+.0f} ms/well"
    )
    stages = sum(r.process_time_s or 0.0 for r in runs2)
    runner = sum(r.run_time_s or 0.0 for r in runs2) - stages
    worker = sum(r.wall_time_s or 0.0 for r in runs2) - stages - runner
    print(
        f"3. per well: stages {stages / n * 1e3:.0f} ms; batch overhead: batch process (hash "
        f"inputs, ledger claim + record) {coordinator * 1e3:.1f} ms + worker (staging, run.json "
        f"paths, batch.json, publish with fsync) {worker / n * 1e3:.1f} ms; runner bookkeeping "
        f"(contract checks, persisted tables, run.json hashes) {runner / n * 1e3:.0f} ms"
    )
    print(
        f"   batch overhead / processing: {(coordinator * n + worker) / stages:.2%} "
        f"(target ≤ 5 %); with the runner's bookkeeping "
        f"{(coordinator * n + worker + runner) / stages:.2%}"
    )
    raw = {j.well_id: pq.read_table(j.inputs["samples"]).nbytes for j in jobs}
    peaks: dict[str, tuple[int, int]] = {}
    for r in runs2:
        peak, largest = peaks.get(str(r.worker), (0, 0))
        peaks[str(r.worker)] = (max(peak, r.peak_rss_bytes or 0), max(largest, raw[r.well]))
    print(f"4. workers fork from the batch process at {baseline / 2**20:.0f} MiB resident")
    for worker, (peak, largest) in sorted(peaks.items()):
        print(
            f"   worker {worker}: peak RSS {peak / 2**20:.0f} MiB "
            f"({(peak - baseline) / 2**20:+.0f} MiB over the fork); largest raw samples in Arrow "
            f"{largest / 2**20:.1f} MiB → {peak / largest:.1f}× "
            f"({(peak - baseline) / largest:.1f}× over the fork; target ≤ 3×)"
        )
    big = raw[biggest.well_id]
    print(
        f"   /usr/bin/time -v gyropipe run {biggest.well_id} ({big / 2**20:.1f} MiB raw): maximum "
        f"resident set {rss_time_v / 2**20:.0f} MiB → {rss_time_v / big:.1f}×"
    )
    hour_file = data / "HOUR" / "samples.parquet"
    hour_raw = pq.read_table(hour_file).nbytes
    hour_peak = hour_run.peak_rss_bytes or 0
    rows = pq.ParquetFile(hour_file).metadata.num_rows
    print(
        f"   one-hour survey ({rows:,} samples, {hour_raw / 2**20:.0f} MiB raw in Arrow): "
        f"worker peak {hour_peak / 2**20:.0f} MiB → {hour_peak / hour_raw:.1f}× "
        f"({(hour_peak - hour_baseline) / hour_raw:.1f}× over the fork); stages "
        f"{hour_run.process_time_s or 0:.1f} s; two such workers "
        f"{2 * hour_peak / 2**30:.1f} GiB of 24 GB"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

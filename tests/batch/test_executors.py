"""The executors' worker processes, as the batch starts them, and the pipeline they run."""

from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path

import pytest
from batch_support import make_wells, runs
from threadpoolctl import threadpool_info

from pipeline.batch.executors import DaskExecutor, LocalExecutor
from pipeline.batch.worker import WellOutcome, WellTask, run_well
from pipeline.executing import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec
from tests_support import gyropipe_cli


def test_pool_workers_run_blas_single_threaded(survey: Path):
    """Wells are the parallelism: a worker's BLAS must not spin threads on the other
    workers' cores (2 workers on 2 cores lost 18 % of their time to it)."""
    plan = build_plan(load_spec(survey), load_registry())
    executor = LocalExecutor(2, PipelineRef(str(survey), plan.spec))
    try:
        libraries = executor._pool.submit(threadpool_info).result(timeout=60)
    finally:
        executor.close(cancel=True)
    blas = [lib for lib in libraries if lib["user_api"] == "blas"]
    assert blas, libraries  # numpy's OpenBLAS is loaded in the worker
    assert {lib["num_threads"] for lib in blas} == {1}


def test_the_pool_does_not_fork_while_another_thread_runs(survey: Path):
    """A fork copies every lock another thread holds, held for good in the child (an
    earlier pool's thread in a notebook or a resumed batch hung a worker so): with another
    thread running, the workers come from the forkserver, and they run tasks."""
    stop = threading.Event()
    other = threading.Thread(target=stop.wait, daemon=True)
    other.start()
    try:
        executor = LocalExecutor(1, PipelineRef(str(survey), load_spec(survey).spec))
    finally:
        stop.set()
        other.join()
    try:
        assert executor._pool._mp_context.get_start_method() == "forkserver"
        assert executor._pool.submit(os.getpid).result(timeout=60) != os.getpid()
    finally:
        executor.close(cancel=True)


def test_the_local_dask_cluster_keeps_glibc_adaptive_malloc(survey: Path):
    """Dask's default MALLOC_TRIM_THRESHOLD_ for its workers made continuous processing 44 %
    slower; the batch's own cluster leaves it out and keeps BLAS single-threaded."""
    pytest.importorskip("distributed")
    executor = DaskExecutor(1, PipelineRef(str(survey), load_spec(survey).spec), None)
    try:
        environ = executor._client.run(lambda: dict(os.environ))
    finally:
        executor.close(cancel=True)
    (worker,) = environ.values()
    assert "MALLOC_TRIM_THRESHOLD_" not in worker
    assert worker["OPENBLAS_NUM_THREADS"] == "1"


def test_a_pool_worker_process_runs_many_wells(tmp_path: Path, survey: Path):
    """Workers import gyropipe once and take well after well: eight wells on two workers
    are recorded in the ledger by at most two worker processes, neither of them the batch
    process (so one of them ran at least four)."""
    make_wells(tmp_path / "in", [f"w{k}" for k in range(8)])
    out = tmp_path / "out"
    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    batch = gyropipe_cli(*args, "--workers", "2")
    assert batch.returncode == 0, batch.stderr
    rows = runs(out / "ledger.sqlite")
    assert [r["status"] for r in rows] == ["done"] * 8
    pids = [int(str(r["worker"]).rsplit(":", 1)[1]) for r in rows]
    assert 1 <= len(set(pids)) <= 2 and os.getpid() not in pids
    assert max(pids.count(pid) for pid in pids) >= 4


def test_workers_run_the_pipeline_the_batch_planned_not_its_file(tmp_path: Path, survey: Path):
    """The batch's plan travels to the workers (PipelineRef, once per worker): a pipeline
    file deleted after the batch planned it changes nothing, and the run is of the pipeline
    with the batch's --set overrides, which no worker applies again."""
    make_wells(tmp_path / "in", ["W"])
    plain = build_plan(load_spec(survey), load_registry())
    plan = build_plan(load_spec(survey, ["trajectory.vs_azimuth=37.5"]), load_registry())
    assert plan.digest != plain.digest
    ref = PipelineRef(str(survey), plan.spec)
    survey.unlink()
    executor = LocalExecutor(1, ref)
    outcomes: list[WellOutcome] = []
    try:
        inputs = {"stations": str(tmp_path / "in" / "W.csv")}
        executor.submit(WellTask("W", 1, 1, ref.digest, inputs, {}, str(tmp_path / "out"), "{}"))
        deadline = time.monotonic() + 60
        while not outcomes and time.monotonic() < deadline:
            outcomes.extend(executor.wait(0.1))
    finally:
        executor.close(cancel=True)
    assert [(o.well_id, o.status) for o in outcomes] == [("W", "done")], outcomes
    recorded = json.loads((tmp_path / "out" / "W" / "run.json").read_text())["pipeline"]
    assert (recorded["file"], recorded["sha256"]) == (str(survey), plan.digest)


def test_a_worker_not_given_the_pipeline_fails_the_well_naming_it(tmp_path: Path):
    task = WellTask("W", 1, 1, "ab" * 32, {}, {}, str(tmp_path / "out"), "{}")
    outcome = run_well(task)
    assert outcome.status == "failed"
    assert outcome.error == (
        "this worker was not given the batch's pipeline abababababab… (an executor hands it "
        "to worker_init or to run_well)"
    )

"""The local executor's worker processes, as the batch starts them."""

from __future__ import annotations

from pathlib import Path

from threadpoolctl import threadpool_info

from pipeline.batch.executors import LocalExecutor
from pipeline.batch.worker import PipelineRef
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec


def test_pool_workers_run_blas_single_threaded(survey: Path):
    """Wells are the parallelism: a worker's BLAS must not spin threads on the other
    workers' cores (2 workers on 2 cores lost 18 % of their time to it)."""
    plan = build_plan(load_spec(survey), load_registry())
    executor = LocalExecutor(2, PipelineRef(str(survey), (), (), plan.digest))
    try:
        libraries = executor._pool.submit(threadpool_info).result(timeout=60)
    finally:
        executor.close(cancel=True)
    blas = [lib for lib in libraries if lib["user_api"] == "blas"]
    assert blas, libraries  # numpy's OpenBLAS is loaded in the worker
    assert {lib["num_threads"] for lib in blas} == {1}

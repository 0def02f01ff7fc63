"""The executors' worker processes, as the batch starts them."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from threadpoolctl import threadpool_info

from pipeline.batch.executors import DaskExecutor, LocalExecutor
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


def test_the_local_dask_cluster_keeps_glibc_adaptive_malloc():
    """Dask's default MALLOC_TRIM_THRESHOLD_ for its workers made continuous processing 44 %
    slower; the batch's own cluster leaves it out and keeps BLAS single-threaded."""
    pytest.importorskip("distributed")
    executor = DaskExecutor(1, None)
    try:
        environ = executor._client.run(lambda: dict(os.environ))
    finally:
        executor.close(cancel=True)
    (worker,) = environ.values()
    assert "MALLOC_TRIM_THRESHOLD_" not in worker
    assert worker["OPENBLAS_NUM_THREADS"] == "1"

"""A forked batch worker never collects what it inherited from the batch process.

A batch resumed in the same process (a full ledger, then the same command again: the CLI
called in process) forked its new pool while the earlier pool was garbage not yet
collected. A worker's collector then collected that pool, and ``concurrent.futures``'
callback for it waited for a lock a thread of the batch process had held as it forked:
the worker, and the batch, hung for good (found by CI in
``test_ledger_faults.test_a_full_ledger_stops_the_batch_in_one_line_and_the_same_command_resumes``).
Here the inherited garbage is a cycle whose collection is recorded, by process id."""

from __future__ import annotations

import concurrent.futures as cf
import gc
import multiprocessing
import os
import sys
import weakref

import pytest

from pipeline.batch.worker import worker_init
from pipeline.executing import PipelineRef
from pipeline.spec import load_spec
from tests_support import ROOT

_collected_in: list[int] = []
"""the processes in which the inherited cycle was collected"""
_KEPT: list[weakref.ref[object]] = []


class _Cycle:
    def __init__(self) -> None:
        self.me = self


def _collect_here() -> bool:
    """In the worker: a full collection; whether it collected the inherited cycle."""
    gc.collect()
    return os.getpid() in _collected_in


@pytest.mark.skipif(sys.platform != "linux", reason="the local executor forks on Linux only")
def test_a_forked_worker_does_not_collect_the_garbage_it_inherited() -> None:
    pipeline = str(ROOT / "pipelines" / "survey.yaml")
    ref = PipelineRef(pipeline, load_spec(pipeline).spec)
    gc.disable()  # the cycle stays garbage in this process until the fork
    try:
        cycle = _Cycle()
        _KEPT.append(weakref.ref(cycle, lambda _: _collected_in.append(os.getpid())))
        del cycle
        with cf.ProcessPoolExecutor(
            1,
            mp_context=multiprocessing.get_context("fork"),
            initializer=worker_init,
            initargs=(ref, os.getpid()),
        ) as pool:
            assert pool.submit(_collect_here).result(timeout=60) is False
    finally:
        gc.enable()
    gc.collect()
    here = os.getpid()
    assert _collected_in == [here]  # the cycle was garbage: this process collects it

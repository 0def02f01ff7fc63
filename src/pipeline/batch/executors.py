"""Where the per-well tasks run: the executor named by ``--executor``, one registered by a
plugin (:class:`~pipeline.executing.ExecutorDef`) — built in, a local process pool (default)
or a Dask cluster.

Each runs :func:`~pipeline.batch.worker.run_well` on a :class:`WellTask` and hands back its
:class:`WellOutcome`, so the results do not depend on the executor; each hands its workers the
batch's :class:`~pipeline.executing.PipelineRef` once, not with every task.

On Linux the local pool forks its workers from the batch process when it is created — before
the batch opens its ledger or starts any thread — so they start with gyropipe and its plugins
already imported. It forks only while the process runs no other thread: a fork copies a lock
some other thread holds, held for good in the child (a notebook kernel's threads, an earlier
pool's or a Dask client's). Then, elsewhere, and for pools created later, workers come from a
``forkserver`` that imports gyropipe once. Each worker exits as soon as the batch process
is gone, so a killed batch leaves no orphan still writing outputs. A worker killed by the OS
(out of memory, a crash in native code) breaks the pool: the wells that were in it are run
again, each alone in a one-process pool, so only the well that kills its worker fails.
"""

from __future__ import annotations

import concurrent.futures as cf
import importlib
import logging
import multiprocessing
import os
import sys
import threading
from typing import Any, Protocol

from pipeline.errors import did_you_mean
from pipeline.executing import ExecutorDef, ExecutorSetup, PipelineRef
from pipeline.registry import Registry

from .jobs import BatchConfigError
from .worker import WellOutcome, WellTask, run_well, worker_init

PRELOAD = ["pipeline.batch.preload"]
WORKER_ENVIRON = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1}
"""The environment of the local Dask cluster's workers: Dask's default without its
``MALLOC_TRIM_THRESHOLD_``, which turns off glibc's adaptive mmap threshold and made a
continuous survey's processing 44 % slower (one hour at 100 Hz: 13.7 s → 19.6 s)."""


class Executor(Protocol):
    """Runs well tasks; ``wait`` returns those finished within ``timeout`` seconds. One may
    also say how many tasks it runs at once (an ``int`` attribute or property ``slots``;
    the batch keeps twice that many claimed wells in flight, else twice ``--workers``)."""

    def submit(self, task: WellTask) -> None: ...

    def wait(self, timeout: float) -> list[WellOutcome]: ...

    def close(self, cancel: bool) -> None:
        """Wait for the submitted tasks, or with ``cancel`` stop them at once."""
        ...


class LocalExecutor:
    """``concurrent.futures.ProcessPoolExecutor`` with ``workers`` processes."""

    def __init__(self, workers: int, ref: PipelineRef) -> None:
        self._workers = workers
        self.slots = workers
        self._ref = ref
        self._later = multiprocessing.get_context("forkserver")
        self._later.set_forkserver_preload(PRELOAD)
        alone = sys.platform == "linux" and threading.active_count() == 1
        early = multiprocessing.get_context("fork") if alone else self._later
        self._pool = self._new_pool(workers, early)
        self._pool.submit(os.getpid)  # a forking pool starts all its workers on a first task
        self._solo: cf.ProcessPoolExecutor | None = None
        self._futures: dict[cf.Future[WellOutcome], tuple[WellTask, cf.ProcessPoolExecutor]] = {}

    def _new_pool(
        self, workers: int, context: multiprocessing.context.BaseContext | None = None
    ) -> cf.ProcessPoolExecutor:
        return cf.ProcessPoolExecutor(
            workers,
            mp_context=context or self._later,
            initializer=worker_init,
            initargs=(self._ref, os.getpid()),
        )

    def submit(self, task: WellTask) -> None:
        try:
            future = self._pool.submit(run_well, task)
        except cf.process.BrokenProcessPool:  # a worker died since the last wait
            self._replace_broken(self._pool)
            future = self._pool.submit(run_well, task)
        self._futures[future] = (task, self._pool)

    def wait(self, timeout: float) -> list[WellOutcome]:
        done, _ = cf.wait(self._futures, timeout=timeout, return_when=cf.FIRST_COMPLETED)
        outcomes = []
        for future in done:
            task, pool = self._futures.pop(future)
            try:
                outcomes.append(future.result())
            except cf.process.BrokenProcessPool:
                if pool is self._solo:
                    self._solo = None
                    outcomes.append(_failed(task, "its worker process died (killed by the OS?)"))
                else:
                    self._retry_alone(task, pool)
        return outcomes

    def _replace_broken(self, broken: cf.ProcessPoolExecutor) -> None:
        if broken is self._pool:  # replace the broken pool once, not per failed future
            broken.shutdown(wait=False)
            self._pool = self._new_pool(self._workers)

    def _retry_alone(self, task: WellTask, broken: cf.ProcessPoolExecutor) -> None:
        self._replace_broken(broken)
        if self._solo is None:
            self._solo = self._new_pool(1)
        self._futures[self._solo.submit(run_well, task)] = (task, self._solo)

    def close(self, cancel: bool) -> None:
        for pool in (self._pool, self._solo):
            if pool is None:
                continue
            processes = list((pool._processes or {}).values())  # shutdown forgets them
            pool.shutdown(wait=not cancel, cancel_futures=True)
            if cancel:
                for process in processes:
                    process.kill()


class DaskExecutor:
    """Tasks on a Dask distributed cluster: the scheduler at ``address``, or a
    ``LocalCluster`` on 127.0.0.1 with ``workers`` single-threaded worker processes. The
    pipeline ``ref`` is scattered to the workers once; each task names it. Its
    :attr:`slots` are the cluster's worker threads, asked of the scheduler."""

    def __init__(self, workers: int, ref: PipelineRef, address: str | None) -> None:
        try:
            self._dask: Any = importlib.import_module("distributed")  # the optional extra
        except ImportError:
            raise ImportError(
                "the dask executor needs the optional extra: pip install 'gyropipe[dask]'"
            ) from None
        self._cluster: Any = None
        if address is None:
            config = importlib.import_module("dask").config
            with config.set({"distributed.nanny.pre-spawn-environ": WORKER_ENVIRON}):
                self._cluster = self._dask.LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    host="127.0.0.1",
                    dashboard_address=None,
                    silence_logs=logging.ERROR,
                )
            self._client: Any = self._dask.Client(self._cluster)
        else:
            self._client = self._dask.Client(address)
        self._ref = self._client.scatter(ref, broadcast=True, hash=False)
        self._futures: dict[Any, WellTask] = {}
        self._submitted = 0

    @property
    def slots(self) -> int:
        """The threads of the cluster's workers now (at least 1)."""
        return max(1, int(sum(self._client.nthreads().values())))

    def submit(self, task: WellTask) -> None:
        self._submitted += 1  # a check and the run after it share their run id
        key = f"gyropipe-{task.well_id}-{task.run_id}-{self._submitted}"
        future = self._client.submit(run_well, task, self._ref, key=key, pure=False)
        self._futures[future] = task

    def wait(self, timeout: float) -> list[WellOutcome]:
        if not self._futures:
            return []
        try:
            self._dask.wait(list(self._futures), timeout=timeout, return_when="FIRST_COMPLETED")
        except TimeoutError:
            return []
        outcomes = []
        for future in [f for f in self._futures if f.done()]:
            task = self._futures.pop(future)
            try:
                outcomes.append(future.result())
            except Exception as exc:  # the cluster lost the task (worker died, cancelled…)
                outcomes.append(_failed(task, f"dask: {type(exc).__name__}: {exc}"))
        return outcomes

    def close(self, cancel: bool) -> None:
        if cancel:
            self._client.cancel(list(self._futures))
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()


class UnknownExecutor(BatchConfigError):
    """``--executor`` names no registered executor, or ``--scheduler`` one that takes none."""


def executor_def(registry: Registry, name: str, scheduler: str | None = None) -> ExecutorDef:
    """The executor registered as ``name``, which must take a ``scheduler`` if one is given;
    else an :class:`UnknownExecutor` naming the registered ones."""
    found = registry.executors.get(name)
    if found is None:
        plugin = registry.disabled_provider("executor", name)
        known = sorted(registry.executors)
        raise UnknownExecutor(
            f"--executor {name}: executor {name!r} is provided by plugin {plugin}, which is "
            f"disabled (--disable-plugin {plugin})"
            if plugin is not None
            else f"--executor {name}: no executor named {name!r}{did_you_mean(name, known)} "
            f"(registered: {', '.join(known) or 'none'})"
        )
    if scheduler is not None and not found[0].scheduler:
        takes = sorted(n for n, (d, _) in registry.executors.items() if d.scheduler)
        raise UnknownExecutor(
            f"--scheduler needs an executor that takes one ({', '.join(takes) or 'none'}), "
            f"not {name!r}"
        )
    return found[0]


def open_executor(registry: Registry, name: str, setup: ExecutorSetup) -> Executor:
    """The executor ``name`` (:func:`executor_def`) created for a batch."""
    executor: Executor = executor_def(registry, name, setup.scheduler).factory(setup)
    return executor


def _failed(task: WellTask, error: str) -> WellOutcome:
    return WellOutcome(task.well_id, task.run_id, "failed", error=error)

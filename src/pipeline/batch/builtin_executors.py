"""The built-in executors, registered through the plugin hook like any plugin's
(:func:`pipeline.hookspecs.gyropipe_register_executors`). Their modules are imported when a
batch creates one, not when the plugins are loaded."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from pipeline.executing import ExecutorDef, ExecutorSetup
from pipeline.hookspecs import hookimpl

if TYPE_CHECKING:
    from .executors import Executor


def local(setup: ExecutorSetup) -> Executor:
    """A process pool on this machine (:class:`~pipeline.batch.executors.LocalExecutor`)."""
    from .executors import LocalExecutor

    return LocalExecutor(setup.workers, setup.ref)


def dask(setup: ExecutorSetup) -> Executor:
    """A Dask cluster (:class:`~pipeline.batch.executors.DaskExecutor`)."""
    from .executors import DaskExecutor

    return DaskExecutor(setup.workers, setup.ref, setup.scheduler)


@hookimpl
def gyropipe_register_executors(register: Callable[[ExecutorDef], None]) -> None:
    register(ExecutorDef("local", "a process pool on this machine (the default)", local))
    register(
        ExecutorDef(
            "dask",
            "a Dask distributed cluster: --scheduler ADDRESS, or a LocalCluster (extra 'dask')",
            dask,
            scheduler=True,
        )
    )

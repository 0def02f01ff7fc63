"""What runs a batch's wells, as plugins register it: :class:`ExecutorDef`, and the one
reference to the batch's pipeline that every executor hands its workers, :class:`PipelineRef`.

An executor runs :func:`pipeline.batch.worker.run_well` on each well task the batch hands it
and gives back each task's outcome (the protocol: :class:`pipeline.batch.executors.Executor`).
The built-in executors (``local``, ``dask``) register through the same hook as a plugin's
(:func:`pipeline.hookspecs.gyropipe_register_executors`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from pipeline.spec import LoadedSpec, PipelineSpec
from pipeline.yamlsource import SourceMap


@dataclass(frozen=True)
class PipelineRef:
    """The batch's pipeline as the batch process loaded and validated it (``--set``
    overrides applied): what each worker builds its plan from, once per process, against
    its own plugins — the file is not read again and no override applied again, so every
    well runs the pipeline the batch validated. Pickled, it is the spec alone (a few KB):
    executors hand it to a worker once (the local pool at start-up, Dask scattered to its
    workers), not with every task."""

    file: str
    """the pipeline file, absolute (recorded in each well's ``run.json``)"""
    spec: PipelineSpec
    disabled: tuple[str, ...] = ()
    """plugins left out (``--disable-plugin``)"""

    @cached_property
    def digest(self) -> str:
        """SHA-256 of the resolved spec (:meth:`PipelineSpec.digest`)."""
        return self.spec.digest()

    def loaded(self) -> LoadedSpec:
        """The spec as :func:`pipeline.graph.build_plan` takes it (already valid: no source
        positions, no problems)."""
        return LoadedSpec(self.spec, SourceMap(self.file), {}, [])


@dataclass(frozen=True)
class ExecutorSetup:
    """What an executor's factory is given."""

    workers: int
    """parallel wells asked for (``--workers``)"""
    ref: PipelineRef
    """the batch's pipeline, for the workers (:func:`pipeline.batch.worker.worker_init`)"""
    scheduler: str | None = None
    """``--scheduler ADDRESS``, for an executor that takes one (:attr:`ExecutorDef.scheduler`)"""


@dataclass(frozen=True)
class ExecutorDef:
    """An executor by name (``gyropipe batch --executor NAME``): ``factory(setup)`` returns
    an object with the methods of :class:`pipeline.batch.executors.Executor` (``submit``,
    ``wait``, ``close``), created when a batch starts and closed when it ends."""

    name: str
    description: str
    """one line, shown by ``gyropipe plugins``"""
    factory: Callable[[ExecutorSetup], Any]
    scheduler: bool = False
    """it takes ``--scheduler ADDRESS``"""

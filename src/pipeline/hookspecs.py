"""Hook specifications: how plugins (built-in or third-party) add to gyropipe.

A plugin is a module or object with functions named like the hooks below, decorated with
``pipeline.hookimpl``. Third-party plugins are found through the entry-point group
``gyropipe``. Each hook receives a ``register`` callback; call it once per item. The host
validates every item and tags it with the plugin's name, so a bad registration is reported
against its plugin and the rest keep working.
"""

from __future__ import annotations

from collections.abc import Callable

import pluggy

from pipeline.executing import ExecutorDef
from pipeline.registry import CheckDef, ReaderDef, StageDef, ToolModelDef, WriterDef
from pipeline.reporting import ReportDef

PROJECT = "gyropipe"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


@hookspec
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    """Register stage types: call ``register(StageDef(...))`` for each.

    A stage's name is what a pipeline's ``uses:`` refers to; it must be unique across
    plugins (lower-case, digits, ``_`` and ``.``; prefix with your plugin name). Ports named
    in ``StageDef.streamed_inputs`` / ``streamed_outputs`` carry a
    :class:`~pipeline.streams.TableStream` (record batches, checked batch by batch) instead
    of a whole table; every other port a whole table (docs/architecture.md, "Streamed ports").
    """


@hookspec
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    """Register file readers: call ``register(ReaderDef(...))`` for each.

    Readers are chosen by name (``reader: las``) or, with ``reader: auto``, by how sure each
    reader of the kind wanted is that the file is its own: ``sniff(path)`` returns a
    :class:`~pipeline.registry.Claim` (content recognised beats a fitting name; at equal
    strength a third-party reader beats a built-in one; a tie left is an error).
    """


@hookspec
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    """Register table writers: call ``register(WriterDef(...))`` for each."""


@hookspec
def gyropipe_register_checks(register: Callable[[CheckDef], None]) -> None:
    """Register QC checks: call ``register(CheckDef(...))`` for each."""


@hookspec
def gyropipe_register_tool_models(register: Callable[[ToolModelDef], None]) -> None:
    """Register tool-model (error model) files: call ``register(ToolModelDef(name, path))``
    for each YAML file (format: ``docs/tool-models.md``). The stages that take a tool model,
    ``gyropipe models`` and the Python API then know the model by name (the registry of the
    run hands the files to the uncertainty code); a shipped model of the same name wins."""


@hookspec
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    """Register report parts: call ``register(ReportDef(...))`` for each.

    A part named like a stage (``ReportDef("compass", …, method=…)``) states that stage's
    method in the reports' Method table when a run uses it; a part with a ``section`` adds
    a whole section (:class:`~pipeline.reporting.ReportSection`: paragraphs, tables with
    units, a figure) to the survey and calibration reports, in HTML and PDF alike. Built-in
    stages describe themselves through this hook too (``docs/vendor-adapter.md``, "Add to
    the report"). A part that raises fails the report with one line naming its plugin."""


@hookspec
def gyropipe_register_executors(register: Callable[[ExecutorDef], None]) -> None:
    """Register batch executors: call ``register(ExecutorDef(...))`` for each.

    ``gyropipe batch --executor NAME`` (and ``executor=`` of the Python API) runs the
    batch's wells on the executor called ``NAME``; ``factory`` is given an
    :class:`~pipeline.executing.ExecutorSetup` (workers, the batch's
    :class:`~pipeline.executing.PipelineRef`, ``--scheduler``) and returns an object with
    ``submit``, ``wait`` and ``close`` (:class:`pipeline.batch.executors.Executor`) that
    runs :func:`pipeline.batch.worker.run_well` on each task. The built-in ``local`` and
    ``dask`` register through this hook too (``docs/batch.md``, "Executors")."""

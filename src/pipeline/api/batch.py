"""Many wells from Python: ``gp.run_batch`` — what ``gyropipe batch`` does: one run per well into
``out/<well>``, on the executor named (a built-in or a plugin's), recorded in the ledger — and
``gp.fleet_page``, the page of every well of an output directory (``gyropipe status DIR
--html``)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, TextIO

from pipeline.api.frames import WellLike, well_metadata
from pipeline.api.run import set_overrides
from pipeline.batch import run as batch_run
from pipeline.batch.executors import executor_def
from pipeline.batch.fleet_page import FLEET_PAGE, fleet_title, write_fleet_page
from pipeline.batch.jobs import LEDGER, BatchConfigError, jobs_from_glob, jobs_from_manifest
from pipeline.batch.ledger import Ledger
from pipeline.batch.policy import Mode
from pipeline.batch.progress import JsonLines, reporter
from pipeline.batch.run import BatchOptions, BatchReport
from pipeline.batch.views import status_fleet
from pipeline.graph import build_plan
from pipeline.plugins import shared_registry
from pipeline.spec import load_spec


def run_batch(
    pipeline: str | Path,
    inputs: str | None = None,
    *,
    out: str | Path,
    manifest: str | Path | None = None,
    workers: int | None = None,
    executor: str = "local",
    scheduler: str | None = None,
    only_changed: bool = False,
    rerun_failed: bool = False,
    ledger: str | Path | None = None,
    set: Mapping[str, Any] | Sequence[str] | None = None,
    well: WellLike = None,
    disable: Sequence[str] = (),
    log: TextIO | None = None,
    progress: bool = False,
) -> BatchReport:
    """Run a pipeline YAML on many wells: ``gyropipe batch`` (``docs/batch.md``), which
    calls it.

    The wells are the files matching the glob ``inputs`` (one-input pipelines; the well id
    is the file name without extension) or the rows of the CSV ``manifest``; ``well`` gives
    header fields for every well (a manifest column overrides them); ``set`` (a mapping as
    :func:`pipeline.run` takes it, or ``--set`` items) and ``disable`` are those of
    :func:`pipeline.run`. ``executor`` names a registered executor (``gyropipe plugins``
    lists them), ``scheduler`` the address for one that takes it (dask); ``workers``
    defaults to the number of CPUs. The batch's JSON log lines go to ``log`` (default:
    stderr), or with ``progress`` a progress bar is drawn when stderr is a terminal. The
    report's ``exit_code`` is the command's. (Named ``run_batch``: ``pipeline.batch`` is the
    package.)

    Raises :class:`~pipeline.errors.SpecError` (an invalid pipeline) or
    :class:`~pipeline.batch.jobs.BatchConfigError` (an unknown executor, no wells, an
    unusable ledger), before any well runs; a failing well is in the report, never raised.
    """
    registry = shared_registry(disable)
    plan = build_plan(load_spec(pipeline, set_overrides(set)), registry)
    executor_def(registry, executor, scheduler)  # before anything is created
    if (inputs is None) == (manifest is None):
        raise BatchConfigError("give either inputs (a glob) or manifest (a CSV file)")
    names, defaults = list(plan.spec.inputs), well_metadata(well)
    jobs = (
        jobs_from_manifest(Path(manifest), names, defaults)
        if manifest is not None
        else jobs_from_glob(str(inputs), names, defaults)
    )
    options = BatchOptions(
        out_dir=Path(out),
        workers=workers or os.cpu_count() or 1,
        executor=executor,
        scheduler=scheduler,
        mode=Mode(only_changed=only_changed, rerun_failed=rerun_failed),
        ledger=Path(ledger) if ledger is not None else None,
        disabled=tuple(disable),
    )
    shown = reporter(quiet=False) if progress else JsonLines(log)
    return batch_run.run_batch(plan, registry, jobs, options, shown)


def fleet_page(
    out: str | Path, path: str | Path | None = None, *, ledger: str | Path | None = None
) -> Path:
    """Write the fleet page of the batch output directory ``out`` — what ``gyropipe status
    DIR --html`` writes (``docs/batch.md``): the latest run of every well its ledger knows
    (``ledger``, default ``out/ledger.sqlite``), failing wells first, with each well's QC,
    acceptance, clearance, drift, TD and DLS figures and a link to its report. Written
    atomically to ``path`` (default ``out/fleet.html``, the page each batch writes); returns
    it. Raises :class:`~pipeline.batch.jobs.BatchConfigError` when there is no ledger,
    :class:`~pipeline.batch.ledger.LedgerError` when it cannot be read."""
    out = Path(out)
    ledger_path = Path(ledger) if ledger is not None else out / LEDGER
    if not ledger_path.is_file():
        raise BatchConfigError(f"no ledger at {ledger_path}")
    opened = Ledger(ledger_path)
    try:
        fleet = status_fleet(opened, fleet_title(out))
    finally:
        opened.close()
    return write_fleet_page(fleet, Path(path) if path is not None else out / FLEET_PAGE)

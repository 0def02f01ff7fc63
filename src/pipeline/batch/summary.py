"""The end-of-batch summary: one row per well (status, why it ran or what failed, time),
printed as a table and written to ``DIR/summary.json`` and ``DIR/summary.csv``."""

from __future__ import annotations

import csv
import io
import json
import shutil
import textwrap
import time
from collections import Counter
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from pipeline.atomic import atomic_write_bytes

from .causes import cause
from .fleet import WellFigures
from .fleet_page import Fleet, FleetWell, write_fleet_page
from .jobs import SUMMARY_FILES
from .records import BatchRow, iso

STATUSES = ("done", "rejected", "failed", "skipped", "interrupted")


@dataclass(frozen=True)
class WellResult:
    """What a batch did with one well."""

    well: str
    status: str
    """done, rejected (done, outputs published, but the survey failed an acceptance gate),
    failed, skipped, or interrupted (the batch was stopped while it ran)"""
    detail: str
    """why it ran (done), the failed gates (rejected), the error (failed) or why it was
    skipped"""
    time_s: float | None = None
    """wall time of the run in its worker, s"""
    run_id: int | None = None


def counts(results: list[WellResult]) -> dict[str, int]:
    found = Counter(r.status for r in results)
    return {status: found.get(status, 0) for status in STATUSES}


def wrapped(prefix: str, detail: str, width: int) -> list[str]:
    """``prefix`` then ``detail`` wrapped to ``width`` columns, continuation lines indented
    under the detail (nothing is cut)."""
    room = max(width - len(prefix), 30)
    parts = textwrap.wrap(detail, room, break_on_hyphens=False) or [""]
    return [prefix + parts[0], *(" " * len(prefix) + part for part in parts[1:])]


def table_text(results: list[WellResult], width: int | None = None) -> str:
    """A plain-text table of ``results`` for a terminal of ``width`` columns (default: this
    terminal's); a failure's cause (:func:`cause`) is wrapped, never cut."""
    width = width or shutil.get_terminal_size((120, 24)).columns
    name = max([4, *(len(r.well) for r in results)])
    lines = [f"{'well':<{name}}  {'status':<8} {'time s':>8}  detail"]
    for r in results:
        time_s = f"{r.time_s:8.2f}" if r.time_s is not None else f"{'-':>8}"
        lines += wrapped(f"{r.well:<{name}}  {r.status:<8} {time_s}  ", cause(r.detail), width)
    return "\n".join(lines)


def write_summary(
    out_dir: Path,
    batch: BatchRow,
    results: list[WellResult],
    figures: Mapping[str, WellFigures] | None = None,
    ledger_id: str | None = None,
) -> list[Path]:
    """Write ``summary.json`` (batch, counts, rows), ``summary.csv`` (rows) and the fleet
    page ``fleet.html`` (:mod:`pipeline.batch.fleet_page`) atomically; ``figures``: the
    wells' fleet figures as their workers read them (the others are read from OUT, from
    the runs of ledger ``ledger_id``)."""
    document: dict[str, Any] = {
        "batch": batch.id,
        "pipeline": batch.pipeline_file,
        "pipeline_sha256": batch.pipeline_sha256,
        "started": iso(batch.started),
        "options": batch.options,
        "counts": counts(results),
        "wells": [asdict(r) for r in results],
    }
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["well", "status", "detail", "time_s", "run_id"])
    for r in results:
        time_s = "" if r.time_s is None else f"{r.time_s:.3f}"
        writer.writerow([r.well, r.status, r.detail, time_s, r.run_id or ""])
    paths = [out_dir / name for name in SUMMARY_FILES]
    atomic_write_bytes(paths[0], json.dumps(document, indent=2).encode())
    atomic_write_bytes(paths[1], text.getvalue().encode())
    write_fleet_page(batch_fleet(out_dir, batch, results, figures or {}, ledger_id), paths[2])
    return paths


def batch_fleet(
    out_dir: Path,
    batch: BatchRow,
    results: list[WellResult],
    figures: Mapping[str, WellFigures],
    ledger_id: str | None = None,
) -> Fleet:
    """The fleet page of one batch of ledger ``ledger_id``: its wells as it left them
    (``not_run``: the wells it listed and never came to)."""
    listed = batch.options.get("wells")
    not_run = max(0, listed - len(results)) if isinstance(listed, int) else 0
    wells = tuple(
        FleetWell(
            r.well, r.status, r.detail, r.time_s, r.run_id, out_dir / r.well, figures.get(r.well)
        )
        for r in results
    )
    return Fleet(
        f"Batch {batch.id}", (batch,), wells, not_run, ended=time.time(), ledger_id=ledger_id
    )

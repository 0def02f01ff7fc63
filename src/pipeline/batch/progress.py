"""Progress of a batch: a rich progress bar (wells done/failed/skipped, ETA) on a terminal,
or one JSON object per line on stderr (``--quiet``, cron, pipes).

JSON lines carry ``time`` (ISO 8601 UTC), ``event`` and the event's fields:
``start`` (batch, pipeline, wells, executor, workers), ``well`` (well, status, detail,
time_s, run_id, done, failed, skipped, total), ``note`` (message) and ``end`` (batch,
counts, wall_time_s).
"""

from __future__ import annotations

import datetime as dt
import json
import sys
from typing import Any, Protocol, TextIO

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from .summary import WellResult, counts


class Reporter(Protocol):
    def start(self, batch: int, pipeline: str, wells: int, executor: str, workers: int) -> None: ...

    def well(self, result: WellResult) -> None: ...

    def note(self, message: str) -> None: ...

    def end(self, batch: int, wall_time_s: float) -> None: ...


class JsonLines:
    """Structured log lines (module docstring)."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self._stream = stream or sys.stderr
        self._results: list[WellResult] = []
        self._total = 0

    def _emit(self, event: str, **fields: Any) -> None:
        now = dt.datetime.now(dt.UTC).isoformat(timespec="milliseconds")
        line = json.dumps({"time": now, "event": event, **fields}, separators=(",", ":"))
        self._stream.write(line + "\n")
        self._stream.flush()

    def start(self, batch: int, pipeline: str, wells: int, executor: str, workers: int) -> None:
        self._total = wells
        self._emit(
            "start", batch=batch, pipeline=pipeline, wells=wells, executor=executor, workers=workers
        )

    def well(self, result: WellResult) -> None:
        self._results.append(result)
        self._emit(
            "well",
            well=result.well,
            status=result.status,
            detail=result.detail,
            time_s=None if result.time_s is None else round(result.time_s, 3),
            run_id=result.run_id,
            total=self._total,
            **counts(self._results),
        )

    def note(self, message: str) -> None:
        self._emit("note", message=message)

    def end(self, batch: int, wall_time_s: float) -> None:
        self._emit(
            "end", batch=batch, counts=counts(self._results), wall_time_s=round(wall_time_s, 3)
        )


class ProgressBar:
    """A rich progress bar on stderr."""

    def __init__(self) -> None:
        self._console = Console(stderr=True)
        self._progress = Progress(
            TextColumn("[bold]batch {task.fields[batch]}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn(
                "[green]{task.fields[done]} done [red]{task.fields[failed]} failed "
                "[dim]{task.fields[skipped]} skipped"
            ),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=self._console,
        )
        self._task: Any = None
        self._results: list[WellResult] = []

    def start(self, batch: int, pipeline: str, wells: int, executor: str, workers: int) -> None:
        self._console.print(
            f"batch {batch}: {pipeline}, {wells} wells, {executor} executor, {workers} workers"
        )
        self._progress.start()
        self._task = self._progress.add_task(
            "wells", total=wells, batch=batch, done=0, failed=0, skipped=0
        )

    def well(self, result: WellResult) -> None:
        self._results.append(result)
        found = counts(self._results)
        self._progress.update(
            self._task,
            advance=1,
            done=found["done"],
            failed=found["failed"],
            skipped=found["skipped"],
        )
        if result.status == "failed":
            self._progress.console.print(
                f"[red]failed[/red] {escape(result.well)}: {escape(result.detail)}"
            )

    def note(self, message: str) -> None:
        self._progress.console.print(escape(message))

    def end(self, batch: int, wall_time_s: float) -> None:
        self._progress.stop()


def reporter(quiet: bool) -> Reporter:
    """A progress bar on a terminal unless ``quiet``; JSON lines otherwise."""
    if not quiet and sys.stderr.isatty():
        return ProgressBar()
    return JsonLines()

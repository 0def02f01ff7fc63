"""The stations a run recorded but dropped: those whose validity checks said drop (a
:class:`~pipeline.qc.tables.QcSummary` row of status ``drop``, its readings removed before
compassing, or one that failed a check of :data:`UNREAD`: it has no readings, whatever the
check's policy) and those compassing could not solve (:class:`~pipeline.tables.CompassRejects`).
Neither is in the trajectory, so whatever states a run's QC (the report, the JSON summary,
the command line, the fleet page) counts and names them from here. A validity drop's reason
is the detail of its failed :data:`UNREAD` row, when the validity results
(:class:`~pipeline.qc.tables.QcResults`) are among the tables."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal, get_args

import pyarrow as pa

from pipeline.qc.tables import QcResults, is_summary

REJECT_COLUMNS = frozenset({"station", "md", "reason"})
"""The columns of a table of stations compassing could not solve."""

DroppedBy = Literal["validity", "compassing"]
DROPPED_BY: tuple[str, ...] = get_args(DroppedBy)
"""What may drop a station."""
MD_DIGITS = 6
"""Two stations dropped at MDs equal to this many decimals of a metre are one."""

UNREAD = ("unread_stop",)
"""Validity checks whose failure says the station has no readings (a stop the tool made
that gave none, :mod:`pipeline.gyrocompass.stops`): its row's detail says why."""


@dataclass(frozen=True)
class Dropped:
    """A station dropped: its MD (m), station index, what dropped it — the validity checks
    (``checks``: the failed checks' names) or compassing (``reason``: why it could not be
    solved)."""

    md: float
    station: int
    by: DroppedBy
    checks: tuple[str, ...] = ()
    reason: str = ""

    def names(self) -> str:
        """What dropped it, for an engineer: the failed checks' names, or ``compassing``."""
        return ", ".join(self.checks) if self.checks else self.by

    def said(self) -> str:
        """What dropped it and, for a validity drop with a reason (a stop with no readings),
        why: the command line's words."""
        if self.by == "validity" and self.reason:
            return f"{self.names()} — {self.reason}"
        return self.names()


def is_rejects(table: pa.Table) -> bool:
    """Whether ``table`` has the columns of a table of stations compassing rejected."""
    return set(table.column_names) >= REJECT_COLUMNS


def dropped_stations(tables: Iterable[pa.Table | None]) -> list[Dropped]:
    """The stations dropped in ``tables`` (validity summaries and compassing rejects; the
    validity results give reasons; other tables and None are skipped), in MD order, each MD
    once (the first table naming it wins)."""
    present = [t for t in tables if t is not None]
    reasons = {
        (r["station"], round(r["md"], MD_DIGITS)): r["detail"]
        for t in present
        if set(QcResults.compiled().schema().names) <= set(t.column_names)
        for r in t.select(["station", "md", "check", "passed", "detail"]).to_pylist()
        if r["check"] in UNREAD and r["passed"] is False and r["md"] is not None
    }
    found: dict[float, Dropped] = {}
    for table in present:
        for item in _of(table, reasons):
            found.setdefault(round(item.md, MD_DIGITS), item)
    return [found[md] for md in sorted(found)]


def _of(table: pa.Table, reasons: dict[tuple[int, float], str]) -> list[Dropped]:
    """The stations ``table`` drops; ``ValueError`` at a row holding what its contract does
    not (a null or non-finite MD, no station index ≥ 0, no text): a table read back from a
    published file could hold anything."""
    if is_summary(table):
        rows = table.select(["md", "station", "status", "failed_checks"]).to_pylist()
        out = []
        for i, r in enumerate(rows):
            checks = tuple(c for c in _text(r, i, "failed_checks").split(",") if c)
            if r["status"] == "drop" or any(c in UNREAD for c in checks):
                dropped = _row(r, i, "validity", checks=checks)
                why = reasons.get((dropped.station, round(dropped.md, MD_DIGITS)), "")
                out.append(Dropped(dropped.md, dropped.station, "validity", checks, why))
        return out
    if is_rejects(table):
        rows = table.select(["md", "station", "reason"]).to_pylist()
        return [_row(r, i, "compassing", reason=_text(r, i, "reason")) for i, r in enumerate(rows)]
    return []


def _row(
    row: dict[str, object],
    index: int,
    by: DroppedBy,
    checks: tuple[str, ...] = (),
    reason: str = "",
) -> Dropped:
    md, station = row["md"], row["station"]
    if not isinstance(md, float | int) or not math.isfinite(md):
        raise ValueError(f"row {index}: md {md!r}, expected a finite MD (m)")
    if not isinstance(station, int) or station < 0:
        raise ValueError(f"row {index}: station {station!r}, expected a station index ≥ 0")
    return Dropped(float(md), station, by, checks, reason)


def _text(row: dict[str, object], index: int, name: str) -> str:
    value = row[name]
    if not isinstance(value, str):
        raise ValueError(f"row {index}: {name} {value!r}, expected text")
    return value

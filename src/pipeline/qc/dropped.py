"""The stations a run recorded but dropped: those whose validity checks said drop (a
:class:`~pipeline.qc.tables.QcSummary` row of status ``drop``, its readings removed before
compassing) and those compassing could not solve (:class:`~pipeline.tables.CompassRejects`).
Neither is in the trajectory, so whatever states a run's QC (the report, the JSON summary,
the command line, the fleet page) counts and names them from here."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal, get_args

import pyarrow as pa

from pipeline.qc.tables import is_summary

REJECT_COLUMNS = frozenset({"station", "md", "reason"})
"""The columns of a table of stations compassing could not solve."""

DroppedBy = Literal["validity", "compassing"]
DROPPED_BY: tuple[str, ...] = get_args(DroppedBy)
"""What may drop a station."""
MD_DIGITS = 6
"""Two stations dropped at MDs equal to this many decimals of a metre are one."""


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


def is_rejects(table: pa.Table) -> bool:
    """Whether ``table`` has the columns of a table of stations compassing rejected."""
    return set(table.column_names) >= REJECT_COLUMNS


def dropped_stations(tables: Iterable[pa.Table | None]) -> list[Dropped]:
    """The stations dropped in ``tables`` (validity summaries and compassing rejects; other
    tables and None are skipped), in MD order, each MD once (the first table naming it
    wins)."""
    found: dict[float, Dropped] = {}
    for table in tables:
        if table is None:
            continue
        for item in _of(table):
            found.setdefault(round(item.md, MD_DIGITS), item)
    return [found[md] for md in sorted(found)]


def _of(table: pa.Table) -> list[Dropped]:
    """The stations ``table`` drops; ``ValueError`` at a row holding what its contract does
    not (a null or non-finite MD, no station index ≥ 0, no text): a table read back from a
    published file could hold anything."""
    if is_summary(table):
        rows = table.select(["md", "station", "status", "failed_checks"]).to_pylist()
        return [
            _row(r, i, "validity", checks=tuple(c for c in r["failed_checks"].split(",") if c))
            for i, r in enumerate(rows)
            if r["status"] == "drop" and _text(r, i, "failed_checks")
        ]
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

"""The stations a run recorded but dropped: those whose validity checks said drop (a
:class:`~pipeline.qc.tables.QcSummary` row of status ``drop``, its readings removed before
compassing) and those compassing could not solve (:class:`~pipeline.tables.CompassRejects`).
Neither is in the trajectory, so whatever states a run's QC (the report, the JSON summary,
the command line, the fleet page) counts and names them from here."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

import pyarrow as pa

from pipeline.qc.tables import is_summary

REJECT_COLUMNS = frozenset({"station", "md", "reason"})
"""The columns of a table of stations compassing could not solve."""

MD_DIGITS = 6
"""Two stations dropped at MDs equal to this many decimals of a metre are one."""


@dataclass(frozen=True)
class Dropped:
    """A station dropped: its MD (m), station index, what dropped it — the validity checks
    (``checks``: the failed checks' names) or compassing (``reason``: why it could not be
    solved)."""

    md: float
    station: int
    by: Literal["validity", "compassing"]
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
    if is_summary(table):
        return [
            Dropped(
                float(r["md"]),
                int(r["station"]),
                "validity",
                checks=tuple(c for c in r["failed_checks"].split(",") if c),
            )
            for r in table.select(["md", "station", "status", "failed_checks"]).to_pylist()
            if r["status"] == "drop"
        ]
    if is_rejects(table):
        return [
            Dropped(float(r["md"]), int(r["station"]), "compassing", reason=r["reason"])
            for r in table.select(["md", "station", "reason"]).to_pylist()
        ]
    return []

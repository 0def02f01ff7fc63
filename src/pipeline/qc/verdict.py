"""A run's QC verdict: how many check results passed and failed (by check) and at how many
stations, over every check table the run produced — as numbers (:func:`qc_tally`, the fleet
page) and in one line (:func:`qc_verdict`, the command line)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import pyarrow as pa

__all__ = ["QcTally", "qc_tally", "qc_verdict"]


@dataclass
class QcTally:
    """Check results counted: ``evaluated`` (a null ``passed`` is not), ``failed`` by check,
    the MDs (m, rounded to 1 µm) of the stations with a failure and the failed data windows
    (rows without MD)."""

    evaluated: int = 0
    failed: Counter[str] = field(default_factory=Counter)
    stations: set[float] = field(default_factory=set)
    windows: int = 0

    @property
    def failures(self) -> int:
        return sum(self.failed.values())


def qc_tally(
    tables: Iterable[pa.Table], others: Iterable[tuple[str, int, Sequence[float]]] = ()
) -> QcTally:
    """The results of ``tables`` (each with ``check``, ``passed`` and ``md`` columns: check
    results, validity results; a null ``passed`` was not evaluated and counts for neither).
    Stations are told apart by MD; a failed row without MD is a data window. ``others``:
    checks recorded otherwise, as (name, stations evaluated, MD of each failed station)."""
    tally = QcTally()
    for table in tables:
        checks = table.column("check").to_pylist()
        passed = table.column("passed").to_pylist()
        md = table.column("md").to_pylist()
        for name, ok, depth in zip(checks, passed, md, strict=True):
            if ok is None:
                continue
            tally.evaluated += 1
            if not ok:
                tally.failed[name] += 1
                if depth is None:
                    tally.windows += 1
                else:
                    tally.stations.add(round(float(depth), 6))
    for name, count, failed_md in others:
        tally.evaluated += count
        if failed_md:
            tally.failed[name] += len(failed_md)
            tally.stations.update(round(float(depth), 6) for depth in failed_md)
    return tally


def qc_verdict(
    tables: Iterable[pa.Table], others: Iterable[tuple[str, int, Sequence[float]]] = ()
) -> str | None:
    """``"QC: 8 failed checks (dls_limit: 8) at 8 stations"`` or ``"QC: all 60 checks
    passed"`` over ``tables`` and ``others`` (:func:`qc_tally`); None when no table holds a
    result."""
    tally = qc_tally(tables, others)
    if not tally.evaluated:
        return None
    if not tally.failed:
        return f"QC: all {tally.evaluated} checks passed"
    by_check = ", ".join(f"{name}: {n}" for name, n in tally.failed.items())
    where = [_count(len(tally.stations), "station"), _count(tally.windows, "data window")]
    return f"QC: {_count(tally.failures, 'failed check')} ({by_check}) at " + " and ".join(
        w for w in where if w
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'s' * (n != 1)}" if n else ""

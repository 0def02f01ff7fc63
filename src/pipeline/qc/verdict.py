"""A run's QC verdict: how many check results passed and failed (by check) and at how many
stations, over every check table the run produced, and the stations it dropped — as numbers
(:func:`qc_tally`, the fleet page) and in one line (:func:`qc_verdict`, the command line)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from pipeline.qc.dropped import Dropped

__all__ = ["INOUT_COLUMNS", "QcTally", "inout_checks", "qc_tally", "qc_verdict"]

INOUT_COLUMNS = ["md", "inc_diff", "azi_diff", "inc_tolerance", "azi_tolerance"]
"""The columns of a free gyro's in-run/out-run comparison
(:class:`~pipeline.drift.tables.InOutQc`) its checks are counted from."""


@dataclass
class QcTally:
    """Check results counted: ``evaluated`` (a null ``passed`` is not), ``failed`` by check,
    the MDs (m, rounded to 1 µm) of the stations with a failure, the failed data windows
    (rows without MD) and the stations dropped (:mod:`pipeline.qc.dropped`)."""

    evaluated: int = 0
    failed: Counter[str] = field(default_factory=Counter)
    stations: set[float] = field(default_factory=set)
    windows: int = 0
    dropped: list[Dropped] = field(default_factory=list)

    @property
    def failures(self) -> int:
        return sum(self.failed.values())


def qc_tally(
    tables: Iterable[pa.Table],
    others: Iterable[tuple[str, int, Sequence[float]]] = (),
    dropped: Sequence[Dropped] = (),
) -> QcTally:
    """The results of ``tables`` (each with ``check``, ``passed`` and ``md`` columns: check
    results, validity results; a null ``passed`` was not evaluated and counts for neither).
    Stations are told apart by MD; a failed row without MD is a data window. ``others``:
    checks recorded otherwise, as (name, stations evaluated, MD of each failed station);
    ``dropped``: the stations the run dropped."""
    tally = QcTally(dropped=list(dropped))
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


def inout_checks(inout: pa.Table) -> list[tuple[str, int, list[float]]]:
    """A free gyro's in-run/out-run comparison as two checks, ``in_out_inclination`` and
    ``in_out_azimuth`` (|in − out| within its tolerance, as the report's QC section judges
    them), each as (name, stations compared, MD (m) of each that failed) — the ``others`` of
    :func:`qc_tally`; an azimuth at vertical (no difference) is not compared."""
    md = np.asarray(inout.column("md").to_numpy(zero_copy_only=False), dtype=np.float64)
    found = []
    for quantity, name in (("inc", "in_out_inclination"), ("azi", "in_out_azimuth")):
        diff = np.asarray(
            inout.column(f"{quantity}_diff").to_numpy(zero_copy_only=False), dtype=np.float64
        )
        tol = np.asarray(
            inout.column(f"{quantity}_tolerance").to_numpy(zero_copy_only=False),
            dtype=np.float64,
        )
        compared = ~np.isnan(diff)
        failed = compared & ~(np.abs(diff) <= tol)
        found.append((name, int(compared.sum()), md[failed].tolist()))
    return found


SHOWN = 8
"""Stations dropped the verdict line names (the rest counted)."""


def qc_verdict(
    tables: Iterable[pa.Table],
    others: Iterable[tuple[str, int, Sequence[float]]] = (),
    dropped: Sequence[Dropped] = (),
) -> str | None:
    """``"QC: 8 failed checks (dls_limit: 8) at 8 stations"`` or ``"QC: all 60 checks
    passed"`` over ``tables`` and ``others`` (:func:`qc_tally`), then the stations
    ``dropped`` (``"; 1 station dropped (MD 200.10 m: rest_acc)"``); None when no table holds
    a result and nothing was dropped."""
    tally = qc_tally(tables, others, dropped)
    said = [_checks(tally)] if tally.evaluated else []
    if tally.dropped:
        shown = ", ".join(f"MD {d.md:.2f} m: {d.said()}" for d in tally.dropped[:SHOWN])
        more = f", and {len(tally.dropped) - SHOWN} more" if len(tally.dropped) > SHOWN else ""
        said.append(f"{_count(len(tally.dropped), 'station')} dropped ({shown}{more})")
    return "QC: " + "; ".join(said) if said else None


def _checks(tally: QcTally) -> str:
    """What the line says of the check results (some evaluated)."""
    if not tally.failed:
        return f"all {tally.evaluated} checks passed"
    by_check = ", ".join(f"{name}: {n}" for name, n in tally.failed.items())
    where = [_count(len(tally.stations), "station"), _count(tally.windows, "data window")]
    return f"{_count(tally.failures, 'failed check')} ({by_check}) at " + " and ".join(
        w for w in where if w
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'s' * (n != 1)}" if n else ""

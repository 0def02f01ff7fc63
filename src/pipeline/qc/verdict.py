"""A run's QC verdict in one line, for the command line: how many check results failed (by
check) and at how many stations, over every check table the run produced."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Sequence

import pyarrow as pa

__all__ = ["qc_verdict"]


def qc_verdict(
    tables: Iterable[pa.Table], others: Iterable[tuple[str, int, Sequence[float]]] = ()
) -> str | None:
    """``"QC: 8 failed checks (dls_limit: 8) at 8 stations"`` or ``"QC: all 60 checks
    passed"`` over ``tables`` (each with ``check``, ``passed`` and ``md`` columns: check
    results, validity results; a null ``passed`` was not evaluated and counts for neither);
    None when no table holds a result. Stations are told apart by MD; a failed row without
    MD is a data window. ``others``: checks recorded otherwise, as (name, stations
    evaluated, MD of each failed station)."""
    failed: Counter[str] = Counter()
    stations: set[float] = set()
    windows = 0
    evaluated = 0
    for table in tables:
        checks = table.column("check").to_pylist()
        passed = table.column("passed").to_pylist()
        md = table.column("md").to_pylist()
        for name, ok, depth in zip(checks, passed, md, strict=True):
            if ok is None:
                continue
            evaluated += 1
            if not ok:
                failed[name] += 1
                if depth is None:
                    windows += 1
                else:
                    stations.add(round(float(depth), 6))
    for name, count, failed_md in others:
        evaluated += count
        if failed_md:
            failed[name] += len(failed_md)
            stations.update(round(float(depth), 6) for depth in failed_md)
    if not evaluated:
        return None
    if not failed:
        return f"QC: all {evaluated} checks passed"
    by_check = ", ".join(f"{name}: {n}" for name, n in failed.items())
    total = sum(failed.values())
    where = [_count(len(stations), "station"), _count(windows, "data window")]
    return f"QC: {_count(total, 'failed check')} ({by_check}) at " + " and ".join(
        w for w in where if w
    )


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}{'s' * (n != 1)}" if n else ""

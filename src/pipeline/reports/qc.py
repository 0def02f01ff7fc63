"""QC results of a run turned into report material: per-check series with their tolerance
bands, per-check summary rows, and a QC flag per survey station.

Sources: the validity checks' :class:`~pipeline.qc.tables.QcResults` (|measured −
reference| ≤ tolerance) and :class:`~pipeline.qc.tables.QcSummary`, generic
:class:`~pipeline.tables.CheckResults` (value ≤ limit), free-gyro
:class:`~pipeline.drift.tables.InOutQc` and two runs'
:class:`~pipeline.qc.tables.RunComparison` (in − out within tolerance), and the acceptance
gates of a survey (:class:`~pipeline.tables.AcceptanceGates`); the stations dropped (the
validity checks' drops and compassing's rejects, :mod:`pipeline.qc.dropped`), which the
listing cannot show.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.qc.dropped import UNREAD, Dropped
from pipeline.qc.tables import diagnoses
from pipeline.reports.check_titles import check_title, printed_unit
from pipeline.reports.document import Column, Table, Verdict, fmt_sig
from pipeline.reports.flags import (
    CHECKS,
    NOT_COMPARED,
    Flag,
    compass_flag,
    continuous_flags,
    failed_check,
)
from pipeline.reports.numbers import fmt
from pipeline.reports.plots import FloatArray, QcSeries

MD_MATCH = 1e-3
"""Two MDs within this many metres are the same station."""


@dataclass(frozen=True)
class QcSources:
    """The QC tables wired into a report (any may be absent)."""

    qc: pa.Table | None = None
    summary: pa.Table | None = None
    checks: pa.Table | None = None
    inout: pa.Table | None = None
    stations: pa.Table | None = None
    comparison: pa.Table | None = None
    gates: pa.Table | None = None

    def any(self) -> bool:
        return any(
            t is not None
            for t in (self.qc, self.summary, self.checks, self.inout, self.comparison, self.gates)
        )

    def compared(self) -> list[pa.Table]:
        """The in-run/out-run comparisons present (free-gyro QC, two runs compared)."""
        return [t for t in (self.inout, self.comparison) if t is not None and t.num_rows]


def _floats(table: pa.Table, name: str) -> FloatArray:
    values: FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


def validity_series(qc: pa.Table) -> list[QcSeries]:
    """One series per validity check, evaluated rows with an MD only."""
    checks = qc.column("check").to_pylist()
    passed = qc.column("passed").to_pylist()
    units = qc.column("unit").to_pylist()
    md = _floats(qc, "md")
    deviation = _floats(qc, "measured") - _floats(qc, "reference")
    tolerance = _floats(qc, "tolerance")
    evaluated = np.array([p is not None for p in passed], dtype=bool) & ~np.isnan(md)
    names = np.array(checks, dtype=object)
    out = []
    for name in dict.fromkeys(checks):
        rows = names == name
        done = rows & evaluated
        if not done.any():
            continue
        titled = check_title(name, "measured − reference")
        out.append(
            QcSeries(
                name=name,
                unit=printed_unit(units[int(np.flatnonzero(rows)[0])]),
                x=md[done],
                value=deviation[done],
                low=np.zeros(done.sum()) if titled.limit else -tolerance[done],
                high=tolerance[done],
                passed=np.array([passed[i] for i in np.flatnonzero(done)], dtype=bool),
                quantity=titled.plotted,
                skipped=int(rows.sum() - done.sum()),
                title=titled.title,
            )
        )
    return out


def check_series(checks: pa.Table) -> list[QcSeries]:
    """One series per generic check: the value with the band from 0 (or −limit for signed
    quantities) up to the limit."""
    names = checks.column("check").to_pylist()
    md = _floats(checks, "md") if "md" in checks.schema.names else np.full(checks.num_rows, np.nan)
    x = np.where(np.isnan(md), _floats(checks, "row"), md)
    value, limit = _floats(checks, "value"), _floats(checks, "limit")
    passed = np.array(checks.column("passed").to_pylist(), dtype=bool)
    units = checks.column("unit").to_pylist()
    out = []
    for name in dict.fromkeys(names):
        rows = np.array([n == name for n in names])
        low = np.zeros(rows.sum()) if (value[rows] >= 0).all() else -limit[rows]
        titled = check_title(name, "value")
        out.append(
            QcSeries(
                name,
                printed_unit(units[int(np.flatnonzero(rows)[0])]),
                x[rows],
                value[rows],
                low,
                limit[rows],
                passed[rows],
                titled.plotted,
                title=titled.title,
            )
        )
    return out


def inout_series(inout: pa.Table) -> list[QcSeries]:
    """In-run minus out-run inclination and azimuth with their tolerances."""
    md = _floats(inout, "md")
    out = []
    for quantity, name in (("inc", "in/out inclination"), ("azi", "in/out azimuth")):
        diff = _floats(inout, f"{quantity}_diff")
        tol = _floats(inout, f"{quantity}_tolerance")
        ok = ~np.isnan(diff)  # an azimuth at vertical is not compared
        out.append(
            QcSeries(
                name,
                "°",
                md[ok],
                diff[ok],
                -tol[ok],
                tol[ok],
                np.abs(diff[ok]) <= tol[ok],
                "in − out",
                skipped=int((~ok).sum()),
                title=f"In-run − out-run {name.removeprefix('in/out ')}",
            )
        )
    return out


def all_series(src: QcSources) -> list[tuple[str, list[QcSeries]]]:
    """(title, series) of every QC source present, for charts and the summary table."""
    groups = []
    if src.qc is not None:
        groups.append(("Validity checks", validity_series(src.qc)))
    if src.checks is not None:
        groups.append(("Survey checks", check_series(src.checks)))
    for table in src.compared():
        groups.append(("In-run / out-run comparison", inout_series(table)))
    return [(title, series) for title, series in groups if series]


def summary_rows(series: list[QcSeries]) -> list[tuple[str, ...]]:
    """Per check: unit, evaluated, passed, failed, not evaluated, worst |value|/limit."""
    rows: list[tuple[str, ...]] = []
    for s in series:
        span = np.abs(np.where(s.value >= 0, s.high, s.low))
        with np.errstate(divide="ignore", invalid="ignore"):  # a zero band: 0, or undefined
            ratio = np.where(span > 0, np.abs(s.value) / span, np.where(s.value == 0, 0, np.nan))
        worst = float(np.max(ratio)) if len(s.value) else float("nan")
        rows.append(
            (
                s.title or s.name,
                s.unit,
                str(len(s.value)),
                str(int(s.passed.sum())),
                str(int((~s.passed).sum())),
                str(s.skipped),
                fmt_sig(worst, 2),
            )
        )
    return rows


def _station_flags(flags: str | int | None) -> list[Flag]:
    """A station's own flags: continuous-mode bit flags, or gyrocompassing flags (comma
    separated names)."""
    if isinstance(flags, int):
        return continuous_flags(flags)
    return [compass_flag(name) for name in (flags or "").split(",") if name]


def station_flags(md: FloatArray, src: QcSources) -> list[list[Flag]]:
    """The flags of each trajectory station (empty: nothing flagged): failed checks (station
    verdicts, survey checks, in/out differences) and processing flags of the stations."""
    found: dict[int, list[Flag]] = defaultdict(list)

    def at(mds: FloatArray, flags: list[list[Flag]]) -> None:
        index = np.clip(np.searchsorted(md, mds), 0, len(md) - 1)
        for value, i, station in zip(mds, index, flags, strict=True):
            near = [j for j in (i - 1, i) if 0 <= j < len(md) and abs(md[j] - value) <= MD_MATCH]
            if not near:
                continue
            for flag in station:
                if flag not in found[near[0]]:
                    found[near[0]].append(flag)

    if src.summary is not None:
        status = src.summary.column("status").to_pylist()
        failed = src.summary.column("failed_checks").to_pylist()
        at(
            _floats(src.summary, "md"),
            [
                [failed_check(c) for c in f.split(",") if c] if s != "ok" else []
                for s, f in zip(status, failed, strict=True)
            ],
        )
    if src.checks is not None and "md" in src.checks.schema.names:
        passed = src.checks.column("passed").to_pylist()
        names = src.checks.column("check").to_pylist()
        md_checks = _floats(src.checks, "md")
        keep = ~np.isnan(md_checks)
        at(
            md_checks[keep],
            [
                [] if p else [failed_check(n)]
                for n, p, k in zip(names, passed, keep, strict=True)
                if k
            ],
        )
    for table in src.compared():
        at(
            _floats(table, "md"),
            [[] if p else [failed_check("in/out")] for p in table.column("passed").to_pylist()],
        )
    if src.inout is not None and src.inout.num_rows:  # a free gyro's station read once
        pairs = _floats(src.inout, "md")
        once = md[np.abs(md[:, None] - pairs[None, :]).min(axis=1) > MD_MATCH]
        at(once, [[NOT_COMPARED] for _ in once])
    if src.stations is not None and "flags" in src.stations.schema.names:
        at(
            _floats(src.stations, "md"),
            [_station_flags(f) for f in src.stations.column("flags").to_pylist()],
        )
    return [found.get(i, []) for i in range(len(md))]


def flag_table(flags: list[list[Flag]]) -> Table | None:
    """Every flag the listing shows, explained once: failed checks first, then processing
    flags, each with the number of stations it is on (None: nothing flagged)."""
    counts: dict[Flag, int] = {}
    for station in flags:
        for flag in station:
            counts[flag] = counts.get(flag, 0) + 1
    if not counts:
        return None
    order = sorted(counts, key=lambda f: not f.failed)  # stable: first seen first
    return Table(
        "Flags in the listing",
        (
            Column("Flag", align="left"),
            Column("Kind", align="left"),
            Column("Stations"),
            Column("Meaning", align="left", wrap=True),
        ),
        tuple(
            (
                f.label,
                "failed check" if f.failed else "processing flag",
                str(counts[f]),
                f.meaning[:1].upper() + f.meaning[1:],
            )
            for f in order
        ),
        kind="flags",
        note="A failed check highlights the station's row in the listing; a processing flag "
        "highlights its QC cell and the values it applies to.",
    )


def diagnosis_table(summary: pa.Table | None) -> Table | None:
    """The validity checks' diagnoses of the failed stations: suspected sensor (or
    interference), where, and the estimate (None: nothing diagnosed)."""
    found = diagnoses(summary) if summary is not None else []
    if not found:
        return None
    return Table(
        "Diagnosis of failed validity checks",
        (
            Column("Suspect", align="left"),
            Column("Stations"),
            Column("MD, m", align="left"),
            Column("Diagnosis", align="left", wrap=True),
        ),
        tuple(
            (
                d.suspect or "—",
                str(len(d.md)),
                f"{fmt(min(d.md))} – {fmt(max(d.md))}" if len(d.md) > 1 else fmt(d.md[0]),
                d.diagnosis,
            )
            for d in found
        ),
        kind="qc",
        note="The sensor a failure points to, from fitting one fault at a time to the "
        "readings at rest; 'undetermined' where the data cannot tell.",
    )


RECORDING_CHECKS = ("recording_end", "missing_positions")
"""Checks of what the recording holds (:mod:`pipeline.qc.recording`): their failures are
listed with their numbers (:func:`recording_table`)."""


RECORDING_TITLE = "Stations cut short or incomplete"


def _recording_failures(qc: pa.Table | None, checks: tuple[str, ...]) -> list[dict[str, Any]]:
    """The failed rows of ``checks`` in ``qc`` (none without it)."""
    if qc is None:
        return []
    return [
        r
        for r in qc.select(["md", "position", "check", "passed", "detail"]).to_pylist()
        if r["check"] in checks and r["passed"] is False
    ]


def recording_verdicts(qc: pa.Table | None, dropped: Sequence[Dropped] = ()) -> list[Verdict]:
    """The summary's lines on the stops the end of the recording cut short and the stations
    that lack frame positions (one line a station; none for a station ``dropped``: it is
    not one the survey rests on, and the summary says why it was dropped)."""
    lines: dict[float, str] = {}
    gone = np.array([d.md for d in dropped])
    for r in _recording_failures(qc, RECORDING_CHECKS):
        if r["md"] is not None and (np.abs(gone - r["md"]) <= MD_MATCH).any():
            continue
        if r["check"] == RECORDING_CHECKS[0]:
            lines[r["md"]] = (
                f"The recording ended during the stop at MD {fmt(r['md'])} m, before its frame "
                f"position {r['position'] + 1} was complete"
            )
        else:
            lines.setdefault(r["md"], f"The station at MD {fmt(r['md'])} m lacks frame positions")
    return [
        Verdict(
            "warn",
            f"{line}: it rests on less data than its neighbours (see “{RECORDING_TITLE}” in "
            "the QC section).",
        )
        for line in lines.values()
    ]


def recording_table(qc: pa.Table | None) -> Table | None:
    """The stations the end of the recording cut short, or that lack frame positions: MD,
    position (numbered from 1) and what was found, with the averaging time used (None:
    none)."""
    found = _recording_failures(qc, RECORDING_CHECKS)
    if not found:
        return None
    return Table(
        RECORDING_TITLE,
        (
            Column("MD, m", align="left"),
            Column("Frame position"),
            Column("Finding", align="left", wrap=True),
        ),
        tuple(
            (
                "—" if r["md"] is None else fmt(r["md"]),
                "—" if r["position"] is None else str(r["position"] + 1),
                r["detail"][:1].upper() + r["detail"][1:] + ".",
            )
            for r in found
        ),
        kind="qc",
        note="The survey's usual averaging time and number of frame positions are those of "
        "its other positions and stations; a station cut short rests on less data than its "
        "neighbours.",
    )


GATE_LABELS = {
    "stations": "Stations compared, in-run and out-run",
    "inclination": "Inclination, in-run − out-run",
    "azimuth": "Azimuth, in-run − out-run",
    "azimuth_low": "Azimuth at low inclination, in-run − out-run",
    "depth": "Depth, in-run − out-run",
    "tie_in": "Tie-in closure, in-run − out-run",
    "coverage": "Depth coverage, largest gap",
    "td": "Total depth reached",
}
"""Client-facing names of the built-in acceptance gates (others show their own name)."""


def gates_table(gates: pa.Table) -> Table:
    """The acceptance gates, one row each, failed rows marked: the worst value against the
    limit and the result."""
    rows = []
    for g in gates.to_pylist():
        value = g["value"]
        shown = "—" if value is None or not np.isfinite(value) else fmt_sig(value, 3)
        label = GATE_LABELS.get(g["gate"], g["gate"])
        rows.append(
            (label, g["description"], shown, fmt_sig(g["limit"], 3), g["unit"], g["status"].upper())
        )
    return Table(
        "Acceptance gates",
        (
            Column("Gate", align="left"),
            Column("Criterion", align="left", wrap=True),
            Column("Worst value"),
            Column("Limit"),
            Column("Unit", align="left"),
            Column("Result", align="left"),
        ),
        tuple(rows),
        kind="gates",
        marked=frozenset(i for i, r in enumerate(rows) if r[5] == "FAIL"),
        note="Each gate compares the worst station (or the number of stations compared) with "
        "the client's limit; a gate with nothing to compare is not evaluated.",
    )


def gates_verdict(gates: pa.Table) -> Verdict:
    """One line: the survey accepted, or which gates failed."""
    rows = gates.to_pylist()
    failed = [GATE_LABELS.get(g["gate"], g["gate"]) for g in rows if g["status"] == "fail"]
    if failed:
        return Verdict("fail", f"Acceptance: FAILED — {'; '.join(failed)}.")
    skipped = sum(1 for g in rows if g["status"] not in ("pass", "fail"))
    note = f" ({skipped} not evaluated)" if skipped else ""
    return Verdict("ok", f"Acceptance: PASSED — all {len(rows) - skipped} gates{note}.")


DROPPED_TITLE = "Stations dropped"
SHOWN = 8
"""Stations a summary line names (failed, dropped); the rest are counted."""


def _mds(md: Sequence[float]) -> str:
    """``100.05 m, 200.10 m …`` (the first :data:`SHOWN`)."""
    return ", ".join(f"{fmt(x)} m" for x in md[:SHOWN]) + (" …" if len(md) > SHOWN else "")


def dropped_by(station: Dropped) -> str:
    """What dropped a station, in the report's words: the failed checks' titles, or
    gyrocompassing."""
    if station.by == "compassing":
        return "Gyrocompassing"
    return "; ".join(check_title(c, "").title for c in station.checks) or "Validity checks"


def qc_verdict(flags: list[list[Flag]], md: FloatArray, dropped: Sequence[Dropped]) -> Verdict:
    """The summary's QC line: the stations recorded but ``dropped`` (a warning: the listing
    cannot show them), the listed stations that failed a check (by MD), and how many carry
    each processing flag."""
    n = len(flags)
    failed = [i for i, f in enumerate(flags) if any(x.failed for x in f)]
    counts: dict[str, int] = {}
    for station in flags:
        for label in dict.fromkeys(x.label for x in station if not x.failed):
            counts[label] = counts.get(label, 0) + 1
    caveats = sum(1 for f in flags if any(not x.failed for x in f))
    said = []
    if dropped:
        k = len(dropped)
        each = ", ".join(f"MD {fmt(d.md)} m ({dropped_by(d).lower()})" for d in dropped[:SHOWN])
        said.append(
            f"{k} station{'s' * (k != 1)} recorded {'were' if k != 1 else 'was'} dropped: "
            f"{'their' if k != 1 else 'its'} readings are in neither the listing nor the "
            "trajectory — "
            f"{each}{' …' if k > SHOWN else ''}, see “{DROPPED_TITLE}” in the QC section"
        )
    if failed:
        said.append(
            f"{len(failed)} of {n} stations failed a check (MD {_mds([md[i] for i in failed])}); "
            "their rows are highlighted in the listing and the checks explained in the QC section"
        )
    elif dropped:
        said.append(f"none of the {n} stations listed failed a check")
    elif caveats:
        said.append("no station failed a check")
    if caveats:
        said.append(
            f"{caveats} of {n} stations carry processing flags "
            f"({', '.join(f'{label}: {count}' for label, count in counts.items())}), marked in "
            "the listing and explained in the QC section"
        )
    if not said:
        return Verdict("ok", f"QC: all {n} stations passed.")
    return Verdict("warn" if failed or dropped else "info", f"QC: {'; '.join(said)}.")


def _finding(rows: list[dict[str, Any]]) -> str:
    """A failed check's worst row of a station (its failed rows ``rows``) in words: the
    quantity, its value against the tolerance, at which frame position."""
    name = rows[0]["check"]
    titled = check_title(name, "measured − reference")

    def value(r: dict[str, Any]) -> float:
        return float(r["measured"] if titled.limit else r["measured"] - r["reference"])

    worst = max(rows, key=lambda r: abs(value(r)) / r["tolerance"] if r["tolerance"] else np.inf)
    unit = printed_unit(worst["unit"])
    bound = "limit " if titled.limit else "tolerance ±"
    where = f" at frame position {worst['position'] + 1}" if worst["position"] is not None else ""
    more = f" (failed at {len(rows)} positions)" if len(rows) > 1 else ""
    return (
        f"{titled.plotted[:1].upper()}{titled.plotted[1:]} {fmt_sig(value(worst), 3)} {unit}, "
        f"{bound}{fmt_sig(worst['tolerance'], 3)} {unit}{where}{more}"
    )


def _why(station: Dropped, qc: pa.Table | None) -> str:
    """Why a station was dropped, in words: each failed check's meaning and finding, or
    why compassing could not solve it."""
    if station.by == "compassing":
        return f"Gyrocompassing could not solve this stop: {station.reason}."
    failed = [
        r
        for r in (qc.to_pylist() if qc is not None else [])
        if r["passed"] is False
        and r["md"] is not None
        and abs(r["md"] - station.md) <= MD_MATCH
        and r["measured"] is not None
        and r["tolerance"] is not None
    ]
    words = []
    for check in station.checks:
        meaning = CHECKS.get(check, f"the check {check!r} found a value beyond its limit.")
        rows = [r for r in failed if r["check"] == check]
        found = f" {_finding(rows)}." if rows else ""
        if check in UNREAD and station.reason:
            found = f" {station.reason[:1].upper()}{station.reason[1:]}."
        words.append(f"{meaning[:1].upper()}{meaning[1:]}{found}")
    return " ".join(words)


def dropped_table(dropped: Sequence[Dropped], qc: pa.Table | None) -> Table | None:
    """The stations recorded but dropped: MD, what dropped it and why, with the validity
    checks' findings from ``qc`` (None: none dropped)."""
    if not dropped:
        return None
    return Table(
        DROPPED_TITLE,
        (
            Column("MD, m", align="left"),
            Column("Dropped by", align="left"),
            Column("Why", align="left", wrap=True),
        ),
        tuple((fmt(d.md), dropped_by(d), _why(d, qc)) for d in dropped),
        kind="dropped",
        marked=frozenset(range(len(dropped))),
        note="A station dropped was recorded, but its readings were not used: a point "
        "survey's listing, trajectory and exported files lack it (one course spans it between "
        "its neighbours); a continuous run is not tied to a stop dropped.",
    )

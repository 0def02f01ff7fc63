"""Contracts of the QC outputs: one row per check evaluation, a per-station verdict and the
magnetic anomaly intervals found along depth."""

from __future__ import annotations

from dataclasses import dataclass

import pyarrow as pa

from pipeline.contracts import TableContract, column

STATUSES = ("ok", "flag", "drop", "stop")
"""Station verdicts, in increasing severity."""


class QcResults(TableContract):
    """One row per check and reading (station × frame position), station (station-level
    checks: ``position`` null) or data window (``window_start``/``window_end`` set, station
    and position null). ``measured``, ``reference`` and ``tolerance`` are in ``unit``; the
    check passes when ``|measured − reference| ≤ tolerance``. ``passed`` is null when the
    check could not be evaluated (``detail`` says why)."""

    station: int | None = column(unit=None, ge=0, description="station index (null: window)")
    position: int | None = column(
        unit=None, ge=0, description="frame position within the station (null: station-level)"
    )
    window_start: float | None = column(unit="s", description="start time of the window")
    window_end: float | None = column(unit="s", description="end time of the window")
    md: float | None = column(unit="m", description="measured depth (null: unknown)")
    check: str = column(unit=None, description="check name (an option of QcOptions)")
    measured: float = column(unit=None, finite=False, description="measured value (in `unit`)")
    reference: float = column(unit=None, finite=False, description="reference value (`unit`)")
    tolerance: float = column(
        unit=None, finite=False, description="allowed |measured − reference| (in `unit`)"
    )
    unit: str = column(unit=None, description="unit of measured, reference and tolerance")
    passed: bool | None = column(unit=None, description="within tolerance (null: not evaluated)")
    suspect: str = column(
        unit=None,
        description="suspected sensor ('gyro y', 'acc x', 'mag z', …), 'interference' when an "
        "external magnetic field explains a magnetic check, 'undetermined' when the data "
        "cannot tell, '' when not failed or not a sensor check",
    )
    detail: str = column(unit=None, description="what failed, by how much, and the diagnosis")


class QcSummary(TableContract):
    """Verdict per station: the most severe policy among its failed checks."""

    station: int = column(unit=None, ge=0, description="station index")
    md: float = column(unit="m", description="measured depth of the station")
    status: str = column(unit=None, description="ok, flag, drop (exclude downstream) or stop")
    failed_checks: str = column(unit=None, description="comma-separated names of failed checks")
    suspect: str = column(
        unit=None,
        description="suspected sensor ('gyro y', 'acc x', 'mag z', …), 'interference' (an "
        "external magnetic field), 'undetermined' or ''",
    )
    diagnosis: str = column(unit=None, description="fault isolation result, e.g. bias estimate")


@dataclass(frozen=True)
class Diagnosis:
    """One diagnosis of a QcSummary and the stations (MD, m) it was made at."""

    suspect: str
    diagnosis: str
    md: tuple[float, ...]


def diagnoses(summary: pa.Table) -> list[Diagnosis]:
    """The distinct (suspect, diagnosis) of a QcSummary's failed stations, in station order."""
    found: dict[tuple[str, str], list[float]] = {}
    for row in summary.select(["md", "status", "suspect", "diagnosis"]).to_pylist():
        if row["status"] != "ok" and (row["suspect"] or row["diagnosis"]):
            found.setdefault((row["suspect"], row["diagnosis"]), []).append(row["md"])
    return [Diagnosis(s, d, tuple(md)) for (s, d), md in found.items()]


def is_summary(table: pa.Table) -> bool:
    """Whether ``table`` has the columns of a QcSummary."""
    return set(QcSummary.compiled().schema().names) <= set(table.column_names)


class MagneticAnomalies(TableContract):
    """Intervals of continuous data whose magnetic field or dip departs from the reference
    model: overlapping or touching failed windows merged."""

    start: float = column(unit="s", description="start time of the first failed window")
    end: float = column(unit="s", description="end time of the last failed window")
    md_from: float | None = column(unit="m", description="smallest window MD (null: no MD)")
    md_to: float | None = column(unit="m", description="largest window MD (null: no MD)")
    field_error: float = column(
        unit="nT", finite=False, description="largest |measured − reference| total field"
    )
    dip_error: float = column(
        unit="deg", finite=False, description="largest |measured − reference| dip"
    )
    windows: int = column(unit=None, ge=1, description="failed windows merged")


def diagnosis_lines(name: str, table: pa.Table) -> list[str]:
    """A validity summary's verdict for the terminal: failed stations and each diagnosis
    (no lines for a table that is not a validity summary, or one without failures)."""
    if not is_summary(table):
        return []
    failed = sum(s != "ok" for s in table.column("status").to_pylist())
    if not failed:
        return []
    lines = [f"{name}: {failed} of {table.num_rows} stations failed a validity check"]
    for d in diagnoses(table):
        lines.append(f"  suspect {d.suspect or '—'} at {len(d.md)} stations: {d.diagnosis}")
    return lines


class RunComparison(TableContract):
    """An in-run compared with an out-run of one tool: one row per pair of stations (the
    out-run station nearest in MD); a row passes when inclination, azimuth and depth agree
    within their tolerances."""

    station: int = column(unit=None, ge=0, description="row of the in-run station")
    md: float = column(unit="m", description="in-run measured depth")
    md_out: float = column(unit="m", description="out-run measured depth")
    md_diff: float = column(unit="m", description="in − out measured depth")
    inc_in: float = column(unit="deg", description="in-run inclination")
    inc_out: float = column(unit="deg", description="out-run inclination")
    inc_diff: float = column(unit="deg", description="in − out inclination")
    azi_in: float = column(unit="deg", finite=False, description="in-run azimuth (NaN: vertical)")
    azi_out: float = column(unit="deg", finite=False, description="out-run azimuth (NaN: vertical)")
    azi_diff: float = column(
        unit="deg", finite=False, description="in − out azimuth, wrapped to ±180° (NaN: vertical)"
    )
    inc_tolerance: float = column(unit="deg", ge=0, description="allowed |inc_diff|")
    azi_tolerance: float = column(unit="deg", ge=0, description="allowed |azi_diff|")
    passed: bool = column(unit=None, description="inclination, azimuth and depth within tolerance")

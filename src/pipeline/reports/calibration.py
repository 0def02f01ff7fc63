"""The drift calibration report: per instrument the linearity verdict, the selected drift
estimate with its σ beside the traditional two-reading estimate, the series table, every
estimate, and a plot of the series. The method is cited by its paper
(:data:`~pipeline.reports.literature.DRIFT_CALIBRATION`)."""

from __future__ import annotations

from functools import partial
from typing import Any

import numpy as np
import pyarrow as pa

from pipeline.drift.calibration import LINEAR, reading_errors, reading_times
from pipeline.registry import Provenance
from pipeline.reports import plots
from pipeline.reports.document import (
    Block,
    Column,
    Document,
    Fields,
    Level,
    Paragraph,
    Plot,
    Section,
    Table,
    Verdict,
    fmt,
    fmt_sig,
    fmt_sigma,
    items,
)
from pipeline.reports.literature import DRIFT_CALIBRATION, Citations
from pipeline.reports.numbers import fmt_measured
from pipeline.reports.parts import Parts, Registered
from pipeline.reports.sections import footer, provenance_section, signoff_section, tool_fields
from pipeline.reports.survey import ReportInputError
from pipeline.well import WellMetadata


def methods_note(cite: str) -> str:
    """What each estimate of the drift is, ``cite`` the mark of the method's paper."""
    return (
        f"Estimates — adjacent: two neighbouring series (the formula of {cite}); pair: two "
        "other series; mean: average of the adjacent estimates; grouped: first half of the "
        "series against the second half; fit: weighted straight line through all series "
        "means (minimum variance); traditional: two single readings of one set azimuth "
        "about the control interval apart. Gain: σ of the traditional method over the "
        "control interval divided by the estimate's σ."
    )


def calibration_document(
    result: pa.Table,
    series: pa.Table,
    readings: pa.Table | None,
    well: WellMetadata,
    provenance: Provenance,
    title: str,
    registered: Registered,
) -> Document:
    """The calibration report of every instrument in a calibrate_drift result, with what
    the ``registered`` report parts state and add."""
    if result.num_rows == 0 or series.num_rows == 0:
        empty = "result" if result.num_rows == 0 else "series"
        raise ReportInputError(
            f"the calibration {empty} table has no rows (the stage that produced it gave "
            "none): nothing to report"
        )
    given = {"result": result, "series": series, "readings": readings}
    tables = {port: table for port, table in given.items() if table is not None}
    if readings is not None and readings.num_rows == 0:
        readings = None  # wired but empty: the report as without readings
    instruments = list(dict.fromkeys(result.column("instrument").to_pylist()))
    citations = Citations()
    parts = Parts(registered, "calibration", tables, well, provenance, citations)
    method = parts.methods()
    cite = citations.cite(DRIFT_CALIBRATION)
    added = parts.sections()  # before the reference list: they may cite
    references = citations.fields()
    owner = _reading_owner(readings, instruments) if readings is not None else None
    sections = [
        Section(
            "Instrument and run",
            (
                Fields(
                    "Calibration",
                    items(
                        [
                            (
                                "Instrument" + ("s" if len(instruments) > 1 else ""),
                                ", ".join(instruments),
                            ),
                            ("Readings", str(readings.num_rows) if readings is not None else None),
                            ("Series", str(series.num_rows)),
                            *(_set_azimuths(readings)),
                        ]
                    ),
                ),
                tool_fields(well, provenance, []),
            ),
            key="run",
        ),
        Section(
            "Method",
            (
                Fields("Method", tuple(method)),
                Paragraph(methods_note(cite)),
                *([references] if references is not None else []),
            ),
            key="method",
        ),
    ]
    for name in instruments:
        sections.append(
            _instrument(
                name,
                result.filter(pa.compute.equal(result.column("instrument"), name)),
                series.filter(pa.compute.equal(series.column("instrument"), name)),
                None
                if readings is None or owner is None
                else readings.filter(pa.array(owner == name)),
                single=len(instruments) == 1,
                cite=cite,
            )
        )
    sections += [*added, signoff_section(), provenance_section(provenance)]
    return Document(
        title=title,
        subject=", ".join(instruments),
        subtitle=" · ".join(x for x in (well.tool_type, well.service_company, well.company) if x),
        issued=f"Processed {provenance.started:%Y-%m-%d}",
        footer=footer(provenance),
        sections=tuple(sections),
    )


def _reading_owner(readings: pa.Table, instruments: list[str]) -> np.ndarray:
    """Instrument of each reading; rows without one belong to the result's instrument that
    no named row claims (as calibration assigned them)."""
    if "instrument" in readings.schema.names:
        names = readings.column("instrument").to_pylist()
    else:
        names = [None] * readings.num_rows
    unclaimed = [i for i in instruments if i not in set(names)]
    fallback = unclaimed[0] if len(unclaimed) == 1 else None
    return np.array([n if n is not None else fallback for n in names], dtype=object)


def _set_azimuths(readings: pa.Table | None) -> list[tuple[str, str]]:
    if readings is None:
        return []
    levels = np.unique(readings.column("set_azimuth").to_numpy())
    step = np.unique(np.round(np.diff(levels), 6))
    spacing = f" every {fmt(step[0], 0)}°" if len(step) == 1 else ""
    return [("Set azimuths", f"{len(levels)}: {fmt(levels[0], 0)}–{fmt(levels[-1], 0)}°{spacing}")]


def _verdict(row: dict[str, Any]) -> Verdict:
    verdict = str(row["verdict"])
    chi2, dof, p = row["chi2"], row["dof"], row["p_value"]
    stats = f"χ² = {fmt_sig(float(chi2))} on {dof} degrees of freedom, p = {fmt_sig(float(p))}"
    level: Level
    if verdict == LINEAR:
        level, text = "ok", f"Linear drift: the series means lie on a straight line ({stats})."
    elif verdict.startswith("non-linear"):
        level, text = "fail", f"NOT linear: {verdict.split(': ', 1)[-1]} ({stats})."
    else:
        level, text = "info", f"Linearity {verdict}."
    return Verdict(level, text)


def _pm(row: dict[str, Any], per: str, decimals: int) -> str:
    """'drift ± σ' of an estimate ``row``, per hour or per minute (``per``: h, min): σ with
    two significant digits, the drift to at least ``decimals`` decimals and σ's last."""
    drift, sigma = row[f"drift_deg_{per}"], row[f"sigma_deg_{per}"]
    return f"{fmt_measured(drift, sigma, decimals)} ± {fmt_sigma(sigma)}"


def _instrument(
    name: str,
    result: pa.Table,
    series: pa.Table,
    readings: pa.Table | None,
    single: bool,
    cite: str,
) -> Section:
    rows = result.to_pylist()
    selected = next((r for r in rows if r["selected"]), rows[0])
    traditional = next((r for r in rows if r["method"] == "traditional"), None)
    summary = [
        (
            f"Drift ({selected['method']})",
            f"{_pm(selected, 'h', 3)} °/h  ({_pm(selected, 'min', 4)} °/min)",
        ),
        ("Reading σ", f"{fmt_sigma(selected['reading_sigma'])}° (pattern and drift removed)"),
    ]
    if traditional is not None:
        summary += [
            (
                "Traditional estimate",
                f"{_pm(traditional, 'h', 3)} °/h over {fmt(traditional['interval'] / 60, 1)} min",
            ),
            (
                "Gain over traditional",
                f"{fmt(selected['gain'], 1)}× smaller σ than the traditional estimate (the "
                f"method's paper {cite} predicts √(n(n−1)/2) = "
                f"{fmt(selected['gain_claimed'], 1)}× for {_per_series(series)} readings per "
                "series)",
            ),
        ]
    series_table = Table(
        "Series",
        (
            Column("Series"),
            Column("Readings"),
            Column("Mid-time", "min"),
            Column("Mean error", "°"),
            Column("σ of mean", "°"),
            Column("Residual σ", "°"),
        ),
        tuple(
            (
                str(r["series"]),
                str(r["readings"]),
                fmt(r["mid_time"] / 60, 2),
                fmt_measured(r["mean_error"], r["sigma_mean"], 3),
                fmt_sigma(r["sigma_mean"]),
                fmt_sigma(r["residual_std"]),
            )
            for r in series.to_pylist()
        ),
        kind="series",
        note="Mean azimuth error of each series with the set-azimuth pattern removed.",
    )
    estimates = Table(
        "Drift estimates",
        (
            Column("Method", align="left"),
            Column("Series / readings", align="left", wrap=True),
            Column("Drift", "°/h"),
            Column("σ", "°/h"),
            Column("Drift", "°/min"),
            Column("σ", "°/min"),
            Column("Interval", "min"),
            Column("Gain"),
            Column("Used", align="left"),
        ),
        tuple(
            (
                r["method"],
                r["label"],
                fmt_measured(r["drift_deg_h"], r["sigma_deg_h"], 3),
                fmt_sigma(r["sigma_deg_h"]),
                fmt_measured(r["drift_deg_min"], r["sigma_deg_min"], 4),
                fmt_sigma(r["sigma_deg_min"]),
                fmt(r["interval"] / 60, 1),
                fmt(r["gain"], 1),
                "selected" if r["selected"] else "",
            )
            for r in rows
        ),
        kind="estimates",
    )
    blocks: list[Block] = [
        _verdict(selected),
        Fields("Drift rate", tuple(summary)),
        series_table,
        estimates,
        Plot(
            "series",
            f"Calibration series of {name}",
            "Left: azimuth error of each reading (dots, by series), series means ± 2σ "
            "(squares) and the fitted drift drawn through the weighted centre of the means. "
            "Right: every estimate ± σ; vertical line: fitted rate.",
            partial(plots.calibration_series, data=_points(series, rows, readings)),
            (6.9, 4.8),
        ),
    ]
    title = "Result" if single else f"Instrument {name}"
    return Section(title, tuple(blocks), key=f"instrument-{name}")


def _per_series(series: pa.Table) -> str:
    """'n = 13' when every series has the same number of readings, else 'n'."""
    counts = set(series.column("readings").to_pylist())
    return f"n = {counts.pop()}" if len(counts) == 1 else "n"


def _points(
    series: pa.Table, rows: list[dict[str, Any]], readings: pa.Table | None
) -> plots.SeriesPoints:
    fit = next((r for r in rows if r["method"] == "fit"), None)
    time = error = ids = None
    if readings is not None and readings.num_rows:
        ids = readings.column("series").to_numpy().astype(np.int64)
        time = reading_times(readings, ids) / 60.0
        error = reading_errors(readings)
    return plots.SeriesPoints(
        reading_time_min=time,
        reading_error=error,
        reading_series=ids,
        series=series.column("series").to_numpy().astype(np.int64),
        mid_time_min=series.column("mid_time").to_numpy() / 60.0,
        mean_error=series.column("mean_error").to_numpy(),
        sigma_mean=series.column("sigma_mean").to_numpy(),
        fit_rate_h=float(fit["drift_deg_h"]) if fit else None,
        fit_sigma_h=float(fit["sigma_deg_h"]) if fit else None,
        estimates=tuple(
            (
                f"{r['method']} {r['label']}"
                if r["method"] in ("adjacent", "pair")
                else str(r["method"]),
                float(r["drift_deg_h"]),
                float(r["sigma_deg_h"]),
                bool(r["selected"]),
            )
            for r in rows
        ),
    )

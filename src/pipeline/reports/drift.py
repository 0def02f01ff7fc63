"""The survey report's gyro drift section: the drift rate the survey was corrected with —
of a calibration, which estimate of which instrument, recorded when — and the correction
against time and depth."""

from __future__ import annotations

from functools import partial

import numpy as np
import pyarrow as pa

from pipeline.drift.correction import DriftRate, correction_rate, drift_rate_of
from pipeline.reports import plots
from pipeline.reports.document import (
    Block,
    Column,
    Fields,
    Paragraph,
    Plot,
    Section,
    Table,
    Verdict,
    fmt,
    fmt_sig,
    fmt_sigma,
)
from pipeline.reports.listing import col
from pipeline.reports.numbers import fmt_measured
from pipeline.reports.sections import north_label

ESTIMATES = {
    "adjacent": "two neighbouring series",
    "pair": "two series",
    "mean": "mean of the neighbouring-series rates",
    "grouped": "first half of the series against the second half",
    "fit": "weighted straight line through the series means",
    "traditional": "two single readings of one set azimuth",
}
"""What each calibration estimate is, in the client's words."""
SOURCES = {
    "given": "a rate given for the run",
    "tie_in": "the misclosure at the tie-in station (its first in-run and last out-run readings)",
}
"""Where a rate not from a calibration came from, in the client's words."""
NOT_STATED = "not stated"


def drift_section(drift: pa.Table | None, calibration: pa.Table | None) -> Section:
    """The section of the corrected readings ``drift`` and the ``calibration`` wired to the
    report: the rate applied as the readings record it; without that record (readings
    written before it was kept), the calibration's selected estimates as such."""
    applied = drift_rate_of(drift) if drift is not None else None
    blocks: list[Block] = []
    if applied is not None and applied.source == "calibration":
        blocks += [calibration_used(applied), *caveat_verdicts(drift)]
    elif applied is not None:
        blocks.append(rate_applied(applied))
    elif calibration is not None:
        blocks.append(selected_estimates(calibration))
    if drift is not None:
        blocks += _correction(drift)
    return Section("Gyro drift", tuple(blocks), key="drift")


def caveat_verdicts(drift: pa.Table | None) -> list[Verdict]:
    """Where the calibration the survey was corrected with does not cover it (extrapolated
    in time or temperature, old, the survey's tool unstated): a warning each, for the drift
    section and the summary."""
    applied = drift_rate_of(drift) if drift is not None and drift.num_rows else None
    caveats = applied.caveats if applied is not None else ()
    return [Verdict("warn", f"Drift calibration: {caveat}.") for caveat in caveats]


def calibration_used(rate: DriftRate) -> Table:
    """The calibration estimate a survey was corrected with, in one row."""
    method = rate.method or ""
    estimate = f"{method}: {ESTIMATES[method]}" if method in ESTIMATES else method
    return Table(
        "Drift calibration used",
        (
            Column("Instrument", align="left"),
            Column("Estimate", align="left", wrap=True),
            Column("Series / readings", align="left", wrap=True),
            Column("Drift", "°/h"),
            Column("σ", "°/h"),
            Column("Calibrated", align="left"),
            Column("Linearity", align="left", wrap=True),
        ),
        (
            (
                rate.instrument or NOT_STATED,
                estimate,
                rate.label or "",
                fmt_measured(rate.rate, rate.sigma, 3),
                fmt_sigma(rate.sigma),
                rate.calibration_date or NOT_STATED,
                rate.verdict or "",
            ),
        ),
        kind="calibration",
    )


def rate_applied(rate: DriftRate) -> Fields:
    """Where a given or tie-in rate a survey was corrected with came from (the rate itself
    is stated beside the correction)."""
    return Fields("Drift rate applied", (("Source", SOURCES[rate.source]),))


def selected_estimates(cal: pa.Table) -> Table:
    """The selected estimate of each instrument of a calibration wired to the report, when
    the corrected readings do not record which one was applied."""
    chosen = cal.filter(cal.column("selected")).to_pylist()
    return Table(
        "Drift calibration (selected estimates; the one applied is not recorded)",
        (
            Column("Instrument", align="left"),
            Column("Estimate", align="left"),
            Column("Drift", "°/h"),
            Column("σ", "°/h"),
            Column("Calibrated", align="left"),
            Column("Linearity", align="left", wrap=True),
        ),
        tuple(
            (
                r["instrument"],
                r["method"],
                fmt_measured(r["drift_deg_h"], r["sigma_deg_h"], 3),
                fmt_sigma(r["sigma_deg_h"]),
                r.get("calibration_date") or NOT_STATED,
                r["verdict"],
            )
            for r in chosen
        ),
        kind="calibration",
    )


def _rate(drift: pa.Table) -> str:
    """The drift rate a survey was corrected with and its σ; of a table written before
    they were recorded, the slope of its correction."""
    if "sigma_drift_rate" in drift.schema.names:
        rate, sigma = (float(col(drift, c)[0]) for c in ("drift_rate", "sigma_drift_rate"))
        return f"drift rate {fmt_measured(rate, sigma, 3)} °/h, σ {fmt_sigma(sigma)} °/h"
    rate = correction_rate(col(drift, "time"), col(drift, "correction"))
    return f"the correction grows at {fmt_sig(rate)} °/h (slope of the correction against time)"


def _correction(drift: pa.Table) -> list[Block]:
    """How many readings were corrected over what time with what rate, and the correction
    plotted."""
    time_h = col(drift, "time") / 3600.0
    span = float(np.ptp(time_h))
    text = f"{drift.num_rows} readings corrected over {fmt(span, 2)} h; {_rate(drift)}."
    outbound = np.array([r == "out" for r in drift.column("run").to_pylist()])
    return [
        Paragraph(text),
        Plot(
            "drift",
            "Drift correction",
            "Left: correction subtracted from each reading against time. Right: azimuth as "
            "read (grey) and corrected against MD.",
            partial(
                plots.drift_correction,
                time_h=time_h,
                correction=col(drift, "correction"),
                md=col(drift, "md"),
                azi_raw=col(drift, "azi_raw"),
                azi=col(drift, "azi"),
                outbound=outbound,
                north_label=north_label(drift, "azi"),
            ),
            (6.9, 3.4),
        ),
    ]

"""Drift correction of free-gyro surveys and their in-run/out-run QC (DOMAIN.md §4).

A free gyro's azimuth reading drifts linearly in time: ``A_corr(t) = A(t) − ω_d·(t − t0)``,
t0 the time of the first in-run reading at the tie-in station (else of the first reading).
The drift rate ω_d (°/h) is

- ``calibration``: the instrument's calibrated rate (:mod:`pipeline.drift.calibration`),
  matched by the serial of the tool that read the survey (:func:`survey_serial`: the
  readings' own, else the stage's ``instrument``, else the well's ``tool_serial``, all that
  are stated agreeing; a calibration of one instrument needs no serial), with its σ;
- ``given``: a rate (and σ) named in the parameters;
- ``tie_in``: the survey's own misclosure at the tie-in station — the first in-run and the
  last out-run readings there see the same azimuth, so ω_d = wrap(A_last − A_first) /
  (t_last − t_first): the misclosure distributed linearly in time.

With a ``reference_azimuth`` (the known azimuth at the tie-in station) the orientation
offset A_first − reference is removed as well; without one, azimuths stay referenced to the
gyro's orientation at the tie-in.

The rate's σ: the calibration's or the given one; a tie-in misclosure's is that of its two
readings, σ_ω = √2·σ_r / (t_last − t_first). The corrected readings carry the rate and its
σ (``drift_rate``, ``sigma_drift_rate``, °/h) so that every document quoting the rate can
state its uncertainty.

Predicted errors: the corrected errors are a linear map of the reading errors ε (σ_r each)
plus the rate error δω (σ_ω): ``err = G·ε + τ·δω`` with τ = t − t0 in hours, so
``Cov = σ_r²·G·Gᵀ + σ_ω²·τ·τᵀ`` exactly (tie-in: G = I − u·(e_last − e_first)ᵀ,
u = (t − t0)/(t_last − t_first); a reference subtracts e_first from every row). σ_r is the
``reading_sigma`` parameter, or estimated robustly from the in/out differences d_k of the
stations read twice, the tie-in readings left out. A rate error δω adds δω·Δτ_k to d_k
(Δτ_k the time between the station's two readings), and so does a tie-in's own error: the
least-squares line in Δτ is removed from the d_k, leaving residuals r_k independent of the
rate's error (an estimate that saw it would shrink the stated σ where the error is large).
σ_r² = median(r_k²/g_k) / m_n, g_k = Var(r_k)/σ_r², m_n the expected sample median of n
χ²₁ values (order-statistic quadrature, :func:`chi2_median_mean`; 0.4549, the median of
χ²₁, only as n → ∞), so σ_r² is unbiased for a few dozen pairs. Pairs beyond
``OUTLIER``·σ̂_r are left out of the line and the median is taken again, so a bad station
moves neither. The σ's carry σ̂_r as if known (no Student-t widening): with 40–80 pairs
±1.96 σ holds 94 % of the errors (benchmarks/README.md, study_drift_sigma.py). Azimuths in
degrees, times in seconds.

QC: each station read on both runs is compared after correction; it fails when
``|inc_in − inc_out| > inc_tolerance`` (default 0.23°) or ``|azi_in − azi_out|`` exceeds
``azi_tolerance`` (1.0°) at a mean inclination ≥ ``low_inclination`` (10°), or
``azi_tolerance_low`` (5.0°) below it — industry gyro in/out-run tolerances. The tie-in
station's pair is judged against ``azi_tolerance`` at any inclination (its error shifts every
corrected azimuth); with the rate from its own misclosure its two corrected readings are
equal by construction, so it is compared with its out-run reading corrected by the rate the
other pairs show instead (:func:`_tie_check`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.contracts import NORTH_KEY
from pipeline.drift.applicability import MAX_AGE_DAYS
from pipeline.drift.calibration import LINEAR, UNTESTED, FloatArray, wrap
from pipeline.drift.tables import CorrectedFreeGyroReadings, DriftStations, InOutQc
from pipeline.errors import GyropipeError
from pipeline.survey.calculation import record_of, with_record

OUTLIER = 5.0
"""A pair whose residual exceeds this many σ of it is left out of σ_r's rate line."""


class CorrectionOptions(BaseModel):
    """Parameters of drift correction (angles deg, rates °/h)."""

    model_config = ConfigDict(extra="forbid")
    source: Literal["auto", "calibration", "given", "tie_in"] = Field(
        "auto",
        description="drift rate from the calibration input, the given rate, or the tie-in "
        "misclosure; auto: calibration if wired, else given if set, else tie-in",
    )
    drift_rate: float | None = Field(None, description="given drift rate, °/h")
    drift_sigma: float = Field(0.0, ge=0, description="σ of the given drift rate, °/h")
    instrument: str | None = Field(
        None,
        description="serial of the tool that read the survey, looked up in the calibration "
        "(default: the readings' own, else the well's tool_serial; each one stated must agree)",
    )
    estimate: str | None = Field(
        None, description="calibration method to use (default: the selected estimate)"
    )
    allow_nonlinear: bool = Field(
        False, description="use a calibration whose verdict is not linear"
    )
    max_calibration_age_days: float = Field(
        MAX_AGE_DAYS,
        gt=0,
        description="days between the calibration and the survey beyond which the "
        "calibration is old (a caveat)",
    )
    calibration_caveats: Literal["warn", "refuse"] = Field(
        "warn",
        description="a calibration that does not cover the survey (its time span, "
        "temperatures, age; the survey's tool serial unstated): warn, or refuse",
    )
    reference_azimuth: float | None = Field(
        None, description="known azimuth at the tie-in station (removes the orientation offset)"
    )
    tie_station: int = Field(0, ge=0, description="station index of the tie-in (surface)")
    reading_sigma: float | None = Field(
        None, gt=0, description="σ of one azimuth reading (default: from the in/out pairs)"
    )
    stations_from: Literal["mean", "in", "out"] = Field(
        "mean", description="stations from the mean of both runs, the in-run or the out-run"
    )
    inc_tolerance: float = Field(0.23, gt=0, description="in/out inclination tolerance")
    azi_tolerance: float = Field(1.0, gt=0, description="in/out azimuth tolerance")
    azi_tolerance_low: float = Field(5.0, gt=0, description="azimuth tolerance below…")
    low_inclination: float = Field(10.0, ge=0, description="…this mean inclination")


DRIFT_RATE_KEY = b"gyropipe.drift_rate"
"""Schema metadata of corrected readings: the :class:`DriftRate` they were corrected with."""


class DriftRate(BaseModel):
    """A drift rate (°/h), its σ and where it came from: a calibration (which estimate of
    which instrument, recorded when, and its linearity verdict), a given rate or the tie-in
    misclosure. The σ of a tie-in misclosure's rate is √2·σ_r / (t_last − t_first) (h),
    σ_r that of one reading: known once the survey is corrected
    (:attr:`CorrectedSurvey.rate`), 0 before."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    rate: float = Field(description="drift rate, °/h")
    sigma: float = Field(ge=0, description="σ of the rate, °/h")
    source: Literal["calibration", "given", "tie_in"]
    instrument: str | None = Field(None, description="the calibrated instrument's serial")
    method: str | None = Field(None, description="the calibration estimate (fit, mean…)")
    label: str | None = Field(None, description="the series or readings it compares")
    calibration_date: str | None = Field(None, description="day of the calibration, ISO 8601")
    verdict: str | None = Field(None, description="the calibration's linearity verdict")
    caveats: tuple[str, ...] = Field(
        (), description="where the calibration does not cover the survey, one sentence each"
    )


def drift_rate_of(table: pa.Table) -> DriftRate | None:
    """The drift rate corrected readings record (None: a table written before they did)."""
    return record_of(table, DRIFT_RATE_KEY, DriftRate)


@dataclass(frozen=True)
class CorrectedSurvey:
    """Corrected readings, combined stations, in/out QC, the rate used and σ_r (deg)."""

    readings: pa.Table
    stations: pa.Table
    qc: pa.Table
    rate: DriftRate
    reading_sigma: float


def azimuth360(angle: FloatArray) -> FloatArray:
    """Angles (deg) in [0, 360) (``%`` alone rounds tiny negative angles up to 360)."""
    wrapped = np.mod(angle, 360.0)
    out: FloatArray = np.where(wrapped >= 360.0, 0.0, wrapped)
    return out


class CalibrationMatchError(GyropipeError, ValueError):
    """The calibration cannot be matched to the tool that read the survey: the serials stated
    for that tool disagree, or the calibration holds no estimate of it."""


def survey_serial(stated: Mapping[str, str | None]) -> str | None:
    """The serial of the tool that read the survey: the first one ``stated`` (what states it
    → the serial, None where silent; the readings' own first). Raises
    :class:`CalibrationMatchError` when two stated serials differ — whose calibration
    applies is then unknown, and applying either could be another tool's."""
    named = {who: serial for who, serial in stated.items() if serial is not None}
    if len(set(named.values())) > 1:
        listed = ", ".join(f"{who} {serial!r}" for who, serial in named.items())
        raise CalibrationMatchError(
            f"the tool serials disagree ({listed}): which tool read the survey, and so whose "
            "drift calibration applies, is unknown; correct the one that is wrong"
        )
    return next(iter(named.values()), None)


def calibration_rate(
    calibration: pa.Table, serial: str | None, estimate: str | None, allow_nonlinear: bool
) -> DriftRate:
    """The drift rate of instrument ``serial`` (the survey's tool, :func:`survey_serial`)
    from a :class:`CalibrationResult` table: the row of method ``estimate``, else its selected
    row. Without a serial, the calibration must hold one instrument. Raises
    :class:`CalibrationMatchError` when it holds no row of the serial (or the estimate)."""
    instruments = calibration.column("instrument").to_pylist()
    held = ", ".join(map(repr, sorted(set(instruments))))
    if serial is None:
        if len(set(instruments)) != 1:
            raise CalibrationMatchError(
                "the survey's tool serial is stated nowhere (the readings' header, the well's "
                f"tool_serial, the stage's instrument) and the calibration holds instruments "
                f"{held}: state the tool serial"
            )
        serial = instruments[0]
    if serial not in instruments:
        raise CalibrationMatchError(
            f"the calibration holds no estimate of instrument {serial!r}, the tool that read "
            f"the survey (it calibrates {held}): give that tool's calibration, another "
            "tool's drift is not this one's"
        )
    methods = calibration.column("method").to_pylist()
    selected = calibration.column("selected").to_pylist()
    rows = [
        i
        for i, name in enumerate(instruments)
        if name == serial and (methods[i] == estimate if estimate else selected[i])
    ]
    if not rows:
        found = sorted({m for m, name in zip(methods, instruments, strict=True) if name == serial})
        raise CalibrationMatchError(
            f"no calibration estimate {estimate or 'selected'!r} of instrument {serial!r} "
            f"(its estimates: {', '.join(found)})"
        )
    if len(rows) > 1:
        raise CalibrationMatchError(
            f"{len(rows)} calibration rows of {serial!r} match: name one estimate"
        )
    row = calibration.slice(rows[0], 1).to_pylist()[0]
    if row["verdict"] not in (LINEAR, UNTESTED) and not allow_nonlinear:
        raise ValueError(
            f"instrument {serial}: calibration verdict {row['verdict']!r} "
            f"(p = {row['p_value']:.3g}); set allow_nonlinear to correct anyway"
        )
    return DriftRate(
        rate=float(row["drift_deg_h"]),
        sigma=float(row["sigma_deg_h"]),
        source="calibration",
        instrument=serial,
        method=row["method"],
        label=row["label"],
        calibration_date=row.get("calibration_date"),
        verdict=row["verdict"],
    )


def correct_survey(
    readings: pa.Table, options: CorrectionOptions, rate: DriftRate | None = None
) -> CorrectedSurvey:
    """Remove the drift from :class:`~pipeline.tables.FreeGyroReadings`: with ``rate``
    (calibrated or given), else from the tie-in misclosure."""
    run = np.array(readings.column("run").to_pylist(), dtype=object)
    station = readings.column("station").to_numpy()
    time = readings.column("time").to_numpy().astype(float)
    azi = readings.column("azi").to_numpy().astype(float)
    n = len(time)
    tie_in = np.flatnonzero((run == "in") & (station == options.tie_station))
    tie_out = np.flatnonzero((run == "out") & (station == options.tie_station))
    first = int(tie_in[0]) if len(tie_in) else None
    t0 = time[first] if first is not None else time[0]
    tau = (time - t0) / 3600.0
    mix = np.eye(n)
    span_h: float | None = None  # tie-in: the time between its two readings, h
    tie: tuple[int, ...] = ()  # tie-in: their rows
    if rate is None:
        if first is None or not len(tie_out) or tie_out[-1] <= first:
            raise ValueError(
                f"tie-in needs an in-run and a later out-run reading at station "
                f"{options.tie_station}; give a calibration or a drift_rate instead"
            )
        last = int(tie_out[-1])
        span_h, tie = float(tau[last]), (first, last)
        rate = DriftRate(
            rate=float(wrap(azi[last] - azi[first]) / span_h), sigma=0.0, source="tie_in"
        )
        mix[:, last] -= tau / span_h
        mix[:, first] += tau / span_h
    correction = rate.rate * tau
    if options.reference_azimuth is not None:
        if first is None:
            raise ValueError(
                f"a reference azimuth needs an in-run reading at the tie station "
                f"{options.tie_station}"
            )
        correction = correction + wrap(azi[first] - options.reference_azimuth)
        mix[:, first] -= 1.0
    corrected = azimuth360(azi - correction)
    pairs = _pairs(run, station)
    sigma_r = options.reading_sigma
    if sigma_r is None:
        sigma_r = _reading_sigma(corrected, mix, tau, pairs, tie)
    cov = sigma_r**2 * mix @ mix.T + rate.sigma**2 * np.outer(tau, tau)
    if span_h is not None:  # the rate's error is in ``mix``: the two tie-in readings'
        rate = rate.model_copy(update={"sigma": float(np.sqrt(2.0) * sigma_r / span_h)})
    north = (readings.schema.field("azi").metadata or {}).get(NORTH_KEY, b"true").decode()
    table = readings
    for name, values in (
        ("azi", corrected),
        ("azi_raw", azi),
        ("correction", correction),
        ("sigma_azi", np.sqrt(np.diag(cov))),
        ("drift_rate", np.full(n, rate.rate)),
        ("sigma_drift_rate", np.full(n, rate.sigma)),
    ):
        spec = next(c for c in CorrectedFreeGyroReadings.compiled().columns if c.name == name)
        field = spec.field(north)
        array = pa.array(values, type=pa.float64())
        if name in table.column_names:
            table = table.set_column(table.column_names.index(name), field, array)
        else:
            table = table.append_column(field, array)
    return CorrectedSurvey(
        readings=with_record(table, DRIFT_RATE_KEY, rate),
        stations=_stations(readings, corrected, cov, run, station, options, north),
        qc=_in_out(readings, corrected, cov, pairs, options, tau, tie, float(sigma_r)),
        rate=rate,
        reading_sigma=float(sigma_r),
    )


def correction_rate(time_s: FloatArray, correction_deg: FloatArray) -> float:
    """How fast the drift correction grows, °/h: the slope of the correction (°) against
    time (s) by least squares (NaN for fewer than two readings or no time span)."""
    time_h = np.asarray(time_s, dtype=float) / 3600.0
    if len(time_h) < 2 or not np.ptp(time_h) > 0:
        return float("nan")
    return float(np.polyfit(time_h, np.asarray(correction_deg, dtype=float), 1)[0])


def _pairs(run: np.ndarray, station: np.ndarray) -> np.ndarray:
    """(k, 2) row indices of the in-run and out-run readings of each station read twice."""
    rows_in = {int(s): i for i, s in enumerate(station) if run[i] == "in"}
    rows_out = {int(s): i for i, s in enumerate(station) if run[i] == "out"}
    both = sorted(set(rows_in) & set(rows_out))
    return np.array([[rows_in[s], rows_out[s]] for s in both], dtype=np.int64).reshape(-1, 2)


@lru_cache(maxsize=256)
def chi2_median_mean(n: int) -> float:
    """Expected sample median of ``n`` independent χ²₁ values: E[X₍ₘ₎] = ∫ x·f₍ₘ₎(x) dx by
    quadrature, f₍ₘ₎ = Beta(m, m)(F(x))·f(x) the density of the middle of 2m − 1 values; an
    even n's (the mean of its middle two) is that of n − 1, by the order-statistic
    recurrence. 1 for n ≤ 2; → 0.4549 (the median of χ²₁) as n grows."""
    from scipy import integrate  # imported on use: slow to import

    if n < 1:
        raise ValueError(f"the median of {n} values")
    m = (n + 1) // 2
    log_beta = 2 * math.lgamma(m) - math.lgamma(2 * m)

    def density(x: float) -> float:  # x·f₍ₘ₎(x), F(x) = erf(√(x/2)) for χ²₁
        below, above = math.erf(math.sqrt(x / 2)), math.erfc(math.sqrt(x / 2))
        if below <= 0.0 or above <= 0.0:
            return 0.0
        log_order = (m - 1) * (math.log(below) + math.log(above)) - log_beta
        return math.exp(log_order - x / 2) * math.sqrt(x / (2 * math.pi))

    return float(integrate.quad(density, 0.0, np.inf, limit=200, epsabs=1e-12)[0])


def _reading_sigma(
    corrected: FloatArray,
    mix: FloatArray,
    tau: FloatArray,
    pairs: np.ndarray,
    tie: tuple[int, ...],
) -> float:
    """Robust σ_r (deg) from the in/out differences, their rate line removed (module
    docstring); ``tie``: the tie-in's two rows, whose pairs are left out."""
    diff = wrap(corrected[pairs[:, 0]] - corrected[pairs[:, 1]])
    noise = mix[pairs[:, 0]] - mix[pairs[:, 1]]  # d_k's reading errors, apart from the rate
    gap = tau[pairs[:, 0]] - tau[pairs[:, 1]]
    rows = np.flatnonzero((np.sum(noise**2, axis=1) > 1e-12) & ~np.isin(pairs, tie).any(axis=1))
    ratio = _residuals(diff[rows], gap[rows], noise[rows])
    var = _median_variance(ratio)
    far = ratio > OUTLIER**2 * var
    if far.any():
        rows = rows[~far]
        var = _median_variance(_residuals(diff[rows], gap[rows], noise[rows]))
    return float(np.sqrt(var))


def _residuals(diff: FloatArray, gap: FloatArray, noise: FloatArray) -> FloatArray:
    """r_k²/g_k: the differences' squared residuals from their least-squares line through
    the origin in ``gap``, over their variance per unit σ_r² (NaN where that is 0)."""
    span = float(gap @ gap)
    if span > 0:
        diff = diff - gap * (gap @ diff) / span
        noise = noise - np.outer(gap, gap @ noise) / span
    gain = np.sum(noise**2, axis=1)
    out: FloatArray = np.where(gain > 1e-12, diff**2 / np.where(gain > 1e-12, gain, 1.0), np.nan)
    return out


def _median_variance(ratio: FloatArray) -> float:
    """σ_r² from r_k²/g_k: their median over that of as many χ²₁ values (NaNs left out)."""
    values = ratio[np.isfinite(ratio)]
    if len(values) < 2:
        raise ValueError(
            "fewer than two stations read on both runs (the tie-in aside): give reading_sigma"
        )
    return float(np.median(values)) / chi2_median_mean(len(values))


def _stations(
    readings: pa.Table,
    corrected: FloatArray,
    cov: FloatArray,
    run: np.ndarray,
    station: np.ndarray,
    options: CorrectionOptions,
    north: str,
) -> pa.Table:
    keep = (
        np.ones(len(run), dtype=bool)
        if options.stations_from == "mean"
        else (run == options.stations_from)
    )
    ids = np.unique(station[keep])
    weights = np.zeros((len(ids), len(run)))
    rows = np.searchsorted(ids, station[keep])
    weights[rows, np.flatnonzero(keep)] = 1.0
    count = weights.sum(axis=1)
    weights /= count[:, None]
    anchor = corrected[np.argmax(weights > 0, axis=1)]  # average around a station's reading
    offset = np.zeros(len(run))
    offset[keep] = wrap(corrected[keep] - anchor[rows])
    azi = azimuth360(anchor + weights @ offset)
    md = weights @ readings.column("md").to_numpy()
    inc = weights @ readings.column("inc").to_numpy()
    order = np.argsort(md, kind="stable")
    return DriftStations.compiled().make_table(
        {
            "md": md[order],
            "inc": inc[order],
            "azi": azi[order],
            "station": ids[order],
            "sigma_azi": np.sqrt(np.einsum("ij,jk,ik->i", weights, cov, weights))[order],
            "readings": count[order].astype(np.int64),
        },
        north_reference=north,
    )


def _in_out(
    readings: pa.Table,
    corrected: FloatArray,
    cov: FloatArray,
    pairs: np.ndarray,
    options: CorrectionOptions,
    tau: FloatArray,
    tie: tuple[int, ...],
    sigma_r: float,
) -> pa.Table:
    """The in/out QC of the stations read twice; the tie-in station's pair judged against
    ``azi_tolerance`` whatever its inclination and, when the rate is its own misclosure
    (``tie``: its two rows), compared as :func:`_tie_check` says (a tie-in it cannot check
    is left out)."""
    i, o = pairs[:, 0], pairs[:, 1]
    station = readings.column("station").to_numpy()[i]
    inc = readings.column("inc").to_numpy()
    azi_out = corrected[o]
    azi_diff = wrap(corrected[i] - corrected[o])
    sigma = np.sqrt(np.maximum(cov[i, i] + cov[o, o] - 2 * cov[i, o], 0.0))
    tie_in = station == options.tie_station
    keep = np.ones(len(i), dtype=bool)
    for k in np.flatnonzero(tie_in if tie else False):  # the rate is its own misclosure
        checked = _tie_check(corrected, cov, tau, pairs, tie, sigma_r, int(k))
        if checked is None:
            keep[k] = False
        else:
            azi_out[k], azi_diff[k], sigma[k] = checked
    inc_diff = inc[i] - inc[o]
    low = ((inc[i] + inc[o]) / 2 < options.low_inclination) & ~tie_in
    azi_tol = np.where(low, options.azi_tolerance_low, options.azi_tolerance)
    return InOutQc.compiled().make_table(
        {
            "station": station[keep],
            "md": readings.column("md").to_numpy()[i][keep],
            "inc_in": inc[i][keep],
            "inc_out": inc[o][keep],
            "inc_diff": inc_diff[keep],
            "azi_in": corrected[i][keep],
            "azi_out": azi_out[keep],
            "azi_diff": azi_diff[keep],
            "sigma_azi_diff": sigma[keep],
            "inc_tolerance": np.full(int(keep.sum()), options.inc_tolerance),
            "azi_tolerance": azi_tol[keep],
            "tie_in": tie_in[keep],
            "passed": ((np.abs(inc_diff) <= options.inc_tolerance) & (np.abs(azi_diff) <= azi_tol))[
                keep
            ],
        }
    )


def _tie_check(
    corrected: FloatArray,
    cov: FloatArray,
    tau: FloatArray,
    pairs: np.ndarray,
    tie: tuple[int, ...],
    sigma_r: float,
    k: int,
) -> tuple[float, float, float] | None:
    """The tie-in pair ``k`` (rows i, o) when the drift rate is its own misclosure, which
    makes its two corrected readings equal: its out-run reading corrected instead by the
    rate the other stations read twice show — ``azi_out``, ``azi_diff`` and σ of the
    difference (deg). That rate exceeds the one applied by b, the least-squares slope
    through the origin of the other pairs' corrected differences d_j in τ_in − τ_out (h);
    pairs beyond :data:`OUTLIER` σ of the line (σ of a difference: √2·σ_r) are left out and
    the line fitted again. Then ``azi_diff`` = d_k + b·(τ_o − τ_i): the tie-in error the
    rest of the survey sees (a good tie-in's is noise), its σ² = wᵀ·Cov·w for the weights
    w of that sum over the readings. None: no other pair has time between its readings."""
    i, o = pairs[:, 0], pairs[:, 1]
    diff = wrap(corrected[i] - corrected[o])
    gap = tau[i] - tau[o]
    rows = np.flatnonzero(~np.isin(pairs, tie).any(axis=1) & (gap != 0))
    for _ in range(2):  # the line, then the line of the pairs near it
        span = float(gap[rows] @ gap[rows])
        if not span > 0:
            return None
        slope = float(gap[rows] @ diff[rows]) / span
        near = np.abs(diff[rows] - slope * gap[rows]) <= OUTLIER * np.sqrt(2.0) * sigma_r
        if near.all():
            break
        rows = rows[near]
    lever = float(tau[o[k]] - tau[i[k]])
    weights = np.zeros(len(corrected))
    weights[i[k]] += 1.0
    weights[o[k]] -= 1.0
    np.add.at(weights, i[rows], lever * gap[rows] / span)
    np.add.at(weights, o[rows], -lever * gap[rows] / span)
    out = float(azimuth360(np.array(corrected[o[k]] - slope * lever)))
    sigma = float(np.sqrt(max(float(weights @ cov @ weights), 0.0)))
    return out, float(wrap(diff[k] + slope * lever)), sigma

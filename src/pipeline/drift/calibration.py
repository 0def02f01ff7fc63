"""Drift rate of a free gyro from its calibration series (seed 000, DOMAIN.md §4).

A calibration records series i = 1…I, one after another, each a sweep of set azimuths α_j.
Reading n (series i, set azimuth α_j, time t_n, s) has the azimuth error

    e_n = b_i + a_j + ω_w·(t_n − t_i) + ε_n,      ε_n ~ N(0, σ²)

with t_i the series' mid-time (mean time of its readings), b_i its level, a_j the
azimuth-dependent systematic error common to all series (Σ_j a_j = 0) and ω_w the drift
inside a series. The least-squares fit of this model (pseudo-inverse: when every series
sweeps the same azimuths in the same order, a_j and ω_w are confounded and only their sum is
fitted, which leaves the residuals unchanged) gives the residual variance σ̂² = RSS/(N − rank)
(``variance="pooled"``) or per series RSS_i/Σ(1 − h_nn) (``"series"``, h the leverages).

Series means, paper's ``M_i[ΔA]``, with the pattern removed: m_i = mean over the series of
(e_n − â_j) — the plain mean when all series sweep the same azimuths. Their covariance C
follows exactly from the linear operator m = L·e: C = L·diag(σ²_n)·Lᵀ (σ²/n_i on the
diagonal for complete series). Every estimate is a weighted sum w·m with σ² = wᵀCw:

- ``adjacent`` (paper's formula): ω(i−1, i) = (m_i − m_{i−1})/(t_i − t_{i−1}),
  σ² = (σ²_{m,i} + σ²_{m,i−1})/Δt²; ``pair``: the same for non-adjacent series;
- ``mean``: the average of the adjacent estimates (telescopes to the end series for equal
  spacing);
- ``grouped`` (I ≥ 4): first ⌊I/2⌋ series against the last ⌊I/2⌋ merged into two big
  series (1+2 vs 3+4), readings-weighted means and mid-times;
- ``fit``: the generalised least-squares slope of m_i against t_i — the minimum-variance
  linear estimate;
- ``traditional``: the regulated method, two readings of one set azimuth ~30 min apart,
  σ² = (σ²_p + σ²_q)/Δt².

``gain`` = σ of the traditional method over ``control_interval`` / σ of the estimate; the
paper's claimed gain √(n(n−1)/2) is reported beside it. At equal time separation a
difference of two series means beats two single readings by √n only, so the claim
overstates the gain by √((n−1)/2) (2.4 for n = 13); real gains come also from the longer
interval the series span.

Linearity: χ² = rᵀC⁻¹r of the series means about their GLS line (equivalently, of the
adjacent drifts about their common value), I − 2 degrees of freedom. With the pooled σ̂ the
statistic χ²/(I − 2) is F(I − 2, N − rank) distributed under linear drift (exact test);
with per-series σ̂ it is referred to χ²(I − 2). p < ``alpha`` (default 0.01) gives the
verdict "non-linear: instrument unfit or needs a non-linear drift model".

Rates are computed in deg/s and reported in °/min and °/h.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from pipeline.drift.tables import CalibrationResult, CalibrationSeries
from pipeline.well import SurveyDate

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

LINEAR = "linear"
NON_LINEAR = "non-linear: instrument unfit or needs a non-linear drift model"
UNTESTED = "untested: fewer than 3 series"
UNKNOWN_INSTRUMENT = "unknown"
LEVEL_DECIMALS = 6
"""Set azimuths equal to this many decimals are the same stand position."""


class CalibrationOptions(BaseModel):
    """Parameters of drift calibration."""

    model_config = ConfigDict(extra="forbid")
    instrument: str | None = Field(
        None, description="serial of rows without one (default: the well's tool_serial)"
    )
    alpha: float = Field(0.01, gt=0, lt=1, description="significance of the linearity test")
    variance: Literal["pooled", "series"] = Field(
        "pooled", description="reading σ pooled over all series, or per series (paper)"
    )
    control_interval: float = Field(
        1800.0, gt=0, description="interval of the traditional two-reading method, s"
    )
    use: Literal["fit", "mean", "grouped"] = Field(
        "fit", description="estimate marked `selected` (grouped needs ≥ 4 series, else fit)"
    )
    date: SurveyDate = Field(
        None,
        description="day the calibration was recorded (default: the survey_date the "
        "calibration readings' header states)",
    )


@dataclass(frozen=True)
class SeriesMeans:
    """Series in time order: ids, readings, mid-times (s), pattern-free mean errors (deg),
    their covariance (deg²), residual scatter per series (deg) and per-reading variances."""

    ids: IntArray
    count: IntArray
    mid_time: FloatArray
    mean: FloatArray
    cov: FloatArray
    residual_std: FloatArray
    reading_var: FloatArray
    dof: int


@dataclass(frozen=True)
class Estimate:
    """One drift estimate: rate and σ in deg/s over ``interval`` s."""

    method: str
    label: str
    rate: float
    sigma: float
    interval: float


@dataclass(frozen=True)
class Linearity:
    """The linearity test of the series means."""

    chi2: float
    dof: int
    p_value: float
    verdict: str


@dataclass(frozen=True)
class Calibration:
    """Everything calibration found for one instrument."""

    series: SeriesMeans
    estimates: list[Estimate]
    linearity: Linearity
    reading_sigma: float
    reference_sigma: float
    """σ of the traditional method over the control interval, deg/s."""
    gain_claimed: float
    selected: str


def wrap(angle: FloatArray) -> FloatArray:
    """Angles (deg) wrapped to [−180, 180)."""
    wrapped: FloatArray = (np.asarray(angle, dtype=float) + 180.0) % 360.0 - 180.0
    return wrapped


def series_means(
    series: NDArray[np.int64],
    set_azimuth: FloatArray,
    error: FloatArray,
    time: FloatArray,
    variance: Literal["pooled", "series"] = "pooled",
) -> SeriesMeans:
    """Fit the calibration model (module docstring) and return the series means."""
    ids, index = np.unique(series, return_inverse=True)
    n_series, n = len(ids), len(error)
    count = np.bincount(index, minlength=n_series)
    mid = np.bincount(index, weights=time, minlength=n_series) / count
    order = np.argsort(mid, kind="stable")
    rank_of = np.empty(n_series, dtype=np.int64)
    rank_of[order] = np.arange(n_series)
    index, ids, count, mid = rank_of[index], ids[order], count[order], mid[order]

    _, level = np.unique(np.round(set_azimuth, LEVEL_DECIMALS), return_inverse=True)
    n_levels = int(level.max()) + 1
    member = np.zeros((n, n_series))
    member[np.arange(n), index] = 1.0
    pattern = np.zeros((n, n_levels - 1))  # sum-to-zero coding of a_j
    last = level == n_levels - 1
    pattern[~last, level[~last]] = 1.0
    pattern[last] = -1.0
    within = time - mid[index]
    scale = float(np.abs(within).max()) or 1.0
    design = np.hstack([member, pattern, (within / scale)[:, None]])

    pinv = np.linalg.pinv(design, rcond=1e-10)
    rank = int(np.linalg.matrix_rank(design))
    dof = n - rank
    if dof < 1:
        raise ValueError(
            f"{n} readings in {n_series} series over {n_levels} set azimuths leave no degrees "
            "of freedom to estimate the reading scatter"
        )
    hat = design @ pinv
    resid = error - hat @ error
    rss = np.bincount(index, weights=resid**2, minlength=n_series)
    free = np.bincount(index, weights=1.0 - np.diag(hat), minlength=n_series)
    if variance == "pooled":
        reading_var = np.full(n, rss.sum() / dof)
        residual_std = np.full(n_series, np.sqrt(rss.sum() / dof))
    else:
        if np.any(free < 0.5):
            raise ValueError("a series is too short for its own variance: use variance=pooled")
        residual_std = np.sqrt(rss / free)
        reading_var = residual_std[index] ** 2
    without_pattern = np.eye(n) - pattern @ pinv[n_series : n_series + n_levels - 1]
    operator = (member.T / count[:, None]) @ without_pattern
    return SeriesMeans(
        ids=ids,
        count=count,
        mid_time=mid,
        mean=operator @ error,
        cov=(operator * reading_var) @ operator.T,
        residual_std=residual_std,
        reading_var=reading_var,
        dof=dof,
    )


def calibrate_series(
    series: NDArray[np.int64],
    set_azimuth: FloatArray,
    error: FloatArray,
    time: FloatArray,
    options: CalibrationOptions,
) -> Calibration:
    """All drift estimates and the linearity verdict of one instrument's readings
    (errors in deg, times in s)."""
    if len(np.unique(series)) < 2:
        raise ValueError("drift calibration needs at least two series")
    means = series_means(series, set_azimuth, error, time, options.variance)
    estimates = _series_estimates(means)
    traditional = _traditional(set_azimuth, error, time, means.reading_var, options)
    if traditional is not None:
        estimates.append(traditional)
    selected = "fit" if options.use == "grouped" and len(means.ids) < 4 else options.use
    n_per_series = len(error) / len(means.ids)
    return Calibration(
        series=means,
        estimates=estimates,
        linearity=_linearity(means, options),
        reading_sigma=float(np.sqrt(means.reading_var.mean())),
        reference_sigma=float(np.sqrt(2.0 * means.reading_var.mean()) / options.control_interval),
        gain_claimed=float(np.sqrt(n_per_series * (n_per_series - 1) / 2)),
        selected=selected,
    )


def _series_estimates(means: SeriesMeans) -> list[Estimate]:
    ids, t, n_series = means.ids, means.mid_time, len(means.ids)
    out: list[Estimate] = []

    def add(method: str, label: str, weights: FloatArray, interval: float) -> None:
        sigma = float(np.sqrt(weights @ means.cov @ weights))
        out.append(Estimate(method, label, float(weights @ means.mean), sigma, interval))

    def pair(i: int, k: int) -> FloatArray:
        w = np.zeros(n_series)
        w[k], w[i] = 1.0, -1.0
        weights: FloatArray = w / (t[k] - t[i])
        return weights

    for i in range(n_series):
        for k in range(i + 1, n_series):
            method = "adjacent" if k == i + 1 else "pair"
            add(method, f"{ids[i]}-{ids[k]}", pair(i, k), float(t[k] - t[i]))
    span = f"{ids[0]}…{ids[-1]}"
    total = float(t[-1] - t[0])
    if n_series > 2:
        mean_w = np.mean([pair(i, i + 1) for i in range(n_series - 1)], axis=0)
        add("mean", span, mean_w, total)
    if n_series >= 4:
        half = n_series // 2
        first, second = np.arange(half), np.arange(n_series - half, n_series)
        w_a = np.zeros(n_series)
        w_b = np.zeros(n_series)
        w_a[first] = means.count[first] / means.count[first].sum()
        w_b[second] = means.count[second] / means.count[second].sum()
        interval = float(w_b @ t - w_a @ t)
        label = "+".join(map(str, ids[first])) + " vs " + "+".join(map(str, ids[second]))
        add("grouped", label, (w_b - w_a) / interval, interval)
    add("fit", span, _gls_operator(means)[1], total)
    return out


def _gls_operator(means: SeriesMeans) -> FloatArray:
    """Rows: weights giving the GLS intercept and slope of the means against mid-time."""
    design = np.stack([np.ones_like(means.mid_time), means.mid_time - means.mid_time[0]], axis=1)
    weight = np.linalg.inv(means.cov)
    operator: FloatArray = np.linalg.solve(design.T @ weight @ design, design.T @ weight)
    return operator


def _linearity(means: SeriesMeans, options: CalibrationOptions) -> Linearity:
    dof = len(means.ids) - 2
    if dof < 1:
        return Linearity(float("nan"), 0, float("nan"), UNTESTED)
    from scipy import stats  # imported on use: scipy.stats takes a second to import

    design = np.stack([np.ones_like(means.mid_time), means.mid_time - means.mid_time[0]], axis=1)
    resid = means.mean - design @ (_gls_operator(means) @ means.mean)
    chi2 = float(resid @ np.linalg.solve(means.cov, resid))
    if options.variance == "pooled":
        p_value = float(stats.f.sf(chi2 / dof, dof, means.dof))
    else:
        p_value = float(stats.chi2.sf(chi2, dof))
    return Linearity(chi2, dof, p_value, NON_LINEAR if p_value < options.alpha else LINEAR)


def _traditional(
    set_azimuth: FloatArray,
    error: FloatArray,
    time: FloatArray,
    reading_var: FloatArray,
    options: CalibrationOptions,
) -> Estimate | None:
    """Two readings of the first reading's set azimuth, as close to ``control_interval``
    apart as the calibration allows (None if that azimuth is never read again)."""
    first = int(np.argmin(time))
    same = np.round(set_azimuth % 360.0, LEVEL_DECIMALS) == round(
        float(set_azimuth[first]) % 360.0, LEVEL_DECIMALS
    )
    later = np.flatnonzero(same & (time > time[first]))
    if len(later) == 0:
        return None
    second = int(later[np.argmin(np.abs(time[later] - time[first] - options.control_interval))])
    interval = float(time[second] - time[first])
    return Estimate(
        "traditional",
        f"readings at {set_azimuth[first]:g}° t={time[first]:g} s and t={time[second]:g} s",
        float((error[second] - error[first]) / interval),
        float(np.sqrt(reading_var[first] + reading_var[second]) / interval),
        interval,
    )


def reading_errors(readings: pa.Table) -> FloatArray:
    """Azimuth errors (deg) of calibration readings: ``azimuth_error`` where given, else
    measured − set wrapped to ±180°."""
    names = readings.column_names
    error = np.full(readings.num_rows, np.nan)
    if "azimuth_error" in names:
        error = readings.column("azimuth_error").to_numpy(zero_copy_only=False).astype(float)
    if "measured_azimuth" in names:
        measured = readings.column("measured_azimuth").to_numpy(zero_copy_only=False)
        set_azimuth = readings.column("set_azimuth").to_numpy()
        error = np.where(np.isnan(error), wrap(measured.astype(float) - set_azimuth), error)
    if np.isnan(error).any():
        row = int(np.flatnonzero(np.isnan(error))[0])
        raise ValueError(f"row {row}: give azimuth_error or measured_azimuth for every reading")
    return error


def reading_times(readings: pa.Table, series: NDArray[np.int64]) -> FloatArray:
    """Times (s) of calibration readings: ``time`` where given, else spread evenly over the
    reading's series from ``series_start`` to ``series_end`` in row order."""
    names = readings.column_names
    time = np.full(readings.num_rows, np.nan)
    if "time" in names:
        time = readings.column("time").to_numpy(zero_copy_only=False).astype(float)
    missing = np.isnan(time)
    if missing.any() and {"series_start", "series_end"} <= set(names):
        start = readings.column("series_start").to_numpy(zero_copy_only=False).astype(float)
        end = readings.column("series_end").to_numpy(zero_copy_only=False).astype(float)
        for value in np.unique(series[missing]):
            rows = np.flatnonzero(series == value)
            slot = (np.arange(len(rows)) + 0.5) / len(rows)
            spread = start[rows] + slot * (end[rows] - start[rows])
            time[rows] = np.where(np.isnan(time[rows]), spread, time[rows])
    if np.isnan(time).any():
        row = int(np.flatnonzero(np.isnan(time))[0])
        raise ValueError(f"row {row}: give time, or series_start and series_end, for every reading")
    return time


def calibrate(
    readings: pa.Table,
    options: CalibrationOptions,
    tool_serial: str | None = None,
    date: dt.date | None = None,
) -> tuple[pa.Table, pa.Table]:
    """:class:`CalibrationResult` and :class:`CalibrationSeries` tables of every instrument
    in a :class:`CalibrationReadings` table (rows without a serial: ``options.instrument``,
    else ``tool_serial``, else "unknown"), recorded on ``options.date``, else ``date``."""
    if readings.num_rows == 0:
        raise ValueError("no calibration readings")
    fallback = options.instrument or tool_serial or UNKNOWN_INSTRUMENT
    if "instrument" in readings.column_names:
        raw = readings.column("instrument").to_pylist()
        instrument = np.array([fallback if s is None else s for s in raw], dtype=object)
    else:
        instrument = np.full(readings.num_rows, fallback, dtype=object)
    series = readings.column("series").to_numpy().astype(np.int64)
    set_azimuth = readings.column("set_azimuth").to_numpy().astype(float)
    error = reading_errors(readings)
    time = reading_times(readings, series)
    heat = np.full(readings.num_rows, np.nan)  # °C, NaN where not stated
    if "temperature" in readings.column_names:
        heat = readings.column("temperature").to_numpy(zero_copy_only=False).astype(float)
    results: list[dict[str, list[object]]] = []
    series_rows: list[dict[str, list[object]]] = []
    for name in dict.fromkeys(instrument):
        rows = instrument == name
        try:
            cal = calibrate_series(
                series[rows], set_azimuth[rows], error[rows], time[rows], options
            )
        except ValueError as exc:
            raise ValueError(f"instrument {name}: {exc}") from None
        span = float(np.ptp(time[rows]))
        results.append(_result_columns(str(name), cal, options.date or date, span, heat[rows]))
        series_rows.append(_series_columns(str(name), cal.series))
    return (
        CalibrationResult.compiled().make_table(_concat(results)),
        CalibrationSeries.compiled().make_table(_concat(series_rows)),
    )


def _result_columns(
    instrument: str, cal: Calibration, date: dt.date | None, span: float, heat: FloatArray
) -> dict[str, list[object]]:
    """The result rows of one instrument: its estimates, recorded on ``date``, from readings
    ``span`` s long at temperatures ``heat`` (°C, NaN: not stated)."""
    est, lin = cal.estimates, cal.linearity
    count = len(est)
    stated = heat[np.isfinite(heat)]
    low, high = (float(stated.min()), float(stated.max())) if len(stated) else (None, None)
    return {
        "instrument": [instrument] * count,
        "method": [e.method for e in est],
        "label": [e.label for e in est],
        "drift_deg_min": [e.rate * 60.0 for e in est],
        "drift_deg_h": [e.rate * 3600.0 for e in est],
        "sigma_deg_min": [e.sigma * 60.0 for e in est],
        "sigma_deg_h": [e.sigma * 3600.0 for e in est],
        "interval": [e.interval for e in est],
        "gain": [cal.reference_sigma / e.sigma if e.sigma > 0 else float("inf") for e in est],
        "gain_claimed": [cal.gain_claimed] * count,
        "reading_sigma": [cal.reading_sigma] * count,
        "selected": [e.method == cal.selected for e in est],
        "chi2": [lin.chi2] * count,
        "dof": [lin.dof] * count,
        "p_value": [lin.p_value] * count,
        "verdict": [lin.verdict] * count,
        "calibration_date": [date.isoformat() if date else None] * count,
        "time_span": [span] * count,
        "temperature_min": [low] * count,
        "temperature_max": [high] * count,
    }


def _series_columns(instrument: str, means: SeriesMeans) -> dict[str, list[object]]:
    return {
        "instrument": [instrument] * len(means.ids),
        "series": means.ids.tolist(),
        "readings": means.count.tolist(),
        "mid_time": means.mid_time.tolist(),
        "mean_error": means.mean.tolist(),
        "sigma_mean": np.sqrt(np.diag(means.cov)).tolist(),
        "residual_std": means.residual_std.tolist(),
    }


def _concat(parts: list[dict[str, list[object]]]) -> dict[str, list[object]]:
    return {key: [v for part in parts for v in part[key]] for key in parts[0]}

"""Allan-variance noise analysis of static records and the compassing dwell it implies.

Overlapping Allan deviations σ(τ) per axis at octave averaging times (allantools ``oadev``,
``taus="octave"``). Noise terms follow IEEE Std 952 (Annex C): the Allan variance is fitted
as a sum of the terms' curves, ``σ²(τ) = N²/τ + bias(τ) + K²·τ/3``, by non-negative weighted
least squares (each point weighted by its equivalent number of clusters, iterated with the
model's own variance), so every term is read where it dominates:

- ARW (VRW for accelerometers): N = the −1/2 slope line's value at τ = 1 s, in the sensor's
  rate unit; reported as N/60 deg/√h for gyros (σ in deg/h) and 60·N (m/s)/√h for
  accelerometers (σ in m/s²), the conventions of :mod:`pipeline.sim.sensors`;
- bias instability, ``bias_model="flicker"``: the flat floor F of a flicker bias,
  B = F/0.664 (F = B·√(2 ln 2/π)); ``"gauss_markov"``: a first-order Gauss–Markov bias of σ_b
  and correlation time T, ``σ²(τ) = σ_b²·(T/τ)²·(2τ/T − 3 + 4e^{−τ/T} − e^{−2τ/T})`` — a bump
  peaking at 0.617·σ_b near τ = 1.89·T, not a floor (the simulator's bias model); its σ_b is
  reported;
- RRW: K = the +1/2 slope line's value at τ = 3 s, reported per √h (60·K).

Dwell: a frame position averaged for τ s has a rate error of about σ(τ) (the fitted curve);
with the frame positions at equal steps the (h, r) covariance of the least squares
(:func:`~pipeline.gyrocompass.precision.hr_covariance`) is σ(τ)² times a fixed matrix, and
:func:`~pipeline.gyrocompass.azimuth.cramer_rao` gives the azimuth σ, taken at the worst azimuth
and starting toolface. Accelerometer noise over the whole station adds its inclination
error's leak into azimuth, ∂A/∂I = −sin A (cos A tan I − tan φ). The recommended dwell is the
shortest on a fine grid meeting the target; when none does, the one with the smallest σ.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.drift.calibration import FloatArray
from pipeline.drift.tables import AllanResult, DwellRecommendation, NoiseParameters
from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.gyrocompass.azimuth import cramer_rao
from pipeline.gyrocompass.positions import DEFAULT_POSITIONS
from pipeline.gyrocompass.precision import hr_covariance

FLICKER_FLOOR = float(np.sqrt(2.0 * np.log(2.0) / np.pi))
"""Allan deviation of a flicker bias of instability B, per unit B (0.664)."""
IRLS_ITERATIONS = 6
GM_GRID = 24
AZIMUTHS = np.radians(np.arange(0.0, 360.0, 5.0))
TOOLFACES = np.radians(np.arange(0.0, 360.0, 10.0))
DWELL_GRID = 400
SERIES_BELOW = 1e-3
"""τ/T below which the Gauss–Markov Allan variance is evaluated by its Taylor series."""

GYRO_AXES = ("gyro_x", "gyro_y", "gyro_z")
ACC_AXES = ("acc_x", "acc_y", "acc_z")
UNIFORM_RTOL = 1e-3
"""Largest relative deviation of a sample interval from the median one."""

BiasModel = Literal["flicker", "gauss_markov"]


class AllanOptions(BaseModel):
    """Parameters of the Allan analysis and dwell recommendation (angles deg, times s)."""

    model_config = ConfigDict(extra="forbid")
    start: float | None = Field(None, description="first sample time of the window, s")
    end: float | None = Field(None, description="last sample time of the window, s")
    station: int | None = Field(None, ge=0, description="use only this station's samples")
    bias_model: BiasModel = Field(
        "flicker", description="flicker (IEEE 952 flat floor) or gauss_markov (bump)"
    )
    inclination: float = Field(45.0, ge=0, le=180, description="design inclination, deg")
    target_sigma_azi: float = Field(1.0, gt=0, description="wanted azimuth σ, deg")
    positions: list[float] = Field(
        default_factory=lambda: list(DEFAULT_POSITIONS),
        min_length=4,
        description="frame angles of the positions of a station, deg",
    )
    move_time: float = Field(3.0, ge=0, description="duration of each frame move, s")
    max_dwell: float = Field(600.0, gt=1, description="longest dwell considered, s")


@dataclass(frozen=True)
class AllanCurve:
    """Allan deviation ``adev`` (sensor units) at averaging times ``tau`` (s); ``clusters``
    overlapping differences each, from ``samples`` samples."""

    tau: FloatArray
    adev: FloatArray
    clusters: FloatArray
    samples: int


@dataclass(frozen=True)
class NoiseFit:
    """Fitted noise terms in the sensor's unit u (deg/h or m/s²): ``white`` = σ of the
    −1/2 line at 1 s (u), ``bias`` = B or σ_b (u), ``walk`` = σ of the +1/2 line at 3 s
    (u), ``correlation_time`` (s, Gauss–Markov only), ``rms`` relative misfit."""

    white: float
    bias: float
    walk: float
    model: BiasModel
    correlation_time: float | None
    rms: float

    def adev(self, tau: FloatArray | float) -> FloatArray:
        """The fitted Allan deviation at ``tau`` s."""
        t = np.asarray(tau, dtype=float)
        if self.model == "flicker":
            bias = (FLICKER_FLOOR * self.bias) ** 2 * np.ones_like(t)
        else:
            assert self.correlation_time is not None
            bias = self.bias**2 * gauss_markov_avar(t, self.correlation_time)
        out: FloatArray = np.sqrt(self.white**2 / t + bias + self.walk**2 * t / 3.0)
        return out


def allan_deviation(values: FloatArray, rate: float) -> AllanCurve:
    """Overlapping Allan deviation of uniformly sampled ``values`` at ``rate`` Hz."""
    import allantools  # imported on use: it loads scipy.stats and scipy.signal (seconds)

    tau, adev, _, clusters = allantools.oadev(
        np.asarray(values, dtype=float), rate=rate, data_type="freq", taus="octave"
    )
    keep = np.isfinite(adev) & (clusters > 0)
    return AllanCurve(
        np.asarray(tau[keep], dtype=float),
        np.asarray(adev[keep], dtype=float),
        np.asarray(clusters[keep], dtype=float),
        len(values),
    )


def gauss_markov_avar(tau: FloatArray, correlation_time: float) -> FloatArray:
    """Allan variance of a unit-variance first-order Gauss–Markov process."""
    x = np.asarray(tau, dtype=float) / correlation_time
    small = np.minimum(x, SERIES_BELOW)  # series where the closed form cancels
    series = 2 / 3 * small - small**2 / 2 + 7 / 30 * small**3
    closed = (2 * x + 4 * np.expm1(-x) - np.expm1(-2 * x)) / x**2
    out: FloatArray = np.where(x < SERIES_BELOW, series, closed)
    return out


def fit_noise(curve: AllanCurve, bias_model: BiasModel = "flicker") -> NoiseFit:
    """Noise terms of one axis from its Allan curve (module docstring)."""
    if len(curve.tau) < 3:
        raise ValueError(f"{len(curve.tau)} averaging times are too few to fit noise terms")
    avar = curve.adev**2
    edf = np.maximum(curve.samples * curve.tau[0] / curve.tau, 1.0)  # ~ independent clusters
    from scipy.optimize import nnls  # imported on use: slow to import

    def solve(middle: FloatArray) -> tuple[FloatArray, float]:
        basis = np.stack([1.0 / curve.tau, middle, curve.tau / 3.0], axis=1)
        model = avar
        for _ in range(IRLS_ITERATIONS):
            weight = np.sqrt(edf) / np.maximum(model, 1e-300)
            coef, _ = nnls(basis * weight[:, None], avar * weight)
            model = np.maximum(basis @ coef, 1e-300)
        misfit = float(np.sqrt(np.mean(edf * (avar / model - 1.0) ** 2)))
        return coef, misfit

    if bias_model == "flicker":
        coef, _ = solve(np.ones_like(curve.tau))
        return NoiseFit(
            white=float(np.sqrt(coef[0])),
            bias=float(np.sqrt(coef[1]) / FLICKER_FLOOR),
            walk=float(np.sqrt(coef[2])),
            model="flicker",
            correlation_time=None,
            rms=_relative_rms(curve, coef, np.ones_like(curve.tau)),
        )
    return _fit_gauss_markov(curve, solve)


def _relative_rms(curve: AllanCurve, coef: FloatArray, middle: FloatArray) -> float:
    model = coef[0] / curve.tau + coef[1] * middle + coef[2] * curve.tau / 3.0
    return float(np.sqrt(np.mean((curve.adev / np.sqrt(np.maximum(model, 1e-300)) - 1.0) ** 2)))


def _fit_gauss_markov(
    curve: AllanCurve, solve: Callable[[FloatArray], tuple[FloatArray, float]]
) -> NoiseFit:
    """Best correlation time on a log grid over the curve's τ range, then refined."""
    from scipy.optimize import minimize_scalar  # imported on use: slow to import

    lo, hi = np.log(curve.tau[0]), np.log(curve.tau[-1] / 2.0)

    def misfit(log_t: float) -> float:
        return solve(gauss_markov_avar(curve.tau, float(np.exp(log_t))))[1]

    grid = np.linspace(lo, hi, GM_GRID)
    best = int(np.argmin([misfit(x) for x in grid]))
    step = grid[1] - grid[0]
    found = minimize_scalar(
        misfit,
        bounds=(max(lo, grid[best] - step), min(hi, grid[best] + step)),
        method="bounded",
        options={"xatol": 1e-4},
    )
    corr = float(np.exp(found.x))
    middle = gauss_markov_avar(curve.tau, corr)
    coef, _ = solve(middle)
    return NoiseFit(
        white=float(np.sqrt(coef[0])),
        bias=float(np.sqrt(coef[1])),
        walk=float(np.sqrt(coef[2])),
        model="gauss_markov",
        correlation_time=corr,
        rms=_relative_rms(curve, coef, middle),
    )


@dataclass(frozen=True)
class Dwell:
    """Recommended dwell per position and what it gives (s, deg, deg/h)."""

    dwell: float
    station_time: float
    sigma_rate: float
    sigma_azi: float
    achievable: bool
    best_dwell: float
    best_sigma_azi: float


def azimuth_sigma(
    gyro: NoiseFit,
    dwell: FloatArray,
    latitude: float,
    inclination: float,
    positions: Sequence[float],
    accelerometer: NoiseFit | None = None,
) -> FloatArray:
    """Worst-case azimuth σ (deg) of a station for each ``dwell`` (s) per position
    (latitude, inclination and positions in deg; module docstring)."""
    lat, inc = np.radians(latitude), np.radians(inclination)
    theta = np.radians(np.asarray(positions, dtype=float))
    times = np.arange(len(theta), dtype=float)  # equal steps; their length does not matter
    unit = np.stack([hr_covariance(theta + off, times, 1.0) for off in TOOLFACES])
    per_azimuth = np.max(
        [
            cramer_rao(
                AZIMUTHS,
                np.full_like(AZIMUTHS, inc),
                lat,
                np.broadcast_to(c, (len(AZIMUTHS), 2, 2)),
            )
            for c in unit
        ],
        axis=0,
    )  # rad per (deg/h) of per-position σ
    dwell = np.asarray(dwell, dtype=float)
    gyro_part = np.outer(gyro.adev(dwell), per_azimuth)
    total = gyro_part
    if accelerometer is not None:
        sigma_inc = accelerometer.adev(len(theta) * dwell) / STANDARD_GRAVITY
        leak = np.abs(np.sin(AZIMUTHS) * (np.cos(AZIMUTHS) * np.tan(inc) - np.tan(lat)))
        total = np.hypot(gyro_part, np.outer(sigma_inc, leak))
    out: FloatArray = np.degrees(total.max(axis=1))
    return out


def recommend_dwell(
    gyro: NoiseFit,
    target: float,
    latitude: float,
    inclination: float,
    positions: Sequence[float],
    move_time: float,
    max_dwell: float,
    min_dwell: float = 1.0,
    accelerometer: NoiseFit | None = None,
) -> Dwell:
    """The shortest dwell per position (s) giving azimuth σ ≤ ``target`` (deg)."""
    grid = np.geomspace(min_dwell, max_dwell, DWELL_GRID)
    sigma = azimuth_sigma(gyro, grid, latitude, inclination, positions, accelerometer)
    meets = np.flatnonzero(sigma <= target)
    best = int(np.argmin(sigma))
    pick = int(meets[0]) if len(meets) else best
    dwell = float(grid[pick])
    return Dwell(
        dwell=dwell,
        station_time=len(positions) * dwell + (len(positions) - 1) * move_time,
        sigma_rate=float(gyro.adev(dwell)),
        sigma_azi=float(sigma[pick]),
        achievable=bool(len(meets)),
        best_dwell=float(grid[best]),
        best_sigma_azi=float(sigma[best]),
    )


def analyse_static(
    samples: pa.Table, options: AllanOptions, latitude: float
) -> tuple[pa.Table, pa.Table, pa.Table]:
    """:class:`AllanResult`, :class:`NoiseParameters` and :class:`DwellRecommendation` of a
    static record (:class:`~pipeline.tables.RawSamples` at rest, or the chosen window)."""
    time = samples.column("time").to_numpy()
    keep = np.ones(len(time), dtype=bool)
    if options.start is not None:
        keep &= time >= options.start
    if options.end is not None:
        keep &= time <= options.end
    if options.station is not None:
        if "station" not in samples.column_names:
            raise ValueError("the samples have no station column to select from")
        keep &= samples.column("station").to_numpy(zero_copy_only=False) == options.station
    rows = np.flatnonzero(keep)
    if len(rows) < 8:
        raise ValueError(f"{len(rows)} samples in the window: too few for an Allan analysis")
    rate = _sample_rate(time[rows])
    axes = [
        a
        for a in GYRO_AXES + ACC_AXES
        if a in samples.column_names and samples.column(a).null_count == 0
    ]
    curves = {a: allan_deviation(samples.column(a).to_numpy()[rows], rate) for a in axes}
    fits = {a: fit_noise(curves[a], options.bias_model) for a in axes}
    first = curves[axes[0]]
    allan = AllanResult.compiled().make_table(
        {"tau": first.tau, "clusters": first.clusters.astype(np.int64)}
        | {a: curves[a].adev for a in axes}
    )
    gyros = [a for a in axes if a in GYRO_AXES]
    accels = [fits[a] for a in ("acc_x", "acc_y") if a in fits]
    accel = max(accels, key=lambda f: float(f.adev(100.0))) if accels else None
    dwells = {
        a: recommend_dwell(
            fits[a],
            options.target_sigma_azi,
            latitude,
            options.inclination,
            options.positions,
            options.move_time,
            options.max_dwell,
            min_dwell=float(first.tau[0]),
            accelerometer=accel,
        )
        for a in gyros
    }
    worst = max(gyros, key=lambda a: (dwells[a].dwell, dwells[a].sigma_azi))
    return allan, _noise_table(curves, fits), _dwell_table(worst, dwells[worst], latitude, options)


def _sample_rate(time: FloatArray) -> float:
    steps = np.diff(time)
    dt = float(np.median(steps))
    if not dt > 0 or np.max(np.abs(steps - dt)) > UNIFORM_RTOL * dt:
        worst = int(np.argmax(np.abs(steps - dt)))
        raise ValueError(
            f"the record must be uniformly sampled without gaps: interval {dt:g} s, but the "
            f"step after t = {time[worst]:g} s is {steps[worst]:g} s"
        )
    return 1.0 / dt


def _noise_table(curves: dict[str, AllanCurve], fits: dict[str, NoiseFit]) -> pa.Table:
    gyro = {a: a in GYRO_AXES for a in fits}
    lowest = {a: int(np.argmin(c.adev)) for a, c in curves.items()}
    return NoiseParameters.compiled().make_table(
        {
            "axis": list(fits),
            "arw": [f.white / 60.0 if gyro[a] else f.white * 60.0 for a, f in fits.items()],
            "arw_unit": ["deg/sqrt(h)" if gyro[a] else "m/s/sqrt(h)" for a in fits],
            "bias_instability": [f.bias for f in fits.values()],
            "bias_instability_unit": ["deg/h" if gyro[a] else "m/s2" for a in fits],
            "rrw": [f.walk * 60.0 for f in fits.values()],
            "rrw_unit": ["deg/h/sqrt(h)" if gyro[a] else "m/s2/sqrt(h)" for a in fits],
            "bias_model": [f.model for f in fits.values()],
            "correlation_time": [f.correlation_time for f in fits.values()],
            "adev_min": [float(curves[a].adev[lowest[a]]) for a in fits],
            "tau_min": [float(curves[a].tau[lowest[a]]) for a in fits],
            "fit_rms": [f.rms for f in fits.values()],
        }
    )


def _dwell_table(axis: str, dwell: Dwell, latitude: float, options: AllanOptions) -> pa.Table:
    return DwellRecommendation.compiled().make_table(
        {
            "axis": [axis],
            "latitude": [latitude],
            "inclination": [options.inclination],
            "positions": [len(options.positions)],
            "target_sigma_azi": [options.target_sigma_azi],
            "dwell": [dwell.dwell],
            "station_time": [dwell.station_time],
            "sigma_rate": [dwell.sigma_rate],
            "sigma_azi": [dwell.sigma_azi],
            "achievable": [dwell.achievable],
            "best_dwell": [dwell.best_dwell],
            "best_sigma_azi": [dwell.best_sigma_azi],
        }
    )

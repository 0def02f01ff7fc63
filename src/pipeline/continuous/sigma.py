"""Predicted errors of continuous-mode azimuth and inclination (DOMAIN.md §6).

Azimuth. The moving run integrates ``Ȧ = (Ω cos φ cos A cos I + Ω sin φ sin I − h)/sin I``
from the tie stop, with ``h = (y − r sin δ)/cos δ`` from the gyro reading y at misalignment δ
from the high side. To first order the azimuth error e obeys

    ė = F(t)·e + ∂Ȧ/∂I·ε_I − ε_y/(sin I cos δ)
    F = ∂Ȧ/∂A = −Ω cos φ (sin A cos I + cos A tan δ)/sin I

so, with Φ(t) = exp ∫F (the heading feedback, ≈ 1 on short runs),
``e(t) = Φ(t)·e₀ + Φ(t) ∫₀ᵗ (∂Ȧ/∂I·ε_I − ε_y/(sin I cos δ))/Φ ds``. The closure on the end stop
removes the misclosure ``e(T) − e_end`` linearly in time, ``w = (t − t₀)/(T − t₀)``:

    e_c(t) = e(t) − w·(e(T) − e_end)

Each error source is one zero-mean random process, independent of the others:

* the two stops' compassed azimuth errors (σ from compassing), e₀ and e_end;
* gyro angle random walk N (white rate noise): variance ``N²·[S(t) − 2w S(t) + w² S(T)]``
  with ``S = ∫ds/(sin²I cos²δ)`` (Φ = 1);
* a random constant bias b: residual ``b·[G(t) − w G(T)]``, ``G = ∫ds/(sin I cos δ)``, zero
  only when 1/sin I is constant over the run;
* a random linear bias trend (per hour), a first-order Gauss–Markov bias (bias instability
  σ, correlation time τ: covariance σ² e^(−|s−u|/τ)) and a rate random walk (bias covariance
  q²·min(s, u) from the tie): their residuals after the closure;
* accelerometer bias and triad misalignment, constant over the run: they bias the
  inclination (through ∂Ȧ/∂I) and the toolface δ (through ``r``, see :func:`azimuth_budget`);
* the inclination's sample noise (accelerometer white noise, and the odometer noise that the
  along-axis acceleration removal turns into a smooth inclination error), entering through
  ∂Ȧ/∂I and through İ: ``r = −Ω cos φ sin A + İ`` feeds ``h`` as ``−İ tan δ``, so
  ``∂Ȧ/∂İ = tan δ/sin I``. Its integral is mostly the boundary term ``tan δ·δI/sin I`` — it
  does not accumulate, but it is not small at low inclination. It is evaluated sample by
  sample through the integration's own filters (the İ and odometer Savitzky–Golay kernels)
  and, its correlation time being seconds, taken as independent between stations.

The integrals are exact sums over the full-rate samples gathered in cells (edges at every
station time and at least 256 per run, each much shorter than the correlation time), with
the bias taken constant within a cell. The output is the full covariance between stations,
so the correlation the stops and the biases give them is kept for position propagation.

Inclination. A station's inclination is one sample of the accelerometers, along-axis
acceleration removed by differentiating the odometer twice (a cubic Savitzky–Golay fit).
Per sample: σ_I² = (σ_acc/g)² + (sin I·σ_a/g)² + (b_acc/g)², with σ_acc the accelerometer
white noise per sample, σ_a the odometer noise times the norm of the second-derivative
filter, and b_acc the accelerometer bias (systematic over the run). The run's end samples
are at rest on the stops: nothing is removed there, and the odometer term is 0.

Units: times s, angles rad, rates rad/s unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.signal import oaconvolve, savgol_coeffs

from pipeline.continuous.run import DEG_H
from pipeline.earth.frames import OMEGA_EARTH, FloatArray
from pipeline.earth.gravity import STANDARD_GRAVITY

__all__ = [
    "AccelErrors",
    "AzimuthBudget",
    "GyroNoise",
    "InclinationNoise",
    "RunGeometry",
    "azimuth_budget",
    "inclination_sigma",
]

_MIN_CELLS = 256
_MAX_CELLS = 4096


@dataclass(frozen=True)
class GyroNoise:
    """Gyro error magnitudes (1σ) of the moving run."""

    arw: float = 0.0
    """angle random walk, deg/√h (white rate noise)"""
    bias: float = 0.0
    """random constant bias, deg/h"""
    bias_trend: float = 0.0
    """random linear bias trend, (deg/h)/h"""
    bias_instability: float = 0.0
    """σ of a first-order Gauss–Markov bias, deg/h"""
    correlation_time: float = 300.0
    """correlation time of the Gauss–Markov bias, s"""
    rate_random_walk: float = 0.0
    """rate random walk, (deg/h)/√h"""
    scale_factor: float = 0.0
    """scale-factor error, ppm"""
    g_sensitivity: float = 0.0
    """g-dependent bias per axis of the specific force, (deg/h)/g"""
    misalignment: float = 0.0
    """input-axis misalignment towards each other body axis, mrad"""


@dataclass(frozen=True)
class InclinationNoise:
    """Per-sample noise of the inclination the integration uses."""

    dt: float
    """sample interval, s"""
    accel: float
    """accelerometer white noise per sample, m/s²"""
    odometer: float
    """odometer white noise per sample, m"""
    odometer_points: int | None
    """samples of the cubic fit differentiating the odometer (None: finite differences)"""
    inc_rate_points: int | None
    """samples of the quadratic fit giving İ (None: finite differences)"""
    gravity: float = STANDARD_GRAVITY
    """m/s²"""


def _derivative_kernel(points: int | None, order: int, deriv: int, dt: float) -> FloatArray:
    """Convolution kernel of the Savitzky–Golay derivative (or, for None, of np.gradient)."""
    if points is None:
        first = np.array([1.0, 0.0, -1.0]) / (2.0 * dt)
        kernel: FloatArray = first if deriv == 1 else np.convolve(first, first)
        return kernel
    out: FloatArray = savgol_coeffs(points, order, deriv=deriv, delta=dt)
    return out


@dataclass(frozen=True)
class RunGeometry:
    """The integrated run, full rate, from the start-stop sample to the end-stop sample."""

    time: FloatArray
    """s, increasing"""
    inc: FloatArray
    """inclination, rad"""
    azi: FloatArray
    """integrated azimuth, rad"""
    misalignment: FloatArray
    """gyro axis from the high side δ, rad (zeros for a tool whose h needs no 1/cos δ)"""
    usable: NDArray[np.bool_]
    """samples whose Ȧ was integrated (not held)"""
    latitude: float
    """deg"""
    closure: bool = True
    """misclosure on the end stop removed linearly in time"""
    backward: bool = False
    """integrated back in time from the end stop (no closure)"""
    inc_noise: InclinationNoise | None = None
    """per-sample inclination noise (None: not modelled)"""


@dataclass(frozen=True)
class AzimuthBudget:
    """Predicted azimuth errors at the stations (rad², rad)."""

    covariance: FloatArray
    """(n, n) covariance between the stations' azimuth errors, rad²"""
    parts: dict[str, FloatArray] = field(default_factory=dict)
    """variance of each source at each station, rad²"""

    @property
    def sigma(self) -> FloatArray:
        """1σ azimuth error per station, rad."""
        out: FloatArray = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        return out


def _cumulative(y: FloatArray, t: FloatArray) -> FloatArray:
    """Running trapezoid integral of y over t, starting at 0."""
    out: FloatArray = np.concatenate([[0.0], np.cumsum(np.diff(t) * (y[1:] + y[:-1]) / 2)])
    return out


@dataclass(frozen=True)
class AccelErrors:
    """Accelerometer errors constant over the run (1σ)."""

    bias: float = 0.0
    """bias of each axis, m/s²"""
    misalignment: float = 0.0
    """tilt of the triad from the gyro frame about each axis, rad"""
    gravity: float = STANDARD_GRAVITY
    """m/s²"""

    @property
    def inclination(self) -> float:
        """σ of the inclination bias they make (high-side/axial bias, tilt about y), rad."""
        return float(np.hypot(self.bias / self.gravity, self.misalignment))


def azimuth_budget(
    run: RunGeometry,
    station_time: FloatArray,
    sigma_start: float,
    sigma_end: float,
    gyro: GyroNoise,
    accel: AccelErrors | None = None,
) -> AzimuthBudget:
    """Covariance of the closed (or single-tie) azimuth at ``station_time`` (s).

    ``sigma_start``/``sigma_end``: the stops' azimuth σ, rad. Systematic accelerometer errors
    bias the inclination (through ∂Ȧ/∂I) and the toolface δ of the gyro: ``h`` then takes
    ``−r·δψ`` with ``r = −Ω cos φ sin A + İ``, so ``∂Ȧ/∂ψ = (r − h tan δ)/sin I`` — large while
    the inclination changes (its integral is ``δψ·ΔI/sin I``). A right-side bias b gives
    ``δψ = b/(g sin I)``, a tilt m of the triad about x gives ``m·cot I``, about z ``m``."""
    acc = accel or AccelErrors()
    t = np.asarray(run.time, dtype=np.float64)
    st = np.asarray(station_time, dtype=np.float64)
    closure = run.closure and not run.backward
    sin_i, cos_i = np.sin(run.inc), np.cos(run.inc)
    sin_a, cos_a = np.sin(run.azi), np.cos(run.azi)
    tan_d = np.tan(run.misalignment)
    phi = np.radians(run.latitude)
    oc, os_ = OMEGA_EARTH * np.cos(phi), OMEGA_EARTH * np.sin(phi)
    ok = run.usable & (np.abs(sin_i) > 0)
    safe_sin = np.where(ok, sin_i, 1.0)
    azi_rate = np.gradient(np.unwrap(run.azi), t)
    r = -oc * sin_a + np.gradient(run.inc, t)
    h = oc * cos_a * cos_i + os_ * sin_i - azi_rate * sin_i
    # rate sensitivities per sample, in time order
    sens = {
        "gain": 1.0 / (safe_sin * np.cos(run.misalignment)),  # |∂Ȧ/∂y|
        "feedback": -oc * (sin_a * cos_i + cos_a * tan_d) / safe_sin,  # ∂Ȧ/∂A
        "d_inc": (-oc * cos_a * sin_i + (os_ - azi_rate) * cos_i) / safe_sin,  # ∂Ȧ/∂I
        "d_inc_rate": tan_d / safe_sin,  # ∂Ȧ/∂İ
        "d_tf": (r - h * tan_d) / safe_sin,  # ∂Ȧ/∂ψ
        # body rates the gyro's errors scale: its own axis, y (≈ r) and z (about the axis)
        "rate_x": h * np.cos(run.misalignment) + r * np.sin(run.misalignment),
        "rate_y": r,
        "rate_z": np.gradient(np.unwrap(run.misalignment), t)
        + azi_rate * cos_i
        + oc * sin_i * cos_a
        - os_ * cos_i,
        "sin": np.abs(sin_i),
        "cot": cos_i / safe_sin,
    }
    sens = {k: np.where(ok, v, 0.0) if k != "sin" else v for k, v in sens.items()}
    if run.backward:  # integrate from the end stop back in time: elapsed time from the tie
        elapsed = t[-1] - t[::-1]
        st_elapsed = t[-1] - st
        sens = {k: v[::-1] for k, v in sens.items()}
        sens["feedback"] = -sens["feedback"]  # d/dτ = −d/dt
        sens["d_inc_rate"] = -sens["d_inc_rate"]
        tie_sigma = sigma_end
    else:
        elapsed = t - t[0]
        st_elapsed = st - t[0]
        tie_sigma = sigma_start
    duration = float(elapsed[-1])
    st_elapsed = np.clip(st_elapsed, 0.0, duration)
    transition = np.exp(_cumulative(sens["feedback"], elapsed))  # Φ
    n_cells = _MIN_CELLS
    if gyro.bias_instability > 0:
        n_cells = max(n_cells, int(np.ceil(8 * duration / gyro.correlation_time)))
    edges = np.unique(
        np.concatenate([np.linspace(0.0, duration, min(n_cells, _MAX_CELLS) + 1), st_elapsed])
    )
    mid = 0.5 * (edges[1:] + edges[:-1])

    def cells(y: FloatArray) -> FloatArray:
        """∫ y/Φ ds over each cell."""
        out: FloatArray = np.diff(np.interp(edges, elapsed, _cumulative(y / transition, elapsed)))
        return out

    phi_k = np.interp(st_elapsed, elapsed, transition)
    phi_t = float(transition[-1])
    w = st_elapsed / duration if closure and duration > 0 else np.zeros_like(st_elapsed)
    before = edges[1:][None, :] <= st_elapsed[:, None] * (1 + 1e-12) + 1e-12
    a = phi_k[:, None] * before - (w * phi_t)[:, None]  # (stations, cells)

    parts: dict[str, FloatArray] = {}
    cov = np.zeros((st.size, st.size))

    def add(name: str, part: FloatArray) -> None:
        nonlocal cov
        cov = cov + part
        parts[name] = np.diag(part).copy()

    def rank_one(name: str, sigma: float, column: FloatArray) -> None:
        add(name, np.outer(sigma * column, sigma * column))

    gain = sens["gain"]
    rank_one("tie_stop", tie_sigma, phi_k - w * phi_t)
    if closure:
        rank_one("end_stop", sigma_end, w)
    arw = gyro.arw * np.pi / 180.0 / 60.0  # deg/√h → rad/√s
    s2 = np.diff(np.interp(edges, elapsed, _cumulative((gain / transition) ** 2, elapsed)))
    add("arw", arw**2 * (a * s2) @ a.T)
    rank_one("bias", gyro.bias * DEG_H, a @ cells(gain))
    rank_one("bias_trend", gyro.bias_trend * DEG_H / 3600.0, a @ cells(gain * elapsed))
    rank_one("gyro_scale_factor", gyro.scale_factor * 1e-6, a @ cells(gain * sens["rate_x"]))
    g_dep = gyro.g_sensitivity * DEG_H
    rank_one("gyro_g_high_side", g_dep, a @ cells(gain * sens["sin"]))
    rank_one("gyro_g_axial", g_dep, a @ cells(gain * sens["sin"] * sens["cot"]))
    mis = gyro.misalignment * 1e-3
    rank_one("gyro_misalignment_y", mis, a @ cells(gain * sens["rate_y"]))
    rank_one("gyro_misalignment_z", mis, a @ cells(gain * sens["rate_z"]))
    m = a * cells(gain)
    if gyro.bias_instability > 0:
        lag = np.abs(mid[:, None] - mid[None, :])
        kernel = np.exp(-lag / gyro.correlation_time)
        add("bias_instability", (gyro.bias_instability * DEG_H) ** 2 * m @ kernel @ m.T)
    if gyro.rate_random_walk > 0:
        q = gyro.rate_random_walk * DEG_H / 60.0  # (deg/h)/√h → rad/s/√s
        add("rate_random_walk", q**2 * m @ np.minimum(mid[:, None], mid[None, :]) @ m.T)
    rank_one("acc_inclination", acc.inclination, a @ cells(sens["d_inc"]))
    d_tf = sens["d_tf"]
    safe = np.where(sens["sin"] > 0, sens["sin"], 1.0)
    rank_one("acc_bias_toolface", acc.bias / acc.gravity, a @ cells(d_tf / safe))
    rank_one("acc_tilt_toolface", acc.misalignment, a @ cells(d_tf * sens["cot"]))
    rank_one("acc_twist_toolface", acc.misalignment, a @ cells(d_tf))
    if run.inc_noise is not None:
        noise = _inclination_noise_variance(
            run.inc_noise,
            elapsed,
            st_elapsed,
            np.gradient(elapsed) / transition,
            transition,
            w,
            sens["d_inc"],
            sens["d_inc_rate"],
            sens["sin"],
        )
        add("inclination_noise", np.diag(noise))
    return AzimuthBudget(covariance=cov, parts=parts)


def _inclination_noise_variance(
    noise: InclinationNoise,
    elapsed: FloatArray,
    st_elapsed: FloatArray,
    step: FloatArray,
    transition: FloatArray,
    w: FloatArray,
    d_inc: FloatArray,
    d_inc_rate: FloatArray,
    sin_i: FloatArray,
    cells: int = 500_000,
) -> FloatArray:
    """Variance at each station of the azimuth error the inclination's sample noise makes.

    A station row p (over samples) integrates the rate error and applies the closure; the
    rate error is ``∂Ȧ/∂I·δI + ∂Ȧ/∂İ·D₁δI`` and ``δI = n_acc/g − sin I·D₂ n_odo/g``, so the
    row seen by the white noises is ``q = p·∂Ȧ/∂I + D₁ᵀ(p·∂Ȧ/∂İ)`` (accelerometer) and
    ``D₂ᵀ(q·sin I)`` (odometer). The row is ``p = g·Δs/Φ`` with g one constant before the
    station's sample (``Φ_k − w Φ_T``) and another from it on (``−w Φ_T``): away from the
    station (farther than the two filters' half-widths) q and the odometer row are those
    constants times the station-free rows ``Q`` and ``D₂ᵀ(Q·sin I)``, whose squares are
    summed by prefix sums; near it they are evaluated exactly. Stations are taken in blocks
    of at most ``cells`` cells of that neighbourhood."""
    d1 = _derivative_kernel(noise.inc_rate_points, 2, 1, noise.dt)[::-1]  # transposed
    d2 = _derivative_kernel(noise.odometer_points, 3, 2, noise.dt)[::-1]
    n = elapsed.size
    index = np.searchsorted(elapsed, st_elapsed, side="left")
    phi_t = float(transition[-1])
    before = np.interp(st_elapsed, elapsed, transition) - w * phi_t  # g before the station
    after = -w * phi_t  # g from the station on
    q_free = step * d_inc + oaconvolve(step * d_inc_rate, d1, mode="same")
    odo_free = oaconvolve(q_free * sin_i, d2, mode="same")
    sum_q = np.concatenate([[0.0], np.cumsum(q_free**2)])
    sum_odo = np.concatenate([[0.0], np.cumsum(odo_free**2)])
    spread = d1.size // 2 + d2.size // 2
    near = spread + 1  # half-width where the rows differ from the station-free ones
    reach = near + spread  # half-width of the samples the neighbourhood depends on
    offsets = np.arange(-reach, reach + 1)
    inner = np.abs(offsets) <= near
    pad = np.zeros(reach)
    padded = [np.concatenate([pad, x, pad]) for x in (step, d_inc, d_inc_rate, sin_i)]
    out = np.empty(st_elapsed.size)
    block = max(1, cells // offsets.size)
    for lo in range(0, st_elapsed.size, block):
        sl = slice(lo, min(lo + block, st_elapsed.size))
        columns = index[sl, None] + offsets[None, :]  # sample index; padded: + reach
        step_n, d_inc_n, d_rate_n, sin_n = (x[columns + reach] for x in padded)
        p = step_n * np.where(offsets < 0, before[sl, None], after[sl, None])
        q = p * d_inc_n + oaconvolve(p * d_rate_n, d1[None, :], mode="same", axes=1)
        odo = oaconvolve(q * sin_n, d2[None, :], mode="same", axes=1)
        inside = inner & (columns >= 0) & (columns < n)
        first = np.clip(index[sl] - near, 0, n)  # first sample of the neighbourhood
        last = np.clip(index[sl] + near + 1, 0, n)  # one past its last
        far_q = before[sl] ** 2 * sum_q[first] + after[sl] ** 2 * (sum_q[n] - sum_q[last])
        far_odo = before[sl] ** 2 * sum_odo[first] + after[sl] ** 2 * (sum_odo[n] - sum_odo[last])
        out[sl] = (noise.accel / noise.gravity) ** 2 * (
            far_q + np.sum(np.where(inside, q, 0.0) ** 2, axis=1)
        ) + (noise.odometer / noise.gravity) ** 2 * (
            far_odo + np.sum(np.where(inside, odo, 0.0) ** 2, axis=1)
        )
    return out


def inclination_sigma(inc: FloatArray, noise: InclinationNoise, accel: AccelErrors) -> FloatArray:
    """1σ inclination error (rad) of single samples at inclination ``inc`` (rad): sample noise
    and the accelerometers' constant errors."""
    kernel = _derivative_kernel(noise.odometer_points, 3, 2, noise.dt)
    odometer = noise.odometer * float(np.linalg.norm(kernel))
    var = (noise.accel**2 + (np.sin(inc) * odometer) ** 2) / noise.gravity**2
    out: FloatArray = np.sqrt(var + accel.inclination**2)
    return out

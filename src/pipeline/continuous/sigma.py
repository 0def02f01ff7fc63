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

from dataclasses import dataclass, field, replace
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from pipeline.continuous.filters import TimeGradient
from pipeline.continuous.run import DEG_H
from pipeline.continuous.sigma_forms import Evaluated, StationRows, markov_kernel
from pipeline.continuous.sigma_noise import InclinationNoise, NoiseSums, derivative_kernel
from pipeline.continuous.store import (
    CarriedUnwrap,
    Interpolation,
    RunningIntegrals,
    carried_cumsum,
    chunks,
)
from pipeline.earth.frames import OMEGA_EARTH, FloatArray, sin_cos, tangent_sin_cos
from pipeline.earth.gravity import STANDARD_GRAVITY

__all__ = [
    "AccelErrors",
    "AzimuthBudget",
    "GyroNoise",
    "InclinationNoise",
    "RunGeometry",
    "RunView",
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
    inc_half: FloatArray | None = None
    """tan(I/2) as the integration had it, whose sine and cosine need no trig function
    (None: from ``inc``)"""
    misalignment_half: FloatArray | None = None
    """tan(δ/2) likewise (None: from ``misalignment``)"""

    @property
    def size(self) -> int:
        """Samples of the run."""
        return int(self.time.size)

    @property
    def rows(self) -> int:
        """Samples the budget reads at a time: all."""
        return max(self.size, 1)

    def times(self, lo: int, hi: int) -> FloatArray:
        """Times of samples ``lo``…``hi − 1``, s."""
        return self.time[lo:hi]

    def slice(self, lo: int, hi: int) -> RunGeometry:
        """Samples ``lo``…``hi − 1`` of the run."""
        part = slice(lo, hi)
        return replace(
            self,
            time=self.time[part],
            inc=self.inc[part],
            azi=self.azi[part],
            misalignment=self.misalignment[part],
            usable=self.usable[part],
            inc_half=None if self.inc_half is None else self.inc_half[part],
            misalignment_half=(
                None if self.misalignment_half is None else self.misalignment_half[part]
            ),
        )


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


class RunView(Protocol):
    """The integrated run read by sample range (time order): a :class:`RunGeometry`, or a run
    kept on disk (:class:`pipeline.continuous.series.StoredRun`)."""

    @property
    def size(self) -> int: ...

    @property
    def rows(self) -> int:
        """samples a pass reads at a time"""
        ...

    @property
    def latitude(self) -> float: ...

    @property
    def closure(self) -> bool: ...

    @property
    def backward(self) -> bool: ...

    @property
    def inc_noise(self) -> InclinationNoise | None: ...

    def slice(self, lo: int, hi: int) -> RunGeometry: ...

    def times(self, lo: int, hi: int) -> FloatArray:
        """Times of samples ``lo``…``hi − 1``, s."""
        ...


def azimuth_budget(
    run: RunView,
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
    ``δψ = b/(g sin I)``, a tilt m of the triad about x gives ``m·cot I``, about z ``m``.

    The run is read ``run.rows`` samples at a time (:class:`_Integrals`)."""
    acc = accel or AccelErrors()
    st = np.asarray(station_time, dtype=np.float64)
    closure = run.closure and not run.backward
    t_first, t_last = (
        float(run.slice(0, 1).time[0]),
        float(run.slice(run.size - 1, run.size).time[0]),
    )
    if run.backward:  # integrate from the end stop back in time: elapsed time from the tie
        st_elapsed, tie_sigma = t_last - st, sigma_end
    else:
        st_elapsed, tie_sigma = st - t_first, sigma_start
    duration = t_last - t_first
    st_elapsed = np.clip(st_elapsed, 0.0, duration)
    n_cells = _MIN_CELLS
    if gyro.bias_instability > 0:
        n_cells = max(n_cells, int(np.ceil(8 * duration / gyro.correlation_time)))
    edges = np.unique(
        np.concatenate([np.linspace(0.0, duration, min(n_cells, _MAX_CELLS) + 1), st_elapsed])
    )
    mid = 0.5 * (edges[1:] + edges[:-1])
    sums = _Integrals(run, edges, st_elapsed, (t_first, t_last))
    cells = sums.cells

    w = st_elapsed / duration if closure and duration > 0 else np.zeros_like(st_elapsed)
    # the stations' rows over the cells: Φ_k before the station, less the closure's w_k·Φ_T
    before = np.searchsorted(edges[1:], st_elapsed * (1 + 1e-12) + 1e-12, side="right")
    rows = StationRows(sums.phi_k, w * sums.phi_t, before, mid.size)

    parts: dict[str, FloatArray] = {}
    columns: list[FloatArray] = []  # σ times each rank-one source's row sums
    quadratic = np.zeros((st.size, st.size))

    def add(name: str, part: FloatArray) -> None:
        nonlocal quadratic
        quadratic += part
        parts[name] = np.diag(part).copy()

    def rank_one(name: str, sigma: float, column: FloatArray) -> None:
        columns.append(sigma * column)
        parts[name] = columns[-1] * columns[-1]

    rank_one("tie_stop", tie_sigma, rows.phi - rows.closure)
    if closure:
        rank_one("end_stop", sigma_end, w)
    arw = gyro.arw * np.pi / 180.0 / 60.0  # deg/√h → rad/√s
    add("arw", arw**2 * rows.diagonal(cells["gain_squared"]))
    rank_one("bias", gyro.bias * DEG_H, rows.linear(cells["gain"]))
    rank_one("bias_trend", gyro.bias_trend * DEG_H / 3600.0, rows.linear(cells["gain_elapsed"]))
    rank_one("gyro_scale_factor", gyro.scale_factor * 1e-6, rows.linear(cells["gain_rate_x"]))
    g_dep = gyro.g_sensitivity * DEG_H
    rank_one("gyro_g_high_side", g_dep, rows.linear(cells["gain_sin"]))
    rank_one("gyro_g_axial", g_dep, rows.linear(cells["gain_cos"]))
    mis = gyro.misalignment * 1e-3
    rank_one("gyro_misalignment_y", mis, rows.linear(cells["gain_rate_y"]))
    rank_one("gyro_misalignment_z", mis, rows.linear(cells["gain_rate_z"]))
    if gyro.bias_instability > 0:
        markov = rows.quadratic(cells["gain"], mid, markov_kernel(gyro.correlation_time))
        add("bias_instability", (gyro.bias_instability * DEG_H) ** 2 * markov)
    if gyro.rate_random_walk > 0:
        q = gyro.rate_random_walk * DEG_H / 60.0  # (deg/h)/√h → rad/s/√s
        add("rate_random_walk", q**2 * rows.quadratic(cells["gain"], mid, Evaluated(np.minimum)))
    rank_one("acc_inclination", acc.inclination, rows.linear(cells["d_inc"]))
    rank_one("acc_bias_toolface", acc.bias / acc.gravity, rows.linear(cells["tf_bias"]))
    rank_one("acc_tilt_toolface", acc.misalignment, rows.linear(cells["tf_tilt"]))
    rank_one("acc_twist_toolface", acc.misalignment, rows.linear(cells["tf_twist"]))
    if sums.noise is not None:
        noise = sums.noise.variance(rows.phi - rows.closure, -rows.closure)
        quadratic[np.diag_indices(st.size)] += noise
        parts["inclination_noise"] = noise
    stacked = np.stack(columns, axis=1)
    return AzimuthBudget(covariance=stacked @ stacked.T + quadratic, parts=parts)


def _sensitivities(run: RunGeometry, oc: float, os_: float) -> dict[str, FloatArray]:
    """Rate sensitivities per sample (time order) of a run's samples; the gradients at the
    ends are one-sided (read one sample beyond a range to have them central)."""
    grad = TimeGradient(run.time)
    sin_i, cos_i = _sin_cos(run.inc, run.inc_half)
    sin_a, cos_a = sin_cos(run.azi)
    if run.misalignment.any():
        sin_d, cos_d = _sin_cos(run.misalignment, run.misalignment_half)
        turn_rate = grad(CarriedUnwrap()(run.misalignment))
    else:  # δ = 0 (a tool whose h needs no 1/cos δ): the same numbers, without trig functions
        sin_d, cos_d, turn_rate = np.zeros(run.size), np.ones(run.size), np.zeros(run.size)
    tan_d = sin_d / cos_d  # (np.tan costs a sine and cosine more)
    ok = run.usable & (np.abs(sin_i) > 0)
    safe_sin = np.where(ok, sin_i, 1.0)
    azi_rate = grad(CarriedUnwrap()(run.azi))
    r = -oc * sin_a + grad(run.inc)
    h = oc * cos_a * cos_i + os_ * sin_i - azi_rate * sin_i
    sens = {
        "gain": 1.0 / (safe_sin * cos_d),  # |∂Ȧ/∂y|
        "feedback": -oc * (sin_a * cos_i + cos_a * tan_d) / safe_sin,  # ∂Ȧ/∂A
        "d_inc": (-oc * cos_a * sin_i + (os_ - azi_rate) * cos_i) / safe_sin,  # ∂Ȧ/∂I
        "d_inc_rate": tan_d / safe_sin,  # ∂Ȧ/∂İ
        "d_tf": (r - h * tan_d) / safe_sin,  # ∂Ȧ/∂ψ
        # body rates the gyro's errors scale: its own axis, y (≈ r) and z (about the axis)
        "rate_x": h * cos_d + r * sin_d,
        "rate_y": r,
        "rate_z": turn_rate + azi_rate * cos_i + oc * sin_i * cos_a - os_ * cos_i,
        "cot": cos_i / safe_sin,
    }
    outside = np.flatnonzero(~ok)  # each array is new: zeroed in place where not integrated
    for values in sens.values():
        values[outside] = 0.0
    sens["sin"] = np.abs(sin_i)
    return sens


def _sin_cos(angle: FloatArray, half: FloatArray | None) -> tuple[FloatArray, FloatArray]:
    """Sine and cosine of ``angle`` (rad), from the tangent of its ``half`` where given."""
    return sin_cos(angle) if half is None else tangent_sin_cos(half)


class _Integrals:
    """What the budget needs from the full-rate run, read ``run.rows`` samples at a time in
    integration order (time order, or back in time from the end stop): the integrals of each
    error's rate over the cells between ``edges`` (elapsed s), Φ at the stations and at the
    end, and the inclination-noise sums. Each running integral carries its last value from
    one chunk to the next, so the numbers are those of the whole series (the cells'
    integrals to the rounding of their sums: :class:`~.store.RunningIntegrals`)."""

    def __init__(
        self,
        run: RunView,
        edges: FloatArray,
        st_elapsed: FloatArray,
        ends: tuple[float, float],
    ) -> None:
        self.run, self.ends, self.size = run, ends, run.size
        phi = np.radians(run.latitude)
        self.oc, self.os_ = OMEGA_EARTH * np.cos(phi), OMEGA_EARTH * np.sin(phi)
        self.noise = (
            None
            if run.inc_noise is None
            else NoiseSums(run.inc_noise, self.size, self._station_index(st_elapsed))
        )
        halo = 2 + (0 if self.noise is None else self.noise.halo)
        at_edges = RunningIntegrals(edges, len(_INTEGRANDS))
        at_stations = Interpolation(st_elapsed, 1)
        feedback_carry = 0.0
        for lo, hi in chunks(0, self.size, run.rows):
            v0, v1 = max(lo - halo, 0), min(hi + halo, self.size)
            elapsed, sens = self._ordered(v0, v1)
            # Φ over [v0, v1) from its running integral at v0 (kept from the chunk before)
            log_phi = np.concatenate(
                [
                    [feedback_carry],
                    carried_cumsum(_trapezoids(sens["feedback"], elapsed), feedback_carry),
                ]
            )
            transition = np.exp(log_phi)
            next_start = max(hi - halo, 0)
            if next_start >= v0:
                feedback_carry = float(log_phi[next_start - v0])
            own = slice(lo - v0, hi - v0)
            before = slice(max(lo - 1, 0) - v0, hi - v0)  # the chunk and the sample before it
            y = self._integrands(sens, elapsed, transition)
            at_edges.add(elapsed[before], *(integrand[before] for integrand in y))
            at_stations.feed(elapsed[own], transition[own])
            if hi == self.size:
                self.phi_t = float(transition[own][-1])
            if self.noise is not None:
                step = np.gradient(elapsed) / transition
                self.noise.add(lo, hi, v0, step, sens["d_inc"], sens["d_inc_rate"], sens["sin"])
        self.cells = dict(zip(_INTEGRANDS, np.diff(at_edges.result(), axis=1), strict=True))
        self.phi_k = at_stations.result()[0]

    def _station_index(self, st_elapsed: FloatArray) -> NDArray[np.int64]:
        """Each station's sample: the first whose elapsed time is at or after the station's."""
        index = np.zeros(st_elapsed.size, dtype=np.int64)
        for lo, hi in chunks(0, self.size, self.run.rows):
            index += np.searchsorted(self._elapsed(lo, hi), st_elapsed, side="left")
        return index

    def _original(self, lo: int, hi: int) -> tuple[int, int]:
        """Samples (time order) of integration-order samples ``[lo, hi)``."""
        return (self.size - hi, self.size - lo) if self.run.backward else (lo, hi)

    def _elapsed(self, lo: int, hi: int) -> FloatArray:
        a, b = self._original(lo, hi)
        t = self.run.times(a, b)
        out: FloatArray = self.ends[1] - t[::-1] if self.run.backward else t - self.ends[0]
        return out

    def _ordered(self, lo: int, hi: int) -> tuple[FloatArray, dict[str, FloatArray]]:
        """Elapsed time and sensitivities of integration-order samples ``[lo, hi)``: read
        with one sample more on each side, so that their gradients are the whole series'."""
        a, b = self._original(lo, hi)
        wa, wb = max(a - 1, 0), min(b + 1, self.size)
        part = self.run.slice(wa, wb)
        sens = {k: v[a - wa : b - wa] for k, v in _sensitivities(part, self.oc, self.os_).items()}
        t = part.time[a - wa : b - wa]
        if not self.run.backward:
            return t - self.ends[0], sens
        sens = {k: v[::-1] for k, v in sens.items()}
        sens["feedback"] = -sens["feedback"]  # d/dτ = −d/dt
        sens["d_inc_rate"] = -sens["d_inc_rate"]
        return self.ends[1] - t[::-1], sens

    @staticmethod
    def _integrands(
        sens: dict[str, FloatArray], elapsed: FloatArray, transition: FloatArray
    ) -> list[FloatArray]:
        """Each error's rate divided by Φ, in the order of :data:`_INTEGRANDS` (the ARW's is
        (gain/Φ)²), each made in its own array (not rows of one: past glibc's mmap threshold,
        :data:`pipeline.streams.MMAP_THRESHOLD`, that would be mapped and faulted in afresh
        for each chunk)."""
        y = [np.empty(transition.size) for _ in _INTEGRANDS]
        gain, gain_elapsed, rate_x, gain_sin, gain_cos, rate_y, rate_z, d_inc, *tf, squared = y
        tf_bias, tf_tilt, tf_twist = tf
        np.divide(sens["gain"], transition, out=gain)
        np.multiply(gain, elapsed, out=gain_elapsed)
        np.multiply(gain, sens["rate_x"], out=rate_x)
        np.multiply(gain, sens["sin"], out=gain_sin)
        np.multiply(gain_sin, sens["cot"], out=gain_cos)
        np.multiply(gain, sens["rate_y"], out=rate_y)
        np.multiply(gain, sens["rate_z"], out=rate_z)
        np.divide(sens["d_inc"], transition, out=d_inc)
        np.divide(sens["d_tf"], transition, out=tf_twist)
        np.divide(tf_twist, np.where(sens["sin"] > 0, sens["sin"], 1.0), out=tf_bias)
        np.multiply(tf_twist, sens["cot"], out=tf_tilt)
        np.square(gain, out=squared)
        return y


_INTEGRANDS = (
    "gain",
    "gain_elapsed",
    "gain_rate_x",
    "gain_sin",
    "gain_cos",
    "gain_rate_y",
    "gain_rate_z",
    "d_inc",
    "tf_bias",
    "tf_tilt",
    "tf_twist",
    "gain_squared",
)
"""Rates integrated over the cells (divided by Φ; the last, the ARW's, is (gain/Φ)²)."""


def _trapezoids(y: FloatArray, t: FloatArray) -> FloatArray:
    """Trapezoid areas of y between consecutive samples of t."""
    out: FloatArray = np.diff(t) * (y[1:] + y[:-1]) / 2
    return out


def inclination_sigma(inc: FloatArray, noise: InclinationNoise, accel: AccelErrors) -> FloatArray:
    """1σ inclination error (rad) of single samples at inclination ``inc`` (rad): sample noise
    and the accelerometers' constant errors."""
    kernel = derivative_kernel(noise.odometer_points, 3, 2, noise.dt)
    odometer = noise.odometer * float(np.linalg.norm(kernel))
    var = (noise.accel**2 + (np.sin(inc) * odometer) ** 2) / noise.gravity**2
    out: FloatArray = np.sqrt(var + accel.inclination**2)
    return out

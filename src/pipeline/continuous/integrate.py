"""Continuous-mode azimuth integration of a single-axis, servo-stabilised gyro (DOMAIN.md §6).

Between a compassing stop at the start and one at the end of the run the tool moves; its
frame x axis (the gyro) is kept near the high side by the servo. Per sample:

* inclination and gravity toolface of frame x from the accelerometers (gravity sign
  convention): ``I = atan2(√(gx² + gy²), gz)``, ``ψ = atan2(gy, −gx)``; the along-axis
  acceleration of the tool (odometer's second derivative) is removed from ``gz`` first;
* ``İ`` is the time derivative of that inclination, smoothed (Savitzky–Golay,
  ``inc_rate_window``);
* the residual misalignment of the gyro from the high side is ``δ = ψ``; with the right-side
  component ``r = −Ω cos φ sin A + İ`` (current A estimate) the high-side component is
  ``h = (y − r sin δ)/cos δ``, and ``Ȧ = (Ω cos φ cos A cos I + Ω sin φ sin I − h)/sin I``;
* ``A(t)`` is integrated with the trapezoid rule (Heun predictor–corrector, as Ȧ depends on
  A) from the start stop's azimuth. The recursion is solved for every sample at once, by
  Newton's method on the whole series (Ȧ depends on A only through the Earth rate, so two to
  four iterations reach the step-by-step result to 1e-12 rad); a later pass starts from the
  previous pass's azimuths.

Closure ("continuous-gyro drift"): the integrated azimuth at the end stop minus the end
stop's compassed azimuth is the misclosure; it is distributed linearly in time over the run
and removed, which cancels a constant gyro bias exactly (its azimuth error grows linearly in
time at constant inclination). The misclosure is reported. A run starting near vertical
(where the start stop's azimuth means nothing) is integrated backward from the end stop
instead, with no closure (misclosure reported as NaN, flag ``FLAG_NO_CLOSURE``).

Near vertical (``sin I < sin(vertical_below)``) Ȧ is singular: those samples are flagged,
the azimuth is held (Ȧ = 0) through them and integration resumes after; flagged stations get
an infinite ``sigma_azi``. A held section's azimuth change is not recovered: the closure
correction then absorbs it as a linear-in-time error, so azimuths after a flagged section
are only as good as that assumption (flag ``FLAG_AFTER_VERTICAL``).

Other tools (``gyro_axes``, default: from the gyro columns present;
:mod:`pipeline.continuous.multiaxis`): two cross-axial gyros (xy) give h directly by the
toolface, ``h = ω_x cos ψ − ω_y sin ψ`` (so δ = 0 above, free rotation allowed), and İ as
``r + Ω cos φ sin A`` from ``r = ω_x sin ψ + ω_y cos ψ``; near vertical they are held as
above. A triad (xyz) is integrated as a strapdown attitude through vertical, with a rotation
closure on the end stop (:mod:`pipeline.continuous.strapdown`; flag
``FLAG_AZIMUTH_UNDEFINED`` where the azimuth is ill-defined, nothing held).

Stations every ``spacing`` m of MD are placed on the odometer's cubic fit, not its noisy
samples (:mod:`pipeline.continuous.stations`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from pipeline.continuous.multiaxis import apsidal_components, resolve_gyro_axes
from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.run import (
    DEG_H,
    ContinuousError,
    Odometer,
    RunStops,
    compassed_stop,
    float_column,
    odometer_fit,
    run_bounds,
    wrap_angle,
)
from pipeline.continuous.sigma import InclinationNoise, RunGeometry
from pipeline.continuous.stations import ContinuousResult, run_result
from pipeline.continuous.strapdown import strapdown_run
from pipeline.continuous.tables import (
    FLAG_AFTER_VERTICAL,
    FLAG_LARGE_MISALIGNMENT,
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
)
from pipeline.earth.frames import OMEGA_EARTH, FloatArray

__all__ = ["integrate_continuous"]


def integrate_continuous(
    samples: pa.Table, stops: pa.Table, latitude: float, options: ContinuousOptions
) -> ContinuousResult:
    """Integrate the azimuth of the moving run between its two compassed stops (x and xy
    tools here; xyz: :mod:`pipeline.continuous.strapdown`)."""
    axes = resolve_gyro_axes(samples.column_names, options.gyro_axes)
    if "md" not in samples.column_names:
        raise ContinuousError("continuous integration needs the odometer MD column")
    if "station" not in samples.column_names:
        raise ContinuousError("continuous integration needs the station markers of the stops")
    begin, end, first_id, last_id = run_bounds(float_column(samples, "station"))
    ends = compassed_stop(stops, first_id), compassed_stop(stops, last_id)
    odometer = odometer_fit(samples, begin, end, options.odometer_window)
    if axes != "xyz":
        sl = slice(begin, end + 1)  # stop sample, moving samples, stop sample
        return _apsidal_run(samples, axes == "xy", sl, odometer, ends, latitude, options)
    sd = strapdown_run(samples, ends, (begin, end), latitude, options)
    run = RunGeometry(  # azimuth errors to first order as a two-axis tool's (δ = 0)
        time=odometer.time,
        inc=sd.inc,
        azi=sd.azi,
        misalignment=np.zeros(odometer.time.size),
        usable=sd.flags == 0,
        latitude=latitude,
        closure=options.closure,
        # I carries the stops' accelerometer bias, no per-sample noise (gyro-driven)
        inc_noise=InclinationNoise(
            dt=odometer.dt, accel=0.0, odometer=0.0, odometer_points=None, inc_rate_points=None
        ),
    )
    return run_result(odometer, sd.toolface, sd.flags, ends, options, run, sd.misclosure)


def _apsidal_run(
    samples: pa.Table,
    two_axis: bool,
    sl: slice,
    odometer: Odometer,
    ends: RunStops,
    latitude: float,
    options: ContinuousOptions,
) -> ContinuousResult:
    """Ȧ from the high-side rate of a single-axis (x) or two-axis (xy) tool over the samples
    ``sl``, closed on the end stop or integrated back from it."""
    start, finish = ends
    t, dt = odometer.time, odometer.dt
    gx, gy, gz = (float_column(samples, f"acc_{a}")[sl] for a in "xyz")
    y = float_column(samples, "gyro_x")[sl] * DEG_H
    y_right = float_column(samples, "gyro_y")[sl] * DEG_H if two_axis else None
    window = max(5, round(options.inc_rate_window / dt) | 1)
    phi = np.radians(latitude)
    oc, os_ = OMEGA_EARTH * np.cos(phi), OMEGA_EARTH * np.sin(phi)
    azi_rate = np.zeros(t.size)
    inc_rate = np.zeros(t.size)
    vertical_stop = np.sin(np.radians(options.vertical_below))
    backward = bool(
        np.sin(np.radians(start["inc"])) < vertical_stop
        and np.sin(np.radians(finish["inc"])) >= vertical_stop
    )
    # a run starting near vertical is tied to the inclined end stop and integrated back in time
    order = slice(None, None, -1) if backward else slice(None)
    tie = float(np.radians((finish if backward else start)["azi"]))
    guess: FloatArray | None = None  # the previous pass's azimuth, in integration order
    for _ in range(options.passes):
        inc, tf = _inclination_toolface(gx, gy, gz, odometer, inc_rate, azi_rate)
        if y_right is None:  # single axis: h from the gyro at misalignment δ = ψ, and İ
            high, delta = y, tf
            inc_rate = (
                savgol_filter(inc, window, 2, deriv=1, delta=dt)
                if t.size > window
                else np.gradient(inc, t)
            )
        else:  # two axes: h and r by the toolface; İ from r after the first pass (below)
            (high, right), delta = apsidal_components(y, y_right, tf), np.zeros(t.size)
        guess, flags, held = _integrate(
            t[order],
            high[order],
            inc[order],
            inc_rate[order],
            delta[order],
            tie,
            oc,
            os_,
            options,
            guess,
        )
        azi, flags, held = guess[order], flags[order], held[order]
        azi_rate = np.gradient(azi, t)
        if y_right is not None:  # İ = r + Ω cos φ sin A, measured, not differentiated
            inc_rate = right + oc * np.sin(azi)
    weight = (t - t[0]) / (t[-1] - t[0])
    if backward:  # one usable tie only: no closure, and the start stop's azimuth is not used
        misclosure = float("nan")
    else:
        misclosure = float(wrap_angle(azi[-1] - np.radians(finish["azi"])))
        if options.closure:
            azi = azi - misclosure * weight
    after = (np.cumsum(held[::-1]) > 0)[::-1] if backward else np.cumsum(held) > 0
    if backward:
        flags |= FLAG_NO_CLOSURE
    flags[after & ~held] |= FLAG_AFTER_VERTICAL
    run = RunGeometry(
        time=t,
        inc=inc,
        azi=azi,
        misalignment=delta,
        usable=(flags & (FLAG_NEAR_VERTICAL | FLAG_LARGE_MISALIGNMENT)) == 0,
        latitude=latitude,
        closure=options.closure,
        backward=backward,
        inc_noise=InclinationNoise(
            dt=dt,
            accel=options.acc_noise / (60.0 * np.sqrt(dt)),  # (m/s)/√h → per sample
            odometer=options.odometer_noise,
            odometer_points=odometer.points,
            inc_rate_points=window if t.size > window else None,
        ),
    )
    return run_result(odometer, tf, flags, ends, options, run, misclosure)


def _inclination_toolface(
    gx: FloatArray,
    gy: FloatArray,
    gz: FloatArray,
    odometer: Odometer,
    inc_rate: FloatArray,
    azi_rate: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """Inclination and gravity toolface of frame x (rad) from the accelerometers (m/s²) with
    the tool's acceleration removed: along the axis the odometer's, across it
    v·(İ·hs + sin I·Ȧ·rs) from the current İ and Ȧ (rad/s)."""
    tf = np.arctan2(gy, -gx)
    inc = np.arctan2(np.hypot(gx, gy), gz + odometer.accel)
    cross_h = odometer.speed * inc_rate
    cross_r = odometer.speed * np.sin(inc) * azi_rate
    cx = gx + cross_h * np.cos(tf) + cross_r * np.sin(tf)
    cy = gy - cross_h * np.sin(tf) + cross_r * np.cos(tf)
    inc_out: FloatArray = np.arctan2(np.hypot(cx, cy), gz + odometer.accel)
    tf_out: FloatArray = np.arctan2(cy, -cx)
    return inc_out, tf_out


def _integrate(
    t: FloatArray,
    y: FloatArray,
    inc: FloatArray,
    inc_rate: FloatArray,
    tf: FloatArray,
    azi0: float,
    oc: float,
    os_: float,
    options: ContinuousOptions,
    guess: FloatArray | None = None,
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.bool_]]:
    """Heun (trapezoid) integration of Ȧ from the high-side gyro component; flags.

    Each step maps ``A_k`` to ``A_{k+1} = A_k + Δt/2·(Ȧ_k(A_k) + Ȧ_{k+1}(A_k + Δt·Ȧ_k(A_k)))``.
    The recursion is solved for all samples at once by Newton's method on the whole series
    (:func:`_heun_series`), from ``guess`` (rad: e.g. a previous pass's azimuth; default the
    start azimuth throughout)."""
    sin_i, cos_i = np.sin(inc), np.cos(inc)
    sin_d, cos_d = np.sin(tf), np.cos(tf)
    flags = np.zeros(t.size, dtype=np.int64)
    vertical = sin_i < np.sin(np.radians(options.vertical_below))
    flags[vertical] |= FLAG_NEAR_VERTICAL
    misaligned = np.abs(cos_d) < np.cos(np.radians(options.max_misalignment))
    flags[misaligned & ~vertical] |= FLAG_LARGE_MISALIGNMENT
    held = vertical | misaligned
    held[0] = held[-1] = False  # the stops themselves: tool at rest
    usable = ~held & ~vertical  # a stop at rest is not held, but Ȧ is still singular there
    # Ȧ = const + by_cos·cos A + by_sin·sin A, from h = (y − r sin δ)/cos δ, r = −Ω cos φ sin A + İ
    sin_u, cos_u = np.where(usable, sin_i, 1.0), np.where(usable, cos_d, 1.0)
    const = np.where(usable, (os_ * sin_i - (y - inc_rate * sin_d) / cos_u) / sin_u, 0.0)
    by_cos = np.where(usable, oc * cos_i / sin_u, 0.0)
    by_sin = np.where(usable, -oc * sin_d / cos_u / sin_u, 0.0)

    def rate(a: FloatArray, k: slice) -> tuple[FloatArray, FloatArray]:
        """Ȧ and ∂Ȧ/∂A (rad/s, 1/s) of the samples ``k`` at azimuths ``a`` (0 where held)."""
        sin_a, cos_a = np.sin(a), np.cos(a)
        return (
            const[k] + by_cos[k] * cos_a + by_sin[k] * sin_a,
            by_sin[k] * cos_a - by_cos[k] * sin_a,
        )

    start = np.full(t.size, azi0) if guess is None else guess.copy()
    start[0] = azi0
    feedback = np.hypot(by_cos, by_sin)  # bounds |∂Ȧ/∂A| and |∂²Ȧ/∂A²|
    return _heun_series(np.diff(t), rate, feedback, start), flags, held


RateFunction = Callable[[FloatArray, slice], tuple[FloatArray, FloatArray]]
"""Ȧ and ∂Ȧ/∂A of a slice of the samples at given azimuths."""

_NEWTON_TOLERANCE = 1e-12
"""rad: bound of the error left in a converged series."""
_NEWTON_ITERATIONS = 40
_SCAN_SPAN = 16.0
"""Largest ∑|ln gain| over one cumulative-product segment of :func:`_affine_recursion`."""


def _heun_series(
    step: FloatArray, rate: RateFunction, feedback: FloatArray, azi: FloatArray
) -> FloatArray:
    """The Heun recursion's azimuths (rad) from ``azi[0]`` over steps ``step`` (s), solved
    as one system by Newton's method from the first guess ``azi`` (overwritten): each
    iteration evaluates every step's residual and the step's derivative at once and solves
    the linearised recursion ``δ_{k+1} = g_k δ_k + res_k`` by cumulative products.

    Ȧ depends on A only through the Earth-rate terms, so few iterations are needed:
    with ``feedback`` a bound of |∂Ȧ/∂A| and |∂²Ȧ/∂A²| per sample (1/s) and ``L`` its
    integral over the run, an iteration leaves an error of at most ``L·e^L·δ²`` after a
    correction of at most δ (quadratic convergence); it stops when that is below
    ``_NEWTON_TOLERANCE``."""
    half = step / 2
    reach = float(np.sum(np.abs(step) * np.maximum(feedback[:-1], feedback[1:])))
    growth = reach * float(np.exp(min(reach, 700.0)))
    for _ in range(_NEWTON_ITERATIONS):
        f, df = rate(azi, slice(None))
        predicted = azi[:-1] + step * f[:-1]
        f_next, df_next = rate(predicted, slice(1, None))
        residual = azi[:-1] + half * (f[:-1] + f_next) - azi[1:]
        gain = 1.0 + half * (df[:-1] + df_next * (1.0 + step * df[:-1]))
        correction = _affine_recursion(gain, residual)
        azi[1:] += correction
        largest = float(np.max(np.abs(correction)))
        if not growth * largest**2 > _NEWTON_TOLERANCE:  # (NaN input propagates)
            return azi
    raise ContinuousError(
        f"the azimuth integration did not converge in {_NEWTON_ITERATIONS} Newton iterations "
        f"(last correction {largest:.3g} rad)"
    )


def _affine_recursion(gain: FloatArray, forcing: FloatArray) -> FloatArray:
    """``x_1 … x_n`` of ``x_{k+1} = gain_k·x_k + forcing_k`` from ``x_0 = 0``: within a
    segment ``x = P·(x_start + cumsum(forcing/P))`` with P the running product of the gains,
    segments cut where the gains' log-variation reaches ``_SCAN_SPAN`` (P stays in range)."""
    with np.errstate(divide="ignore"):
        variation = np.cumsum(np.nan_to_num(np.abs(np.log(np.abs(gain))), nan=0.0))
    cuts = np.searchsorted(variation, np.arange(_SCAN_SPAN, variation[-1], _SCAN_SPAN))
    out = np.empty_like(forcing)
    carry = 0.0
    for lo, hi in zip([0, *cuts], [*cuts, gain.size], strict=True):
        if hi > lo:
            product = np.cumprod(gain[lo:hi])
            out[lo:hi] = product * (carry + np.cumsum(forcing[lo:hi] / product))
            carry = float(out[hi - 1])
    return out

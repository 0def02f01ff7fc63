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
instead, with no closure (misclosure reported as NaN, flag ``FLAG_NO_CLOSURE``); so is a
run whose end stop compassing rejected (an ambiguous azimuth near horizontal, say), forward
from the start stop (x and xy tools; a triad's rotation closure needs both stops).

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
from typing import Literal, NamedTuple

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.continuous.multiaxis import apsidal_components, resolve_gyro_axes
from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.run import (
    DEG_H,
    ContinuousError,
    Odometer,
    RunStops,
    compassed_stop,
    is_compassed,
    odometer_fit,
    run_bounds,
    uncompassed_stop,
    wrap_angle,
)
from pipeline.continuous.series import StoredRun
from pipeline.continuous.sigma import InclinationNoise
from pipeline.continuous.stations import ContinuousResult, run_result
from pipeline.continuous.store import CHUNK_ROWS, ColumnStore, chunks, savgol_range, savgol_span
from pipeline.continuous.tables import FLAG_LARGE_MISALIGNMENT, FLAG_NEAR_VERTICAL
from pipeline.earth.frames import OMEGA_EARTH, FloatArray, sin_cos, turned_sin_cos
from pipeline.errors import EmptyTableError
from pipeline.streams import Port, as_stream

__all__ = ["integrate_continuous"]

_COLUMNS = ("time", "md", "station", "acc_x", "acc_y", "acc_z", "position")
"""the samples' columns kept in the store (the stop positions: for the strapdown's stops only)"""


def integrate_continuous(
    samples: Port,
    stops: pa.Table,
    latitude: float,
    options: ContinuousOptions,
    rows: int = CHUNK_ROWS,
) -> ContinuousResult:
    """Integrate the azimuth of the moving run between its two compassed stops (x and xy
    tools here; xyz: :mod:`pipeline.continuous.strapdown`). The samples (a table or a stream
    of record batches) are read once into a column store (on disk past 24 MiB) and
    integrated ``rows`` at a time; the full-rate series comes back as a stream read from
    that store."""
    stream = as_stream(samples)
    axes = resolve_gyro_axes(stream.column_names, options.gyro_axes)
    if "md" not in stream.column_names:
        raise ContinuousError("continuous integration needs the odometer MD column")
    if "station" not in stream.column_names:
        raise ContinuousError("continuous integration needs the station markers of the stops")
    store = ColumnStore()
    gyros = [f"gyro_{a}" for a in axes]
    kept = (*_COLUMNS, *gyros) if axes == "xyz" else (*_COLUMNS[:-1], *gyros)
    names = [n for n in kept if n in stream.column_names]
    if store.add_batches(stream, names) == 0:
        raise EmptyTableError("samples", "a continuous run needs samples")
    begin, end, first_id, last_id = run_bounds(store, rows)
    # an x or xy run whose end stop compassing rejected is integrated from the start alone
    open_end = axes != "xyz" and not is_compassed(stops, last_id)
    finish = (
        uncompassed_stop(float(store.floats("md", end, end + 1)[0]))
        if open_end
        else compassed_stop(stops, last_id)
    )
    ends = compassed_stop(stops, first_id), finish
    odometer = odometer_fit(store, begin, end, options.odometer_window, rows)
    if axes != "xyz":
        run = _apsidal_run(odometer, axes == "xy", ends, open_end, latitude, options)
    else:
        run = _strapdown(odometer, ends, end, latitude, options)
    return run_result(run, ends, options)


def _strapdown(
    odometer: Odometer, ends: RunStops, end: int, latitude: float, options: ContinuousOptions
) -> StoredRun:
    """A three-axis run: the strapdown attitude over the samples read whole (its running
    product of rotations is not chunked), its angles stored like a single-axis run's."""
    from pipeline.continuous.strapdown import strapdown_run  # on use: loads scipy.spatial

    store, begin = odometer.store, odometer.begin
    names = [n for n in (*_COLUMNS, "gyro_x", "gyro_y", "gyro_z") if n in store]
    table = pa.table({n: store.floats(n, 0, store.rows(n)) for n in names})
    sd = strapdown_run(table, ends, (begin, end), latitude, options)
    for name, values in (("inc", sd.inc), ("azi", sd.azi), ("toolface", sd.toolface)):
        store.write(name, 0, values)
    store.write("flags", 0, sd.flags)
    store.write("held", 0, np.zeros(odometer.size, dtype=np.int8))
    # I carries the stops' accelerometer bias, no per-sample noise (gyro-driven)
    noise = InclinationNoise(
        dt=odometer.dt, accel=0.0, odometer=0.0, odometer_points=None, inc_rate_points=None
    )
    # azimuth errors to first order as a two-axis tool's (δ = 0)
    return StoredRun(odometer, latitude, options.closure, False, noise, "azi", sd.misclosure)


def _apsidal_run(
    odometer: Odometer,
    two_axis: bool,
    ends: RunStops,
    open_end: bool,
    latitude: float,
    options: ContinuousOptions,
) -> StoredRun:
    """Ȧ from the high-side rate of a single-axis (x) or two-axis (xy) tool over the run,
    closed on the end stop, integrated back from it, or (``open_end``: the end stop not
    compassed) from the start stop with no closure, a chunk of ``odometer.rows`` samples
    at a time: each pass reads the previous pass's azimuth and İ from the store (with the
    overlap its filters need) and integrates from the azimuth the chunk before ended on."""
    store, size, dt = odometer.store, odometer.size, odometer.dt
    start, finish = ends
    window = max(5, round(options.inc_rate_window / dt) | 1)
    smooth = size > window
    phi = np.radians(latitude)
    oc, os_ = OMEGA_EARTH * np.cos(phi), OMEGA_EARTH * np.sin(phi)
    vertical_stop = np.sin(np.radians(options.vertical_below))
    backward = not open_end and bool(
        np.sin(np.radians(start["inc"])) < vertical_stop
        and np.sin(np.radians(finish["inc"])) >= vertical_stop
    )
    # a run starting near vertical is tied to the inclined end stop and integrated back in time
    tie = float(np.radians((finish if backward else start)["azi"]))
    for n in range(options.passes):
        previous = None if n == 0 else str((n - 1) % 2)
        last = n == options.passes - 1
        # İ from the inclination (x) or from r (xy), h from the toolface (xy); both stored
        # last, with their half-angle tangents for the budget (the inclination, and an x
        # tool's toolface, stored only, from their tangents)
        wanted: tuple[_Wanted, _Wanted] = (
            ("half", "angle" if two_axis else "half")
            if last
            else ("", "angle")
            if two_axis
            else ("half", "")
        )
        carry = tie  # azimuth of the sample integrated last
        for a, b in chunks(0, size, odometer.rows, reverse=backward):
            # the chunk, and the sample integrated before it (first chunk: none)
            sa, sb = (a, min(b + 1, size)) if backward else (max(a - 1, 0), b)
            lo, hi = savgol_span(0, size, sa, sb, window) if smooth else (sa - 1, sb + 1)
            lo, hi = max(lo, 0), min(hi, size)
            t = odometer.time(lo, hi)
            angles = _pass_angles(odometer, lo, hi, previous, wanted)
            inc, tf = angles.inc, angles.tf
            y = store.floats("gyro_x", odometer.begin + lo, odometer.begin + hi) * DEG_H
            seg = slice(sa - lo, sb - lo)
            if not two_axis:  # single axis: h from the gyro at misalignment δ = ψ, and İ
                high, attitude = y, angles
                inc_rate = (
                    savgol_range(inc, lo, sa, sb, window, 2, (1,), dt)[0]
                    if smooth
                    else np.gradient(inc, t)[seg]
                )
            else:  # two axes: h and r by the toolface; İ from r after the first pass (below)
                y_right = store.floats("gyro_y", odometer.begin + lo, odometer.begin + hi) * DEG_H
                high, right = apsidal_components(y, y_right, tf)
                zeros = np.zeros(hi - lo)
                attitude = angles._replace(tf=zeros, sin_tf=zeros, cos_tf=np.ones(hi - lo))
                inc_rate = _previous(store, "inc_rate", previous, sa, sb)
            order = slice(None, None, -1) if backward else slice(None)
            guess = None if previous is None else store.floats(f"azi{previous}", sa, sb)[order]
            index = np.arange(sa, sb)
            azi, flags, held = (
                x[order]
                for x in _integrate(
                    t[seg][order],
                    high[seg][order],
                    _Angles(*(x[seg][order] for x in attitude)),
                    inc_rate[order],
                    carry,
                    oc,
                    os_,
                    options,
                    guess,
                    rest=((index == 0) | (index == size - 1))[order],
                    # each chunk's share of the run's error bound: the chunks' errors add up
                    tolerance=_NEWTON_TOLERANCE * (sb - sa) / size,
                )
            )
            own = slice(a - sa, b - sa)  # the chunk's samples within the segment
            carry = float(azi[own][0] if backward else azi[own][-1])
            store.write(f"azi{n % 2}", a, azi[own])
            if not last:  # İ for the next pass (the budget takes its own)
                if two_axis:  # İ = r + Ω cos φ sin A, measured, not differentiated
                    inc_rate = right[seg] + oc * sin_cos(azi.astype(np.float64, copy=False))[0]
                store.write(f"inc_rate{n % 2}", a, inc_rate[own])
            else:  # and the half-angle tangents, whose sines and cosines the budget takes
                for name, values in (
                    ("inc", inc[seg]),
                    ("inc_half", angles.inc_half[seg]),
                    ("toolface", tf[seg]),
                    *(() if two_axis else [("toolface_half", angles.tf_half[seg])]),
                    ("flags", flags),
                    ("held", held.astype(np.int8)),
                ):
                    store.write(name, a, values[own])
    azi_column = f"azi{(options.passes - 1) % 2}"
    if backward or open_end:  # one usable tie only: no closure
        misclosure = float("nan")
    else:
        end_azi = store.floats(azi_column, size - 1, size)
        misclosure = float(wrap_angle(end_azi[0] - np.radians(finish["azi"])))
    noise = InclinationNoise(
        dt=dt,
        accel=options.acc_noise / (60.0 * np.sqrt(dt)),  # (m/s)/√h → per sample
        odometer=options.odometer_noise,
        odometer_points=odometer.points,
        inc_rate_points=window if smooth else None,
    )
    shift = misclosure if options.closure and not (backward or open_end) else 0.0
    return StoredRun(
        odometer,
        latitude,
        options.closure and not open_end,
        backward,
        noise,
        azi_column,
        misclosure,
        shift,
        misaligned=not two_axis,  # δ = ψ, the toolface column
        open_end=open_end,
        halves=True,
    )


def _previous(store: ColumnStore, name: str, previous: str | None, lo: int, hi: int) -> FloatArray:
    """Column ``name`` of the previous pass at run samples ``lo``…``hi − 1`` (zeros before
    the first pass)."""
    return np.zeros(hi - lo) if previous is None else store.floats(f"{name}{previous}", lo, hi)


_Wanted = Literal["", "angle", "half"]
"""What :func:`_polar` gives of an angle: nothing (its sine and cosine only), the angle
(arctan2), or the tangent of its half and the angle from it (``2·atan``: within 2 ulp of
arctan2, at half its CPU — NumPy's float64 arctan is vectorised here, arctan2 not)."""


class _Angles(NamedTuple):
    """Inclination and toolface (rad) of run samples (empty where a pass does not need the
    angle), their sines and cosines, and the tangents of their halves."""

    inc: FloatArray
    tf: FloatArray
    sin_i: FloatArray
    cos_i: FloatArray
    sin_tf: FloatArray
    cos_tf: FloatArray
    inc_half: FloatArray
    """tan(I/2) (empty where not wanted)"""
    tf_half: FloatArray
    """tan(ψ/2) (likewise)"""


def _pass_angles(
    odometer: Odometer, lo: int, hi: int, previous: str | None, wanted: tuple[_Wanted, _Wanted]
) -> _Angles:
    """Inclination and toolface (rad) at run samples ``lo``…``hi − 1`` with the tool's
    acceleration removed, from the previous pass's İ and Ȧ (none before the first);
    ``wanted``: what of the inclination and of the toolface angle is needed (:data:`_Wanted`:
    each angle costs an arctan or arctan2, their sines and cosines come without)."""
    store, begin = odometer.store, odometer.begin
    gx, gy, gz = (store.floats(f"acc_{a}", begin + lo, begin + hi) for a in "xyz")
    accel = odometer.column("accel", lo, hi)
    if previous is None:  # nothing across the axis to remove yet
        return _inclination_toolface(gx, gy, gz, accel, wanted)
    inc_rate = store.floats(f"inc_rate{previous}", lo, hi)
    # the gradient at the range's ends needs one sample beyond it
    wlo, whi = max(lo - 1, 0), min(hi + 1, odometer.size)
    wide = np.gradient(store.floats(f"azi{previous}", wlo, whi), odometer.time(wlo, whi))
    azi_rate = wide[lo - wlo : lo - wlo + hi - lo]
    speed = odometer.column("speed", lo, hi)
    return _inclination_toolface(gx, gy, gz, accel, wanted, (speed, inc_rate, azi_rate))


def _inclination_toolface(
    gx: FloatArray,
    gy: FloatArray,
    gz: FloatArray,
    accel: FloatArray,
    wanted: tuple[_Wanted, _Wanted],
    across: tuple[FloatArray, FloatArray, FloatArray] | None = None,
) -> _Angles:
    """Inclination and gravity toolface of frame x (rad; ``wanted``: :func:`_pass_angles`)
    from the accelerometers (m/s²) with the tool's acceleration removed: along the axis the
    odometer's ``accel`` (m/s²), across it v·(İ·hs + sin I·Ȧ·rs) from ``across``: the speed
    (m/s) and the current İ and Ȧ (rad/s; None: zero)."""
    axial = gz + accel
    if across is None:
        tf, tf_half, sin_tf, cos_tf, transverse = _polar(gy, -gx, wanted[1])
    else:  # the first estimate's toolface and inclination: their sines and cosines only
        speed, inc_rate, azi_rate = across
        sin_tf, cos_tf, transverse = _unit(gy, -gx)
        cross_h = speed * inc_rate
        cross_r = speed * _unit(transverse, axial)[0] * azi_rate
        cx = gx + cross_h * cos_tf + cross_r * sin_tf
        cy = gy - cross_h * sin_tf + cross_r * cos_tf
        tf, tf_half, sin_tf, cos_tf, transverse = _polar(cy, -cx, wanted[1])
    inc, inc_half, sin_i, cos_i, _ = _polar(transverse, axial, wanted[0])
    return _Angles(inc, tf, sin_i, cos_i, sin_tf, cos_tf, inc_half, tf_half)


_HALF_REACH = 1e16
"""Largest half-angle tangent :func:`_polar` takes as computed: beyond, the angle is ±π to
its rounding (the tangent of the rounded π/2 is 1.6e16), and its square would overflow."""


def _polar(
    y: FloatArray, x: FloatArray, wanted: _Wanted
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """The angle ``arctan2(y, x)`` and the tangent of its half as ``wanted`` (:data:`_Wanted`;
    else empty), and :func:`_unit`'s sine, cosine and radius. The tangent from the radius in hand,
    ``y/(r + x)`` (x ≥ 0) or ``(r − x)/y`` (x < 0; neither form cancels); beyond
    :data:`_HALF_REACH` or NaN (r 0, not finite or NaN; an angle of ±π) from the angle, there
    by arctan2."""
    sin, cos, r = _unit(y, x)
    if wanted != "half":
        return np.arctan2(y, x) if wanted else np.empty(0), np.empty(0), sin, cos, r
    with np.errstate(invalid="ignore", divide="ignore"):
        half = np.divide(y, np.add(r, x))
        back = np.flatnonzero(x < 0)
        half[back] = (r[back] - x[back]) / y[back]
    angle = np.arctan(half)
    angle *= 2.0
    if half.size and not max(float(half.max()), -float(half.min())) <= _HALF_REACH:  # NaN: not
        odd = np.flatnonzero(~(np.abs(half) <= _HALF_REACH))
        angle[odd] = np.arctan2(y[odd], x[odd])
        half[odd] = np.tan(angle[odd] / 2)
    return angle, half, sin, cos, r


def _unit(y: FloatArray, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The sine and cosine of ``arctan2(y, x)`` and ``r = √(x² + y²)``: the sine and cosine
    as y/r and x/r (the trig functions' values to an ulp or two, at a tenth of their cost;
    by the trig functions where r is 0, not finite or NaN)."""
    r = np.sqrt(x * x + y * y)
    with np.errstate(invalid="ignore", divide="ignore"):
        sin, cos = y / r, x / r
    if r.size and float(r.min()) > 0 and float(r.max()) < np.inf:  # (NaN: neither)
        return sin, cos, r
    odd = np.flatnonzero(~((r > 0) & (r < np.inf)))
    if odd.size:
        angle = np.arctan2(y[odd], x[odd])
        sin[odd], cos[odd] = np.sin(angle), np.cos(angle)
    return sin, cos, r


def _integrate(
    t: FloatArray,
    y: FloatArray,
    attitude: _Angles,
    inc_rate: FloatArray,
    azi0: float,
    oc: float,
    os_: float,
    options: ContinuousOptions,
    guess: FloatArray | None = None,
    *,
    rest: NDArray[np.bool_],
    tolerance: float = 1e-12,
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.bool_]]:
    """Heun (trapezoid) integration of Ȧ from the high-side gyro component ``y`` (rad/s) at
    the ``attitude``'s inclination and misalignment δ (its toolface); flags.

    Each step maps ``A_k`` to ``A_{k+1} = A_k + Δt/2·(Ȧ_k(A_k) + Ȧ_{k+1}(A_k + Δt·Ȧ_k(A_k)))``.
    The recursion is solved for all samples at once by Newton's method on the whole series
    (:func:`_heun_series`), from ``guess`` (rad: e.g. a previous pass's azimuth; default the
    start azimuth throughout); ``rest``: the samples on a stop, never held; ``tolerance``
    (rad): the error bound left in the series."""
    sin_i, cos_i = attitude.sin_i, attitude.cos_i
    sin_d, cos_d = attitude.sin_tf, attitude.cos_tf
    flags = np.zeros(t.size, dtype=np.int64)
    vertical = sin_i < np.sin(np.radians(options.vertical_below))
    flags[vertical] |= FLAG_NEAR_VERTICAL
    misaligned = np.abs(cos_d) < np.cos(np.radians(options.max_misalignment))
    flags[misaligned & ~vertical] |= FLAG_LARGE_MISALIGNMENT
    held = vertical | misaligned
    held[rest] = False  # the stops themselves: tool at rest
    usable = ~held & ~vertical  # a stop at rest is not held, but Ȧ is still singular there
    # Ȧ = const + by_cos·cos A + by_sin·sin A, from h = (y − r sin δ)/cos δ, r = −Ω cos φ sin A + İ;
    # 0 where not usable (there sin I and cos δ taken as 1: finite, then zeroed)
    off = ~usable
    some_off = bool(off.any())
    sin_u, cos_u = np.ascontiguousarray(sin_i), np.ascontiguousarray(cos_d)  # quicker divisors
    if some_off:
        sin_u, cos_u = np.array(sin_i), np.array(cos_d)
        sin_u[off] = cos_u[off] = 1.0
    const = (os_ * sin_i - (y - inc_rate * sin_d) / cos_u) / sin_u
    by_cos = oc * cos_i / sin_u
    by_sin = -oc * sin_d / cos_u / sin_u
    if some_off:
        const[off] = by_cos[off] = by_sin[off] = 0.0

    def rate(sin_a: FloatArray, cos_a: FloatArray, k: slice) -> tuple[FloatArray, FloatArray]:
        """Ȧ and ∂Ȧ/∂A (rad/s, 1/s) of the samples ``k`` at azimuths of sine ``sin_a`` and
        cosine ``cos_a`` (0 where held)."""
        # in place, the operations of const + by_cos·cos A + by_sin·sin A, by_sin·cos A −
        # by_cos·sin A in their order: fewer temporaries, a tenth less CPU
        slope = by_sin[k] * cos_a
        product = np.multiply(by_cos[k], sin_a)
        slope -= product
        value = by_cos[k] * cos_a
        value += const[k]
        value += np.multiply(by_sin[k], sin_a, out=product)
        return value, slope

    start = np.full(t.size, azi0) if guess is None else guess.copy()
    start[0] = azi0
    feedback = np.sqrt(by_cos * by_cos + by_sin * by_sin)  # bounds |∂Ȧ/∂A| and |∂²Ȧ/∂A²|
    return _heun_series(np.diff(t), rate, feedback, start, tolerance), flags, held


RateFunction = Callable[[FloatArray, FloatArray, slice], tuple[FloatArray, FloatArray]]
"""Ȧ and ∂Ȧ/∂A of a slice of the samples at azimuths of given sines and cosines."""

_NEWTON_TOLERANCE = 1e-12
"""rad: bound of the error left in a converged series."""
_NEWTON_ITERATIONS = 40
_SCAN_SPAN = 16.0
"""Largest ∑|ln gain| over one cumulative-product segment of :func:`_affine_recursion`."""


def _heun_series(
    step: FloatArray,
    rate: RateFunction,
    feedback: FloatArray,
    azi: FloatArray,
    tolerance: float = _NEWTON_TOLERANCE,
) -> FloatArray:
    """The Heun recursion's azimuths (rad) from ``azi[0]`` over steps ``step`` (s), solved
    as one system by Newton's method from the first guess ``azi`` (overwritten): each
    iteration evaluates every step's residual and the step's derivative at once and solves
    the linearised recursion ``δ_{k+1} = g_k δ_k + res_k`` by cumulative products.

    Ȧ depends on A only through the Earth-rate terms, so few iterations are needed:
    with ``feedback`` a bound of |∂Ȧ/∂A| and |∂²Ȧ/∂A²| per sample (1/s) and ``L`` its
    integral over the run, an iteration leaves an error of at most ``L·e^L·δ²`` after a
    correction of at most δ (quadratic convergence); it stops when that is below
    ``tolerance`` (rad)."""
    half = step / 2
    reach = float(np.sum(np.abs(step) * np.maximum(feedback[:-1], feedback[1:])))
    # each gain 1 + Δt/2·(∂Ȧ_k + ∂Ȧ_next·(1 + Δt·∂Ȧ_k)) is within Δt·F·(1 + Δt·F/2) of 1 (F:
    # the larger feedback of the step), so ∑|ln gain| < 2·reach: below a segment's span
    # when reach is small (its every term too), and the gains' scan is not needed
    bounded = reach < _SCAN_SPAN / 64
    growth = reach * float(np.exp(min(reach, 700.0)))
    # the azimuths' sines and cosines: once by the trig functions (a constant first guess:
    # of one value), then turned by each predictor step and Newton correction
    # (turned_sin_cos, within 2.3e-16 a turn: against sin and cos of the stored azimuth,
    # rounded at each turn, ≈ 2.5e-15 after the iterations' seven turns, measured)
    if azi.size and bool(np.all(azi == azi[0])):
        sin_a, cos_a = (np.full(azi.size, x[0]) for x in sin_cos(azi[:1]))
    else:
        sin_a, cos_a = sin_cos(azi)
    for _ in range(_NEWTON_ITERATIONS):
        f, df = rate(sin_a, cos_a, slice(None))
        lead = step * f[:-1]
        predicted = lead + azi[:-1]
        f_next, df_next = rate(
            *turned_sin_cos(sin_a[:-1], cos_a[:-1], lead, predicted), slice(1, None)
        )
        # in place (the same operations in the same order, commuted at most): residual
        # A_k + Δt/2·(f_k + f_next) − A_{k+1}, gain 1 + Δt/2·(df_k + df_next·(1 + Δt·df_k))
        residual = np.add(f[:-1], f_next, out=f_next)
        residual *= half
        residual += azi[:-1]
        residual -= azi[1:]
        gain = np.multiply(step, df[:-1], out=predicted)
        gain += 1.0
        gain *= df_next
        gain += df[:-1]
        gain *= half
        gain += 1.0
        correction = _affine_recursion(gain, residual, bounded)
        azi[1:] += correction
        largest = float(max(np.max(correction), -np.min(correction)))
        if not growth * largest**2 > tolerance:  # (NaN input propagates)
            return azi
        sin_a[1:], cos_a[1:] = turned_sin_cos(sin_a[1:], cos_a[1:], correction, azi[1:])
    raise ContinuousError(
        f"the azimuth integration did not converge in {_NEWTON_ITERATIONS} Newton iterations "
        f"(last correction {largest:.3g} rad)"
    )


def _affine_recursion(gain: FloatArray, forcing: FloatArray, bounded: bool = False) -> FloatArray:
    """``x_1 … x_n`` of ``x_{k+1} = gain_k·x_k + forcing_k`` from ``x_0 = 0``: within a
    segment ``x = P·(x_start + cumsum(forcing/P))`` with P the running product of the gains,
    segments cut where the gains' log-variation reaches ``_SCAN_SPAN`` (P stays in range;
    ``bounded``: the gains positive and their log-variation known to be below that, one
    segment without a scan)."""
    if bounded:
        cuts = np.empty(0, dtype=np.intp)
    elif (least := float(np.min(gain))) > 0 and gain.size * max(
        np.log(float(np.max(gain))), -np.log(least)
    ) < _SCAN_SPAN / 2:
        cuts = np.empty(0, dtype=np.intp)  # the whole variation is below one segment's
    else:
        with np.errstate(divide="ignore"):
            variation = np.cumsum(np.nan_to_num(np.abs(np.log(np.abs(gain))), nan=0.0))
        cuts = np.searchsorted(variation, np.arange(_SCAN_SPAN, variation[-1], _SCAN_SPAN))
    out = np.empty_like(forcing)
    carry = 0.0
    for lo, hi in zip([0, *cuts], [*cuts, gain.size], strict=True):
        if hi > lo:
            product = np.cumprod(gain[lo:hi])
            running = np.divide(forcing[lo:hi], product)
            np.cumsum(running, out=running)
            if carry:  # (the first segment's 0: nothing to add)
                running += carry
            np.multiply(product, running, out=out[lo:hi])
            carry = float(out[hi - 1])
    return out

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
  A) from the start stop's azimuth.

Closure ("continuous-gyro drift"): the integrated azimuth at the end stop minus the end
stop's compassed azimuth is the misclosure; it is distributed linearly in time over the run.
A run starting near vertical (where the start stop's azimuth means nothing) is integrated
backward from the end stop instead, with no closure (misclosure reported as NaN)
and removed, which cancels a constant gyro bias exactly (its azimuth error grows linearly in
time at constant inclination). The misclosure is reported.

Near vertical (``sin I < sin(vertical_below)``) Ȧ is singular: those samples are flagged,
the azimuth is held (Ȧ = 0) through them and integration resumes after; flagged stations get
an infinite ``sigma_azi``. A held section's azimuth change is not recovered: the closure
correction then absorbs it as a linear-in-time error, so azimuths after a flagged section
are only as good as that assumption (flag ``FLAG_AFTER_VERTICAL``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field
from scipy.signal import savgol_filter

from pipeline.contracts import TableContract, column
from pipeline.earth.frames import OMEGA_EARTH
from pipeline.tables import Stations

FloatArray = NDArray[np.float64]

FLAG_NEAR_VERTICAL = 1
"""Sample/station near vertical: azimuth held, not integrated."""
FLAG_AFTER_VERTICAL = 2
"""Azimuth integrated after a held near-vertical section (closure absorbs its change)."""
FLAG_LARGE_MISALIGNMENT = 4
FLAG_NO_CLOSURE = 8
"""Integrated back from the end stop alone: the gyro bias is not removed by a closure."""
"""Gyro more than ``max_misalignment`` from the high side: h is ill-conditioned."""

_DEG_H = np.pi / 180.0 / 3600.0  # °/h → rad/s


class ContinuousError(ValueError):
    """The samples or stops do not make a continuous run."""


class ContinuousOptions(BaseModel):
    """Parameters of continuous-mode integration."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    latitude: float | None = Field(
        None, ge=-90, le=90, description="site latitude, deg (default: the well's)"
    )
    spacing: float = Field(10.0, gt=0, description="MD spacing of the output stations, m")
    vertical_below: float = Field(
        3.0, gt=0, lt=90, description="inclination below which samples are flagged, deg"
    )
    odometer_window: float = Field(
        2.0,
        gt=0,
        description="s, window of the cubic fit differentiating the odometer "
        "(a noise-free odometer needs no smoothing: set it small)",
    )
    inc_rate_window: float = Field(
        1.0, gt=0, description="Savitzky–Golay window of the İ smoothing, s"
    )
    max_misalignment: float = Field(
        60.0, gt=0, lt=90, description="|δ| above which a sample is flagged, deg"
    )
    closure: bool = Field(True, description="remove the misclosure linearly in time")
    passes: int = Field(
        2, ge=1, le=5, description="passes removing the tool's acceleration (1: along-axis only)"
    )


class ContinuousStations(Stations):
    """Stations of a continuous survey resampled at a fixed MD spacing (azimuth true north)."""

    time: float = column(unit="s", description="time at the station")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth, true north"
    )
    sigma_inc: float = column(unit="deg", ge=0, description="σ of inc (from the stops)")
    sigma_azi: float = column(
        unit="deg", ge=0, finite=False, description="σ of azi (stops, time-weighted)"
    )
    flags: int = column(unit=None, ge=0, description="bit flags (FLAG_* of the module)")


class ContinuousSeries(TableContract):
    """Full-rate series of the moving run (azimuth true north, closure applied)."""

    time: float = column(unit="s", monotonic="strict", description="time since the start")
    md: float = column(unit="m", description="odometer MD")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth, true north"
    )
    toolface: float = column(unit="deg", description="gravity toolface of frame x (δ), deg")
    flags: int = column(unit=None, ge=0, description="bit flags (FLAG_* of the module)")


@dataclass(frozen=True)
class ContinuousResult:
    stations: pa.Table
    series: pa.Table
    misclosure: float
    """Integrated minus end-stop azimuth before correction, deg."""


def _column(table: pa.Table, name: str) -> FloatArray:
    values: FloatArray = np.asarray(
        table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64
    )
    return values


def _wrap(angle: FloatArray | float) -> FloatArray:
    wrapped: FloatArray = (np.asarray(angle, dtype=np.float64) + np.pi) % (2 * np.pi) - np.pi
    return wrapped


def _run_bounds(station: FloatArray) -> tuple[int, int, int, int]:
    """Indices (last start-stop sample, first end-stop sample) and their station ids."""
    moving = np.isnan(station)
    stopped = np.flatnonzero(~moving)
    if stopped.size == 0:
        raise ContinuousError("no compassing stop in the samples (station markers all null)")
    first_stop = int(stopped[0])
    after = np.flatnonzero(moving[first_stop:])
    if after.size == 0:
        raise ContinuousError("the samples never leave the first stop")
    begin = first_stop + int(after[0]) - 1  # last sample of the start stop
    rest = np.flatnonzero(~moving[begin + 1 :])
    if rest.size == 0:
        raise ContinuousError("no compassing stop after the moving run")
    end = begin + 1 + int(rest[0])  # first sample of the end stop
    return begin, end, int(station[begin]), int(station[end])


def _stop(stops: pa.Table, station: int) -> dict[str, float]:
    ids = np.asarray(stops.column("station").to_numpy(zero_copy_only=False))
    rows = np.flatnonzero(ids == station)
    if rows.size == 0:
        raise ContinuousError(
            f"stop {station} is not among the compassed stops (rejected by compassing?)"
        )
    row = int(rows[0])
    return {
        n: float(_column(stops, n)[row]) for n in ("azi", "inc", "sigma_azi", "sigma_inc", "md")
    }


def integrate_continuous(
    samples: pa.Table, stops: pa.Table, latitude: float, options: ContinuousOptions
) -> ContinuousResult:
    """Integrate the azimuth of the moving run between its two compassed stops."""
    if "md" not in samples.column_names:
        raise ContinuousError("continuous integration needs the odometer MD column")
    station = _column(samples, "station") if "station" in samples.column_names else None
    if station is None:
        raise ContinuousError("continuous integration needs the station markers of the stops")
    begin, end, first_id, last_id = _run_bounds(station)
    start, finish = _stop(stops, first_id), _stop(stops, last_id)
    sl = slice(begin, end + 1)  # stop sample, moving samples, stop sample
    t = _column(samples, "time")[sl]
    md = _column(samples, "md")[sl]
    gx, gy, gz = (_column(samples, f"acc_{a}")[sl] for a in "xyz")
    y = _column(samples, "gyro_x")[sl] * _DEG_H
    dt = float(np.median(np.diff(t)))
    window = max(5, round(options.inc_rate_window / dt) | 1)
    # odometer noise is white per sample: differentiate a local cubic fit, never raw samples
    odo = max(7, round(options.odometer_window / dt) | 1)
    if t.size > odo:
        speed = savgol_filter(md, odo, 3, deriv=1, delta=dt)
        md_accel = savgol_filter(md, odo, 3, deriv=2, delta=dt)
    else:
        speed = np.gradient(md, t)
        md_accel = np.gradient(speed, t)
    phi = np.radians(latitude)
    oc, os_ = OMEGA_EARTH * np.cos(phi), OMEGA_EARTH * np.sin(phi)
    azi_rate = np.zeros(t.size)
    inc_rate = np.zeros(t.size)
    vertical_stop = np.sin(np.radians(options.vertical_below))
    backward = bool(
        np.sin(np.radians(start["inc"])) < vertical_stop
        and np.sin(np.radians(finish["inc"])) >= vertical_stop
    )
    for _ in range(options.passes):
        # remove the tool's acceleration: along the axis a, across it v·(İ·hs + sin I·Ȧ·rs)
        tf = np.arctan2(gy, -gx)
        inc = np.arctan2(np.hypot(gx, gy), gz + md_accel)
        cross_h = speed * inc_rate
        cross_r = speed * np.sin(inc) * azi_rate
        cx = gx + cross_h * np.cos(tf) + cross_r * np.sin(tf)
        cy = gy - cross_h * np.sin(tf) + cross_r * np.cos(tf)
        tf = np.arctan2(cy, -cx)
        inc = np.arctan2(np.hypot(cx, cy), gz + md_accel)
        inc_rate = (
            savgol_filter(inc, window, 2, deriv=1, delta=dt)
            if t.size > window
            else np.gradient(inc, t)
        )
        if backward:  # tie to the inclined end stop and integrate back in time
            rev = slice(None, None, -1)
            azi, flags, held = _integrate(
                t[rev],
                y[rev],
                inc[rev],
                inc_rate[rev],
                tf[rev],
                float(np.radians(finish["azi"])),
                oc,
                os_,
                options,
            )
            azi, flags, held = azi[rev], flags[rev], held[rev]
        else:
            azi, flags, held = _integrate(
                t, y, inc, inc_rate, tf, float(np.radians(start["azi"])), oc, os_, options
            )
        azi_rate = np.gradient(azi, t)
    weight = (t - t[0]) / (t[-1] - t[0])
    if backward:  # one usable tie only: no closure, and the start stop's azimuth is not used
        misclosure = float("nan")
    else:
        misclosure = float(_wrap(azi[-1] - np.radians(finish["azi"])))
        if options.closure:
            azi = azi - misclosure * weight
    after = (np.cumsum(held[::-1]) > 0)[::-1] if backward else np.cumsum(held) > 0
    if backward:
        flags |= FLAG_NO_CLOSURE
    flags[after & ~held] |= FLAG_AFTER_VERTICAL
    inc_deg = np.degrees(inc)
    azi_deg = np.degrees(azi) % 360.0
    series = ContinuousSeries.compiled().make_table(
        {
            "time": t,
            "md": md,
            "inc": inc_deg,
            "azi": np.where(azi_deg < 360.0, azi_deg, 0.0),
            "toolface": np.degrees(tf),
            "flags": flags,
        },
        north_reference="true",
    )
    stations = _resample(t, md, inc, azi, flags, weight, start, finish, options.spacing)
    return ContinuousResult(stations=stations, series=series, misclosure=np.degrees(misclosure))


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
) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.bool_]]:
    """Heun (trapezoid) integration of Ȧ from the high-side gyro component; flags."""
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

    def rate(k: int, a: float) -> float:
        if not usable[k]:
            return 0.0
        r = -oc * np.sin(a) + inc_rate[k]
        h = (y[k] - r * sin_d[k]) / cos_d[k]
        return float((oc * np.cos(a) * cos_i[k] + os_ * sin_i[k] - h) / sin_i[k])

    azi = np.empty(t.size)
    azi[0] = azi0
    a = float(azi[0])
    f = rate(0, a)
    for k in range(t.size - 1):
        step = t[k + 1] - t[k]
        predicted = a + step * f
        f_next = rate(k + 1, predicted)
        a = a + step / 2 * (f + f_next)
        f = rate(k + 1, a)
        azi[k + 1] = a
    return azi, flags, held


def _resample(
    t: FloatArray,
    md: FloatArray,
    inc: FloatArray,
    azi: FloatArray,
    flags: NDArray[np.int64],
    weight: FloatArray,
    start: dict[str, float],
    finish: dict[str, float],
    spacing: float,
) -> pa.Table:
    """Stations every ``spacing`` m of odometer MD from the start stop, plus the end stop."""
    keep = np.concatenate([[True], np.diff(md) > 0])  # strictly increasing MD samples
    keep &= md >= np.maximum.accumulate(md)
    m = md[keep]
    grid = np.arange(m[0], m[-1], spacing)
    if m[-1] - grid[-1] > 1e-6 * spacing:
        grid = np.append(grid, m[-1])
    else:
        grid[-1] = m[-1]

    def at(x: FloatArray) -> FloatArray:
        values: FloatArray = np.interp(grid, m, x[keep])
        return values

    # flags of a station: union over the samples closest to it
    index = np.clip(np.searchsorted(m, grid), 0, m.size - 1)
    station_flags = flags[keep][index]
    w = at(weight)
    sigma_azi = np.hypot((1 - w) * start["sigma_azi"], w * finish["sigma_azi"])
    sigma_azi = np.where(station_flags & FLAG_NEAR_VERTICAL, np.inf, sigma_azi)
    sigma_inc = np.hypot((1 - w) * start["sigma_inc"], w * finish["sigma_inc"])
    azi_deg = np.degrees(at(np.unwrap(azi))) % 360.0
    return ContinuousStations.compiled().make_table(
        {
            "md": grid,
            "inc": np.degrees(at(inc)),
            "azi": np.where(azi_deg < 360.0, azi_deg, 0.0),
            "time": at(t),
            "sigma_inc": sigma_inc,
            "sigma_azi": sigma_azi,
            "flags": station_flags,
        },
        north_reference="true",
    )

"""The outputs of an integrated continuous run: its full-rate series, and stations every
``spacing`` m of odometer MD (:func:`station_times`) with their predicted σ
(:mod:`pipeline.continuous.sigma`)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.run import ContinuousError, Odometer, RunStops
from pipeline.continuous.sigma import (
    AccelErrors,
    GyroNoise,
    RunGeometry,
    azimuth_budget,
    inclination_sigma,
)
from pipeline.continuous.tables import (
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_NEAR_VERTICAL,
    ContinuousSeries,
    ContinuousStations,
)
from pipeline.earth.frames import FloatArray

__all__ = ["ContinuousResult", "run_result", "station_times"]

_MERGE = 0.01
"""A station closer than this fraction of the spacing to the end stop is the end stop."""


@dataclass(frozen=True)
class ContinuousResult:
    """An integrated run: its stations (ContinuousStations) and full-rate series
    (ContinuousSeries)."""

    stations: pa.Table
    series: pa.Table
    misclosure: float
    """Integrated minus end-stop azimuth before correction, deg."""


def run_result(
    odometer: Odometer,
    toolface: FloatArray,
    flags: NDArray[np.int64],
    stops: RunStops,
    options: ContinuousOptions,
    run: RunGeometry,
    misclosure: float,
) -> ContinuousResult:
    """The full-rate series and the resampled stations of an integrated run: toolface and
    misclosure rad, the compassed (start, end) stops (deg)."""
    t = odometer.time
    inc_deg = np.degrees(run.inc)
    azi_deg = np.degrees(run.azi) % 360.0
    series = ContinuousSeries.compiled().make_table(
        {
            "time": t,
            "md": odometer.reading,
            "inc": inc_deg,
            "azi": np.where(azi_deg < 360.0, azi_deg, 0.0),
            "toolface": np.degrees(toolface),
            "flags": flags,
        },
        north_reference="true",
    )
    stations = _resample(odometer, flags, stops, options, run)
    return ContinuousResult(stations=stations, series=series, misclosure=np.degrees(misclosure))


def station_times(
    odometer: Odometer, first: float, last: float, spacing: float
) -> tuple[FloatArray, FloatArray]:
    """MDs every ``spacing`` m from the start stop's MD ``first`` to the end stop's ``last``
    (included; the last one before it merged into it if closer than 1 % of the spacing), m,
    and the times the tool passed them, s.

    The end stations are the stops: the compassed MD (median over the dwell), at the run's
    first and last sample. Between them a station's time is where the odometer's cubic fit
    passes its MD — never the raw odometer, whose samples at a running maximum are those with
    positive noise (MDs biased deep). The fit rises while the tool moves but wiggles by its
    own noise where the tool is nearly at rest (ends of the speed ramps); the mean of its
    running maximum and its backward running minimum rises everywhere and, unlike either
    alone, is biased neither up nor down there."""
    if not last > first:
        raise ContinuousError(
            f"the end stop's MD ({last:.3f} m) is not deeper than the start stop's "
            f"({first:.3f} m): continuous runs are integrated down the hole"
        )
    t, fit = odometer.time, odometer.md
    track = (np.maximum.accumulate(fit) + np.minimum.accumulate(fit[::-1])[::-1]) / 2
    rising = np.concatenate([[True], np.diff(track) > 0])
    grid = np.arange(first, last, spacing)
    if last - grid[-1] > _MERGE * spacing:
        grid = np.append(grid, last)
    else:
        grid[-1] = last
    times = np.interp(grid, track[rising], t[rising])
    times[0], times[-1] = t[0], t[-1]
    return grid, times


def _resample(
    odometer: Odometer,
    flags: NDArray[np.int64],
    stops: RunStops,
    options: ContinuousOptions,
    run: RunGeometry,
) -> pa.Table:
    """Stations every ``spacing`` m of odometer MD from the start stop, plus the end stop."""
    start, finish = stops
    t = odometer.time
    grid, times = station_times(odometer, start["md"], finish["md"], options.spacing)

    def at(x: FloatArray) -> FloatArray:
        values: FloatArray = np.interp(times, t, x)
        return values

    # flags of a station: those of the first sample at or after it
    station_flags = flags[np.clip(np.searchsorted(t, times), 0, t.size - 1)]
    noise = GyroNoise(
        arw=options.gyro_arw,
        bias=options.gyro_bias,
        bias_trend=options.gyro_bias_trend,
        bias_instability=options.gyro_bias_instability,
        correlation_time=options.gyro_correlation_time,
        rate_random_walk=options.gyro_rate_random_walk,
        scale_factor=options.gyro_scale_factor,
        g_sensitivity=options.gyro_g_sensitivity,
        misalignment=options.gyro_misalignment,
    )
    accel = AccelErrors(bias=options.acc_bias, misalignment=options.acc_misalignment * 1e-3)
    sigma_ends = float(np.radians(start["sigma_azi"])), float(np.radians(finish["sigma_azi"]))
    budget = azimuth_budget(run, times, *sigma_ends, noise, accel)
    undefined = station_flags & (FLAG_NEAR_VERTICAL | FLAG_AZIMUTH_UNDEFINED)
    sigma_azi = np.where(undefined, np.inf, np.degrees(budget.sigma))
    assert run.inc_noise is not None
    inc = at(run.inc)
    sigma_inc = inclination_sigma(inc, run.inc_noise, accel)
    # the end stations are the stops, at rest: no acceleration removed from their inclination
    ends = [0, -1]
    sigma_inc[ends] = inclination_sigma(inc[ends], replace(run.inc_noise, odometer=0.0), accel)
    azi_deg = np.degrees(at(np.unwrap(run.azi))) % 360.0
    return ContinuousStations.compiled().make_table(
        {
            "md": grid,
            "inc": np.degrees(inc),
            "azi": np.where(azi_deg < 360.0, azi_deg, 0.0),
            "time": times,
            "sigma_inc": np.degrees(sigma_inc),
            "sigma_azi": sigma_azi,
            "flags": station_flags,
        },
        north_reference="true",
    )

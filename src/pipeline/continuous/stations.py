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
from pipeline.continuous.series import StoredRun, azimuth_degrees, series_stream
from pipeline.continuous.sigma import (
    AccelErrors,
    GyroNoise,
    azimuth_budget,
    inclination_sigma,
)
from pipeline.continuous.store import CarriedUnwrap, Interpolation, chunks
from pipeline.continuous.tables import (
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_NEAR_VERTICAL,
    ContinuousStations,
)
from pipeline.earth.frames import FloatArray
from pipeline.streams import TableStream

__all__ = ["ContinuousResult", "run_result", "station_times"]

_MERGE = 0.01
"""A station closer than this fraction of the spacing to the end stop is the end stop."""


@dataclass(frozen=True)
class ContinuousResult:
    """An integrated run: its stations (ContinuousStations) and full-rate series
    (ContinuousSeries, a stream read from the run's store)."""

    stations: pa.Table
    series: TableStream
    misclosure: float
    """Integrated minus end-stop azimuth before correction, deg."""


def run_result(run: StoredRun, stops: RunStops, options: ContinuousOptions) -> ContinuousResult:
    """The full-rate series and the resampled stations of an integrated run (the compassed
    (start, end) stops, deg)."""
    stations = _resample(run, stops, options)
    return ContinuousResult(
        stations=stations, series=series_stream(run), misclosure=np.degrees(run.misclosure)
    )


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
    alone, is biased neither up nor down there. Read a chunk at a time: the running maximum
    forward, the running minimum backward, then the crossings forward."""
    if not last > first:
        raise ContinuousError(
            f"the end stop's MD ({last:.3f} m) is not deeper than the start stop's "
            f"({first:.3f} m): continuous runs are integrated down the hole"
        )
    store, size, rows = odometer.store, odometer.size, odometer.rows
    top = -np.inf
    for a, b in chunks(0, size, rows):
        running = np.maximum.accumulate(np.concatenate([[top], odometer.column("md", a, b)]))
        store.write("track", a, running[1:])
        top = float(running[-1])
    bottom = np.inf
    for a, b in chunks(0, size, rows, reverse=True):
        fit = odometer.column("md", a, b)[::-1]
        running = np.minimum.accumulate(np.concatenate([[bottom], fit]))[1:][::-1]
        store.write("track", a, (store.floats("track", a, b) + running) / 2)
        bottom = float(running[0])
    grid = np.arange(first, last, spacing)
    if last - grid[-1] > _MERGE * spacing:
        grid = np.append(grid, last)
    else:
        grid[-1] = last
    crossing = Interpolation(grid, 1)
    previous = -np.inf
    for a, b in chunks(0, size, rows):
        track = store.floats("track", a, b)
        rising = np.diff(np.concatenate([[previous], track])) > 0
        crossing.feed(track[rising], odometer.time(a, b)[rising])
        previous = float(track[-1])
    times = crossing.result()[0]
    times[0], times[-1] = odometer.time(0, 1)[0], odometer.time(size - 1, size)[0]
    return grid, times


def _resample(run: StoredRun, stops: RunStops, options: ContinuousOptions) -> pa.Table:
    """Stations every ``spacing`` m of odometer MD from the start stop, plus the end stop."""
    start, finish = stops
    grid, times = station_times(run.odometer, start["md"], finish["md"], options.spacing)
    inc, azi, station_flags = _at_stations(run, times)
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
    sigma_inc = inclination_sigma(inc, run.inc_noise, accel)
    # the end stations are the stops, at rest: no acceleration removed from their inclination
    ends = [0, -1]
    sigma_inc[ends] = inclination_sigma(inc[ends], replace(run.inc_noise, odometer=0.0), accel)
    return ContinuousStations.compiled().make_table(
        {
            "md": grid,
            "inc": np.degrees(inc),
            "azi": azimuth_degrees(azi),
            "time": times,
            "sigma_inc": np.degrees(sigma_inc),
            "sigma_azi": sigma_azi,
            "flags": station_flags,
        },
        north_reference="true",
    )


def _at_stations(
    run: StoredRun, times: FloatArray
) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Inclination and unwrapped azimuth (rad) interpolated at the station ``times`` (s,
    increasing), and each station's flags: those of the first sample at or after it."""
    held = run.held_span()
    values = Interpolation(times, 2)
    flags = np.zeros(times.size, dtype=np.int64)
    done = 0
    unwrap = CarriedUnwrap()  # np.unwrap of the whole series
    for a, b in chunks(0, run.size, run.rows):
        t, inc, azi, part_flags = run.angles(a, b, held)
        values.feed(t, inc, unwrap(azi))
        here = int(np.searchsorted(times, t[-1], side="right"))
        flags[done:here] = part_flags[np.searchsorted(t, times[done:here], side="left")]
        done = here
    flags[done:] = part_flags[-1]
    inc, azi = values.result()
    return inc, azi, flags

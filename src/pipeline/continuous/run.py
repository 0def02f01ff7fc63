"""The moving run of a continuous survey: where it starts and ends in the samples, the
compassed stops it is tied to, and its odometer differentiated by a local cubic fit.

Units: times s, MD m, angles rad unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from scipy.signal import savgol_filter

from pipeline.earth.frames import FloatArray
from pipeline.errors import GyropipeError

__all__ = [
    "DEG_H",
    "ContinuousError",
    "Odometer",
    "RunStops",
    "compassed_stop",
    "float_column",
    "odometer_fit",
    "odometer_points",
    "run_bounds",
    "wrap_angle",
]

DEG_H = np.pi / 180.0 / 3600.0
"""°/h → rad/s."""


RunStops = tuple[dict[str, float], dict[str, float]]
"""The compassed (start, end) stops of a run, as from :func:`compassed_stop`."""


class ContinuousError(GyropipeError, ValueError):
    """The samples or stops do not make a continuous run."""


def float_column(table: pa.Table, name: str) -> FloatArray:
    """Column ``name`` of ``table`` as float64 (nulls NaN)."""
    values: FloatArray = np.asarray(
        table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64
    )
    return values


def wrap_angle(angle: FloatArray | float) -> FloatArray:
    """Angle (rad) wrapped into [−π, π)."""
    wrapped: FloatArray = (np.asarray(angle, dtype=np.float64) + np.pi) % (2 * np.pi) - np.pi
    return wrapped


def run_bounds(station: FloatArray) -> tuple[int, int, int, int]:
    """Indices (last start-stop sample, first end-stop sample) and their station ids, from the
    samples' station markers (NaN while moving)."""
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


def compassed_stop(stops: pa.Table, station: int) -> dict[str, float]:
    """Azimuth, inclination, their σ, MD, high-side and gyro toolface and its σ (deg, m) of
    the compassed stop ``station``. A stop whose azimuth is undefined (vertical) keeps NaN
    and takes the gyro toolface's σ as its azimuth σ: a run is tied there through that
    toolface (A + ψ at I = 0)."""
    ids = np.asarray(stops.column("station").to_numpy(zero_copy_only=False))
    rows = np.flatnonzero(ids == station)
    if rows.size == 0:
        raise ContinuousError(
            f"stop {station} is not among the compassed stops (rejected by compassing?)"
        )
    row = int(rows[0])
    stop = {
        n: float(float_column(stops, n)[row])
        for n in (
            "azi",
            "inc",
            "sigma_azi",
            "sigma_inc",
            "md",
            "highside_toolface",
            "gyro_toolface",
            "sigma_toolface",
        )
    }
    if np.isnan(stop["azi"]):  # vertical: tied through the gyro toolface, and its σ
        stop["sigma_azi"] = stop["sigma_toolface"]
    return stop


def odometer_points(window: float, dt: float) -> int:
    """Odd number of samples (≥ 7) of the cubic fit differentiating the odometer over
    ``window`` s at sample interval ``dt`` s."""
    return max(7, round(window / dt) | 1)


@dataclass(frozen=True)
class Odometer:
    """The odometer over the run, from the start stop's last sample to the end stop's first."""

    time: FloatArray
    """s"""
    reading: FloatArray
    """MD read by the odometer, m"""
    md: FloatArray
    """MD of the fit, m (the reading without a fit)"""
    speed: FloatArray
    """m/s"""
    accel: FloatArray
    """along-hole acceleration, m/s²"""
    points: int | None
    """samples of the cubic fit (None: too few samples, finite differences of the reading)"""

    @property
    def dt(self) -> float:
        """Sample interval (median), s."""
        return float(np.median(np.diff(self.time)))


def odometer_fit(samples: pa.Table, begin: int, end: int, window: float) -> Odometer:
    """MD, speed and acceleration of the run ``begin``..``end`` (sample indices: the start
    stop's last sample, the end stop's first) from a local cubic fit (Savitzky–Golay) over
    ``window`` s of the odometer. Its noise is white per sample: never differentiate raw
    samples. The fit spans the stops' samples (at rest) too, so the speed ramps are not at
    its edges."""
    t = float_column(samples, "time")[begin : end + 1]
    reading = float_column(samples, "md")[begin : end + 1]
    dt = float(np.median(np.diff(t)))
    points = odometer_points(window, dt)
    lo, hi = max(begin - points, 0), min(end + 1 + points, samples.num_rows)
    if hi - lo <= points:
        md, speed = reading, np.gradient(reading, t)
        accel, points_used = np.gradient(speed, t), None
    else:
        wide = float_column(samples, "md")[lo:hi]
        inner = slice(begin - lo, end + 1 - lo)
        md, speed, accel = (
            savgol_filter(wide, points, 3, deriv=d, delta=dt)[inner] for d in (0, 1, 2)
        )
        points_used = points
    # the first and last samples are the stops', at rest: the fit, which cannot follow the
    # start of a speed ramp, would give them the ramp's acceleration
    speed[[0, -1]] = accel[[0, -1]] = 0.0
    return Odometer(t, reading, md, speed, accel, points_used)

"""The moving run of a continuous survey: where it starts and ends in the samples, the
compassed stops it is tied to, and its odometer differentiated by a local cubic fit.

Units: times s, MD m, angles rad unless a name says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.continuous.store import ColumnStore, chunks, median_step, savgol_range, savgol_span
from pipeline.earth.frames import FloatArray
from pipeline.errors import GyropipeError

__all__ = [
    "DEG_H",
    "ContinuousError",
    "Odometer",
    "RunStops",
    "compassed_stop",
    "float_column",
    "is_compassed",
    "is_short",
    "odometer_fit",
    "odometer_points",
    "run_bounds",
    "uncompassed_stop",
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


def run_bounds(store: ColumnStore, rows: int) -> tuple[int, int, int, int]:
    """Indices (last start-stop sample, first end-stop sample) and their station ids, from the
    samples' station markers (column ``station`` of ``store``: NaN while moving), read
    ``rows`` at a time."""
    total = store.rows("station")

    def first(start: int, moving: bool) -> int | None:
        for a, b in chunks(start, total, rows):
            found = np.flatnonzero(np.isnan(store.floats("station", a, b)) == moving)
            if found.size:
                return a + int(found[0])
        return None

    first_stop = first(0, False)
    if first_stop is None:
        raise ContinuousError("no compassing stop in the samples (station markers all null)")
    leaves = first(first_stop, True)
    if leaves is None:
        raise ContinuousError("the samples never leave the first stop")
    begin = leaves - 1  # last sample of the start stop
    end = first(begin + 1, False)  # first sample of the end stop
    if end is None:
        raise ContinuousError("no compassing stop after the moving run")
    ids = store.floats("station", begin, begin + 1), store.floats("station", end, end + 1)
    return begin, end, int(ids[0][0]), int(ids[1][0])


def compassed_stop(stops: pa.Table, station: int) -> dict[str, float]:
    """Azimuth, inclination, their σ, MD, high-side and gyro toolface and its σ (deg, m) of
    the compassed stop ``station``. A stop whose azimuth is undefined (vertical) keeps NaN
    and takes the gyro toolface's σ as its azimuth σ: a run is tied there through that
    toolface (A + ψ at I = 0)."""
    rows = _stop_rows(stops, station)
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


SHORT_STOP_FLAGS = frozenset({"fewer_positions"})
"""Compassing flags of a stop compassed from less data than the survey's others."""


def is_short(stops: pa.Table, station: int) -> bool:
    """Whether compassing flagged stop ``station`` as read from fewer frame positions than
    the survey's others (False where it is not compassed)."""
    rows = _stop_rows(stops, station)
    if rows.size == 0 or "flags" not in stops.column_names:
        return False
    flags = str(stops.column("flags")[int(rows[0])].as_py() or "").split(",")
    return bool(SHORT_STOP_FLAGS.intersection(flags))


def is_compassed(stops: pa.Table, station: int) -> bool:
    """Whether ``stops`` has a compassed row for stop ``station``."""
    return bool(_stop_rows(stops, station).size)


def uncompassed_stop(md: float) -> dict[str, float]:
    """The end stop of a run as :func:`compassed_stop` gives it where compassing rejected
    it: its MD (m) only, the rest NaN — the run is integrated from the start stop with no
    closure."""
    names = ("azi", "inc", "sigma_azi", "sigma_inc", "highside_toolface", "gyro_toolface")
    return {"md": md, "sigma_toolface": float("nan")} | dict.fromkeys(names, float("nan"))


def _stop_rows(stops: pa.Table, station: int) -> NDArray[np.intp]:
    ids = np.asarray(stops.column("station").to_numpy(zero_copy_only=False))
    return np.flatnonzero(ids == station)


def odometer_points(window: float, dt: float) -> int:
    """Odd number of samples (≥ 7) of the cubic fit differentiating the odometer over
    ``window`` s at sample interval ``dt`` s."""
    return max(7, round(window / dt) | 1)


@dataclass(frozen=True)
class Odometer:
    """The odometer over the run, from the start stop's last sample (store row ``begin``) to
    the end stop's first: columns ``odometer_md`` (MD of the fit, m; the reading without a
    fit), ``odometer_speed`` (m/s) and ``odometer_accel`` (along-hole acceleration, m/s²) of
    ``store``, run sample 0 at row 0; the time and the MD read at rows ``begin``… of the raw
    columns ``time`` (s) and ``md`` (m)."""

    store: ColumnStore
    begin: int
    size: int
    """samples of the run"""
    dt: float
    """sample interval (median), s"""
    points: int | None
    """samples of the cubic fit (None: too few samples, finite differences of the reading)"""
    rows: int
    """rows per chunk"""

    def time(self, lo: int, hi: int) -> FloatArray:
        """Times of run samples ``lo``…``hi − 1``, s."""
        return self.store.floats("time", self.begin + max(lo, 0), self.begin + min(hi, self.size))

    def reading(self, lo: int, hi: int) -> FloatArray:
        """MD read by the odometer at run samples ``lo``…``hi − 1``, m."""
        return self.store.floats("md", self.begin + max(lo, 0), self.begin + min(hi, self.size))

    def column(self, name: str, lo: int, hi: int) -> FloatArray:
        """``md``, ``speed`` or ``accel`` of the fit at run samples ``lo``…``hi − 1``."""
        return self.store.floats(f"odometer_{name}", lo, hi)


def odometer_fit(store: ColumnStore, begin: int, end: int, window: float, rows: int) -> Odometer:
    """MD, speed and acceleration of the run ``begin``..``end`` (sample indices: the start
    stop's last sample, the end stop's first) from a local cubic fit (Savitzky–Golay) over
    ``window`` s of the odometer, written to ``store`` ``rows`` at a time. Its noise is white
    per sample: never differentiate raw samples. The fit spans the stops' samples (at rest)
    too, so the speed ramps are not at its edges."""
    size = end + 1 - begin
    dt = median_step(store, "time", begin, end + 1, rows)
    points = odometer_points(window, dt)
    lo, hi = max(begin - points, 0), min(end + 1 + points, store.rows("md"))
    fitted = hi - lo > points
    if not fitted:  # too few samples for the fit: finite differences of the reading
        t, md = store.floats("time", begin, end + 1), store.floats("md", begin, end + 1)
        speed = np.gradient(md, t)
        whole = {"md": md, "speed": speed, "accel": np.gradient(speed, t)}
    for a, b in chunks(begin, end + 1, rows):
        if fitted:
            wlo, whi = savgol_span(lo, hi, a, b, points)
            wide = store.floats("md", wlo, whi)
            fits = savgol_range(wide, wlo, a, b, points, 3, (0, 1, 2), dt)
            fit = dict(zip(("md", "speed", "accel"), fits, strict=True))
        else:
            fit = {name: values[a - begin : b - begin] for name, values in whole.items()}
        # the first and last samples are the stops', at rest: the fit, which cannot follow
        # the start of a speed ramp, would give them the ramp's acceleration
        for index in (begin, end):
            if a <= index < b:
                fit["speed"][index - a] = fit["accel"][index - a] = 0.0
        for name, values in fit.items():
            store.write(f"odometer_{name}", a - begin, values)
    return Odometer(store, begin, size, dt, points if fitted else None, rows)

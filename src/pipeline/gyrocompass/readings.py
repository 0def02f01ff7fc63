"""Point-survey raw samples reduced to one reading per station × frame position (the first
step of multi-position gyrocompassing, DOMAIN.md §5).

A *dwell* is a run of samples with the frame held in one position and the tool stopped.
Dwells come from the samples' ``station``/``position`` markers when they have them, else
they are detected from the frame angle and the odometer MD:

- a dwell starts at the first sample (after the previous dwell) from which the frame angle
  stays within ``angle_tolerance`` and the MD — smoothed by a moving average over
  ``md_smoothing`` to ride over odometer noise — within ``md_tolerance`` of that sample's
  values for long enough to leave ``min_dwell`` after trimming; it ends at the first sample
  where either leaves its tolerance around its median over that first stretch (a stop
  creeping in at the edge of the tolerance does not cut the dwell short);
- a dwell's ends are then cut back to where its odometer MD rests (the tool arriving or
  leaving creeps within ``md_tolerance`` for seconds: :mod:`~pipeline.gyrocompass.still`);
  one left too short for ``min_dwell`` after trimming is not a dwell (the tool crept
  through it);
- consecutive dwells belong to one station until the stop MD differs from the previous one
  by more than ``station_gap``, or the MD strayed farther than that between them (the tool
  moved and came back); stations and positions are numbered from 0;
- a stop the tool made that holds no dwell — the smoothed MD held within ``md_tolerance``
  for at least ``stop_hold``, farther than ``station_gap`` from the dwells either side (the
  stop too short, or the frame or the tool not still enough) — is numbered as a station in
  its place with no reading, and recorded for the validity checks to drop by name
  (:mod:`~pipeline.gyrocompass.stops`).

Each dwell loses ``trim_start`` seconds at its start and ``trim_end`` at its end (frame-move
transients, settling); the rest is averaged. Rates in °/h, accelerations in m/s², MD in m,
angles in degrees, times in seconds; the sample rate comes from the (uniform) time column.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from pipeline.gyrocompass.recording_end import RecordingEnd, attach, station_md
from pipeline.gyrocompass.still import still_spans
from pipeline.gyrocompass.stops import (
    Dwells,
    Stop,
    UnreadStop,
    attach_unread,
    place,
    unread_records,
)
from pipeline.tables import PositionReadings, RawSamples

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]

SIGNALS = ("gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z")
"""Sensor columns averaged per reading (the gyro axes a tool lacks are skipped)."""
UNIFORM_RTOL = 0.01
"""Largest deviation of a time step from the mean step, as a fraction of it: a dropped or
doubled sample, or a change of sample rate, breaks uniform sampling; clock jitter does not."""
Ended = tuple[int, int, int, int]
"""The dwell a recording ended in: first and end sample, station, position."""


class ReadingOptions(BaseModel):
    """How raw samples are cut into position readings (times in s, angles in deg, MD in m)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    trim_start: float = Field(
        1.0,
        ge=0,
        description="time dropped at the start of each dwell (frame-move transients, settling), s",
    )
    trim_end: float = Field(0.0, ge=0, description="time dropped at the end of each dwell, s")
    min_dwell: float = Field(
        5.0,
        ge=0,
        description="shortest averaging time left after trimming, s: shorter detected dwells "
        "are not positions; a shorter marked position is an error",
    )
    angle_tolerance: float = Field(
        0.5, gt=0, description="detection: the frame angle stays within this during a dwell, deg"
    )
    md_tolerance: float = Field(
        0.05, gt=0, description="detection: the smoothed MD stays within this during a dwell, m"
    )
    md_smoothing: float = Field(
        1.0,
        ge=0,
        description="detection: moving-average window applied to the MD before the "
        "md_tolerance test, s (0: none)",
    )
    station_gap: float = Field(
        0.5,
        gt=0,
        description="detection: a new station starts when the stop MD changes by more than "
        "this, or the MD strays farther than this between two dwells, m",
    )
    end_stop: float = Field(
        1.0,
        ge=0,
        description="detection: the recording's end, steady for at least this long (and "
        "longer than the trims) but too short for a dwell, is reported as a frame position "
        "the recording cut short, s",
    )
    stop_hold: float = Field(
        2.0,
        gt=0,
        description="detection: the smoothed MD held within md_tolerance for at least this "
        "long is a stop the tool made; one with no dwell, farther than station_gap from "
        "the dwells either side, is numbered as a station without a reading and reported, s",
    )


DEFAULTS = ReadingOptions()


def position_readings(samples: pa.Table, options: ReadingOptions = DEFAULTS) -> pa.Table:
    """Reduce a point survey's raw samples (:class:`RawSamples`) to :class:`PositionReadings`:
    per dwell, the station, its MD (median odometer MD over all the station's averaged
    samples, m), the position, the mid-time of the averaged samples (s), the circular mean
    frame angle (deg, [0, 360)), the mean and sample standard deviation (ddof = 1) of every
    gyro (°/h) and accelerometer (m/s²) axis, the number of samples and their duration
    (n / sample rate, s). The dwell the recording ended in (ending at the last sample: a
    marked run, a detected dwell, or a steady end at least ``end_stop`` long but too short
    for a dwell) is recorded in the table's schema metadata
    (:mod:`~pipeline.gyrocompass.recording_end`); too short after trimming, it is not
    averaged (not an error). Detected dwells only: the stops the tool made without a dwell
    are numbered as stations without readings and recorded in the schema metadata too
    (:mod:`~pipeline.gyrocompass.stops`). Raises ``ValueError`` naming the problem: no
    markers and no frame angle, another marked position repeated or too short after
    trimming, a station marked again after other stations (:func:`remarked_stations`),
    non-uniform time, no positions found."""
    RawSamples.validate_table(samples)
    time = samples.column("time").to_numpy()
    rate = _sample_rate(time)
    md = _optional(samples, "md")
    if md is None:
        raise ValueError(NO_MD)
    angle = _optional(samples, "frame_angle")
    k_start, k_end, need, _ = counts(options, rate)
    markers = _markers(samples)
    last: Ended | None = None
    unread: list[UnreadStop] = []
    if markers is not None:
        starts, ends, station, position = markers
        if ends.size and ends[-1] == time.size:
            last = (int(starts[-1]), int(ends[-1]), int(station[-1]), int(position[-1]))
            if ends[-1] - starts[-1] - k_start - k_end < need:  # too short: dropped, reported
                starts, ends, station, position = (x[:-1] for x in markers)
        check_lengths(ends - starts - k_start - k_end, need, time[starts], station, position)
    else:
        if angle is None:
            raise ValueError(NO_ANGLE)
        starts, ends, station, position, last, unread = _detected(md, angle, time, options, rate)
    signals = {name: v for name in SIGNALS if (v := _optional(samples, name)) is not None}
    if starts.size == 0 and last is not None:
        left = max(last[1] - last[0] - k_start - k_end, 0) / rate
        raise ValueError(only_stop(time[last[0]], time[last[1] - 1], left))
    readings = reduce_readings(
        signals, time, rate, md, angle, starts + k_start, ends - k_end, station, position
    )
    readings = attach_unread(readings, unread)
    if last is None:
        return readings
    first, end, s, p = last
    left = max(end - first - k_start - k_end, 0)
    return attach(
        readings,
        RecordingEnd(
            s,
            p,
            station_md(readings, s, float(np.median(md[first:end]))),
            float(time[first]),
            float(time[end - 1]),
            left / rate,
            left >= need,
        ),
    )


def _detected(
    md: FloatArray, angle: FloatArray, time: FloatArray, options: ReadingOptions, rate: float
) -> tuple[IndexArray, IndexArray, IndexArray, IndexArray, Ended | None, list[UnreadStop]]:
    """The detected dwells' still samples (first and end, before the trims), stations and
    positions; the dwell the recording ended in (first and end sample, station, position)
    and the unread stops (module docstring)."""
    k_start, k_end, need, window = counts(options, rate)
    smooth_md = moving_average(md, window)
    watched = (np.unwrap(angle, period=360.0), smooth_md)
    tolerances = (options.angle_tolerance, options.md_tolerance)
    starts, ends = _detect_dwells(watched, tolerances, k_start + need + k_end)
    begin = max(int(ends[-1]) if ends.size else 0, time.size - k_start - need - k_end)
    first, end = still_spans(md, starts, ends, window)
    keep = end - first - k_start - k_end >= need  # else the tool crept through it: no dwell
    starts, ends, first, end = starts[keep], ends[keep], first[keep], end[keep]
    tail = begin + steady_tail(tuple(x[begin:] for x in watched), tolerances)
    cut = begin < time.size and time.size - tail >= end_stop_count(options, rate)
    numbered = np.append(starts, tail) if cut else starts
    station, position = _number_stations(smooth_md, numbered, options.station_gap)
    closed = np.append(ends, time.size) if cut else ends
    found = Dwells(numbered, closed, smooth_md[numbered], station)
    placed = place(found, md_stops(smooth_md, md, time, options, rate), options.station_gap)
    station = placed.renumber[station]
    unread = unread_records(placed, rate, *stop_terms(options, rate))
    last = None
    if cut:
        last = (tail, time.size, int(station[-1]), int(position[-1]))
        station, position = station[:-1], position[:-1]
    elif ends.size and ends[-1] == time.size:
        last = (int(first[-1]), int(end[-1]), int(station[-1]), int(position[-1]))
    return first, end, station, position, last, unread


def end_stop_count(options: ReadingOptions, rate: float) -> int:
    """The fewest samples of a steady end of the recording taken for a frame position cut
    short (detection): ``end_stop`` and more than the trims leave nothing of."""
    k_start, k_end, _, _ = counts(options, rate)
    return max(round(options.end_stop * rate), k_start + k_end + 2)


def stop_count(options: ReadingOptions, rate: float) -> int:
    """The fewest samples of held MD that make a stop (``stop_hold``, at least 2)."""
    return max(2, round(options.stop_hold * rate))


def stop_terms(options: ReadingOptions, rate: float) -> tuple[float, float, float, float]:
    """What an unread stop's record states of a dwell (:func:`~pipeline.gyrocompass.stops.
    unread_records`): the steady time it needs (s: the trims and ``min_dwell`` in whole
    samples), ``min_dwell`` (s) and the angle (deg) and MD (m) tolerances."""
    k_start, k_end, need, _ = counts(options, rate)
    return (
        (k_start + need + k_end) / rate,
        options.min_dwell,
        options.angle_tolerance,
        options.md_tolerance,
    )


def md_stops(
    smooth_md: FloatArray, md: FloatArray, time: FloatArray, options: ReadingOptions, rate: float
) -> list[Stop]:
    """The stops of the MD (:mod:`~pipeline.gyrocompass.stops`): ``smooth_md`` the smoothed
    MD, ``md`` the odometer's (m), ``time`` (s), at ``rate`` (Hz)."""
    starts, ends = _detect_dwells((smooth_md,), (options.md_tolerance,), stop_count(options, rate))
    return [
        Stop(a, b, float(np.median(md[a:b])), float(time[a]), float(time[b - 1]))
        for a, b in zip(starts.tolist(), ends.tolist(), strict=True)
    ]


def only_stop(start: float, end: float, left: float) -> str:
    """Why the only dwell, from ``start`` to ``end`` (s) and cut short by the end of the
    recording with ``left`` s after trimming, gave no reading."""
    return (
        f"{NO_POSITIONS}: the recording ended {end - start:.2f} s into the only frame "
        f"position (from t = {start:g} s), leaving {left:.2f} s after trimming"
    )


def steady_tail(signals: tuple[FloatArray, ...], tolerances: tuple[float, ...]) -> int:
    """The first sample of the longest end of the signals over which each stays within its
    tolerance of a middle value (its range at most twice the tolerance, as a dwell stays
    within its tolerance of its median); 0 for empty signals. Detection looks for it after
    the last dwell, in as many of the last samples as a dwell needs (a longer one is a
    dwell: the streamed path has those samples at hand)."""
    if signals[0].size == 0:
        return 0
    steady = np.ones(signals[0].size, dtype=bool)
    for x, tol in zip(signals, tolerances, strict=True):
        high = np.maximum.accumulate(x[::-1])[::-1]
        low = np.minimum.accumulate(x[::-1])[::-1]
        steady &= high - low <= 2 * tol
    return int(np.argmax(steady))


NO_POSITIONS = "no frame positions found"
NO_MD = "samples have no md column: position readings need the station MD"
NO_ANGLE = (
    "samples have neither station/position markers nor a frame_angle column: "
    "cannot tell the frame positions apart"
)


def counts(options: ReadingOptions, rate: float) -> tuple[int, int, int, int]:
    """Samples trimmed at a dwell's start and end, the fewest averaged (``min_dwell``, at
    least 2) and the MD smoothing window, at ``rate`` (Hz)."""
    need = max(2, int(np.ceil(options.min_dwell * rate - 1e-6)))  # slack for rounding
    window = max(1, round(options.md_smoothing * rate))
    return round(options.trim_start * rate), round(options.trim_end * rate), need, window


def _optional(samples: pa.Table, name: str) -> FloatArray | None:
    """A float column as an array; None when absent or all null; ValueError when partly null."""
    if name not in samples.column_names:
        return None
    column = samples.column(name)
    if column.null_count == len(column):
        return None
    if column.null_count:
        raise ValueError(
            f"column {name!r} has {column.null_count} missing values of {len(column)}: "
            "position readings need it complete or absent"
        )
    values: FloatArray = column.to_numpy()
    return values


def _sample_rate(time: FloatArray) -> float:
    """Sample rate (Hz) of uniformly spaced times (s); ValueError otherwise."""
    if time.size < 2:
        raise ValueError(too_few(time.size))
    dt = float(time[-1] - time[0]) / (time.size - 1)
    if np.any(np.abs(np.diff(time) - dt) > UNIFORM_RTOL * dt):
        raise ValueError(not_uniform(time))
    return 1.0 / dt


def too_few(n: int) -> str:
    return f"need at least 2 samples to know the sample rate, got {n}"


def not_uniform(time: FloatArray) -> str:
    """The message of non-uniform ``time`` (s): the usual (median) step, the first step off
    it by more than :data:`UNIFORM_RTOL` (its time and row; where none is, the one farthest
    off) and how many are."""
    steps = np.diff(time)
    middle = (len(steps) - 1) // 2
    usual = float(np.partition(steps, middle)[middle])  # a median that is one of the steps
    deviation = np.abs(steps - usual)
    off = deviation > UNIFORM_RTOL * usual
    i = int(np.argmax(off)) if off.any() else int(np.argmax(deviation))
    count = max(int(off.sum()), 1)
    return (
        f"time is not uniformly sampled: the usual step is {usual:g} s, but the step at "
        f"t = {time[i]:g} s is {steps[i]:g} s (after row {i}; {count} step(s) off the usual: "
        "samples dropped or doubled, a gap, or a change of sample rate?)"
    )


def _markers(samples: pa.Table) -> tuple[IndexArray, IndexArray, IndexArray, IndexArray] | None:
    """Runs of consecutive samples with the same non-null (station, position) markers, as
    (start, end) sample indices and their markers; None when the samples carry no markers."""
    codes = {}
    for name in ("station", "position"):
        if name in samples.column_names and samples.column(name).null_count < samples.num_rows:
            codes[name] = samples.column(name).fill_null(-1).to_numpy()
    if not codes:
        return None
    if len(codes) == 1:
        (have,) = codes
        lack = "position" if have == "station" else "station"
        raise ValueError(f"samples have {have} markers but no {lack} markers: give both or neither")
    station, position = codes["station"], codes["position"]
    orphans = int(np.count_nonzero((station < 0) & (position >= 0)))
    if orphans:
        raise ValueError(f"{orphans} samples have a position marker but no station marker")
    change = np.flatnonzero((station[1:] != station[:-1]) | (position[1:] != position[:-1])) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [station.size]])
    keep = (station[starts] >= 0) & (position[starts] >= 0)
    starts, ends = starts[keep], ends[keep]
    keys = np.stack([station[starts], position[starts]], axis=-1)
    unique, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    if (counts > 1).any():
        time = samples.column("time").to_numpy()
        repeated = [
            f"station {s} position {p} at t = "
            + ", ".join(f"{time[i]:g}" for i in starts[inverse.ravel() == k])
            + " s"
            for k, (s, p) in enumerate(unique)
            if counts[k] > 1
        ]
        raise ValueError(
            "markers label a (station, position) in separate runs of samples: "
            + "; ".join(repeated)
        )
    problem = remarked_stations(keys[:, 0], samples.column("time").to_numpy()[starts])
    if problem:
        raise ValueError(problem)
    return starts, ends, keys[:, 0], keys[:, 1]


def remarked_stations(station: IndexArray, t0: FloatArray) -> str | None:
    """The problem of stations marked again after other stations, from the station and the
    first time (s) of every marked run in order; None if each station's runs are together.

    A gyrocompass station's positions are read in one visit, at one depth: the runs of a
    station that comes back after others (a repeated shot numbered as the first) are not
    merged into it but refused, and the later visit is to be numbered as a station of its
    own."""
    if station.size == 0:
        return None
    first = np.concatenate([[0], np.flatnonzero(np.diff(station) != 0) + 1])
    visits = station[first]
    ids, count = np.unique(visits, return_counts=True)
    again = ids[count > 1]
    if again.size == 0:
        return None
    listed = "; ".join(
        f"station {s} at t = " + ", ".join(f"{t:g}" for t in t0[first[visits == s]]) + " s"
        for s in again
    )
    return (
        f"stations marked again after other stations (visits start): {listed}. A station's "
        "positions are read in one visit at one depth: number a later visit as a station "
        "of its own"
    )


def check_lengths(
    n: IndexArray, need: int, t0: FloatArray, station: IndexArray, position: IndexArray
) -> None:
    """ValueError naming every marked position with fewer than ``need`` samples left."""
    short = np.flatnonzero(n < need)
    if short.size:
        listed = ", ".join(
            f"station {station[i]} position {position[i]} (t = {t0[i]:g} s): {max(int(n[i]), 0)}"
            for i in short
        )
        raise ValueError(
            f"marked positions too short after trimming (samples left; need ≥ {need} for "
            f"min_dwell and at least 2): {listed}"
        )


def moving_average(values: FloatArray, window: int) -> FloatArray:
    """Centred moving average over ``window`` samples; within half a window of either end,
    the mean of the samples the window holds there (not the end sample repeated, which
    would weigh one sample's noise half a window over)."""
    if window == 1 or values.size == 0:
        return values
    from scipy.ndimage import uniform_filter1d  # imported on use: slow to import

    smooth: FloatArray = uniform_filter1d(values, window, mode="nearest")
    lo = window // 2  # the window at sample i spans i − lo … i − lo + window − 1
    hi = window - 1 - lo
    n = values.size
    head = np.arange(min(lo, n))
    tail = np.arange(max(n - hi, 0), n)
    sums = np.concatenate([[0.0], np.cumsum(values[: min(n, lo + hi + 1)])])
    top = np.minimum(head + hi + 1, n)
    smooth[head] = sums[top] / top
    back = np.concatenate([[0.0], np.cumsum(values[::-1][: min(n, lo + hi + 1)])])
    count = np.minimum(n - tail + lo, n)
    smooth[tail] = back[count] / count
    return smooth


def _detect_dwells(
    signals: tuple[FloatArray, ...], tolerances: tuple[float, ...], length: int
) -> tuple[IndexArray, IndexArray]:
    """(start, end) sample indices of dwells: each starts at the first sample from which
    every signal stays within its tolerance of its value there for ``length`` samples, and
    ends where :func:`_leave` says (module docstring)."""
    candidates = steady_starts(signals, tolerances, length)
    starts: list[int] = []
    ends: list[int] = []
    i = 0
    while i < candidates.size:
        start = int(candidates[i])
        end = _leave(signals, tolerances, start, start + length)
        starts.append(start)
        ends.append(end)
        i = int(np.searchsorted(candidates, end))
    return np.asarray(starts, dtype=np.intp), np.asarray(ends, dtype=np.intp)


def steady_starts(
    signals: tuple[FloatArray, ...], tolerances: tuple[float, ...], length: int
) -> IndexArray:
    """Samples ``s`` from which every signal stays within its tolerance of its value at ``s``
    for ``length`` samples (``s + length`` ≤ the signals' length)."""
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    count = signals[0].size - length + 1
    if count <= 0:
        return np.empty(0, np.intp)
    steady = np.ones(count, dtype=bool)
    lo = length // 2  # the centred filters' window at lo + s spans samples s … s + length − 1
    for x, tol in zip(signals, tolerances, strict=True):
        first = x[:count]
        steady &= maximum_filter1d(x, length)[lo : lo + count] - first <= tol
        steady &= first - minimum_filter1d(x, length)[lo : lo + count] <= tol
    return np.flatnonzero(steady)


def _leave(
    signals: tuple[FloatArray, ...], tolerances: tuple[float, ...], start: int, begin: int
) -> int:
    """First sample from ``begin`` on where a signal leaves its tolerance around its median
    over samples ``start`` … ``begin`` − 1; the signals' length if none does. Searches
    chunks of doubling size."""
    size = signals[0].size
    levels = [float(np.median(x[start:begin])) for x in signals]
    chunk = max(begin - start, 1024)
    while begin < size:
        end = min(size, begin + chunk)
        out = np.zeros(end - begin, dtype=bool)
        for x, level, tol in zip(signals, levels, tolerances, strict=True):
            out |= np.abs(x[begin:end] - level) > tol
        if out.any():
            return begin + int(np.argmax(out))
        begin, chunk = end, 2 * chunk
    return size


def _number_stations(
    md: FloatArray, starts: IndexArray, gap: float
) -> tuple[IndexArray, IndexArray]:
    """Station and position numbers of consecutive dwells (from 0): a new station when the
    stop MD (``md`` at the dwell's start) changes by more than ``gap``, or ``md`` strays
    farther than ``gap`` from it before the next dwell."""
    if starts.size == 0:
        return np.empty(0, np.intp), np.empty(0, np.intp)
    stop = md[starts]
    high = np.maximum.reduceat(md, starts)[:-1] - stop[:-1]  # from a dwell to the next one
    low = stop[:-1] - np.minimum.reduceat(md, starts)[:-1]
    new = (np.abs(np.diff(stop)) > gap) | (np.maximum(high, low) > gap)
    station = np.concatenate([[0], np.cumsum(new)]).astype(np.intp)
    first = np.flatnonzero(np.concatenate([[True], new]))
    position = np.arange(starts.size) - first[station]
    return station, position


def reduce_readings(
    signals: dict[str, FloatArray],
    time: FloatArray,
    rate: float,
    md: FloatArray,
    angle: FloatArray | None,
    a: IndexArray,
    b: IndexArray,
    station: IndexArray,
    position: IndexArray,
) -> pa.Table:
    """PositionReadings from the samples [a, b) of each reading (``signals``: the sensor
    columns of :data:`SIGNALS` the samples have)."""
    if a.size == 0:
        raise ValueError(f"{NO_POSITIONS}: no dwell long enough for min_dwell after trimming")
    n = b - a
    groups, inverse = np.unique(station, return_inverse=True)
    label = inverse.ravel()  # station of each reading as 0 … groups − 1
    columns: dict[str, object] = {
        "station": station,
        "md": _station_medians(md, a, b, label, groups.size)[label],
        "position": position,
    }
    columns |= reading_stats(signals, time, angle, a, b)
    columns["duration"] = n / rate
    return PositionReadings.compiled().make_table(columns)


def reading_stats(
    signals: dict[str, FloatArray],
    time: FloatArray,
    angle: FloatArray | None,
    a: IndexArray,
    b: IndexArray,
) -> dict[str, np.ndarray]:
    """Each reading's mid time ``t`` (s, of ``time``), circular mean frame angle (deg, when
    ``angle`` is given), the mean and sample standard deviation of each signal and its
    sample count ``n``, over the samples [a, b) of the columns (the readings in order, none
    overlapping: ``b[i]`` ≤ ``a[i + 1]``, each of at least 2 samples). A reading's numbers
    do not depend on its neighbours: each column is reduced in a buffer of the readings'
    samples alone (:class:`_Packed`: the samples between readings are not gone over)."""
    n = b - a
    columns: dict[str, np.ndarray] = {"t": (time[a] + time[b - 1]) / 2}
    packed = _Packed(a, b)
    if angle is not None:
        columns["frame_angle"] = _circular_mean(packed.gather(angle), packed.starts)
    stds: dict[str, FloatArray] = {}
    for name, values in signals.items():
        columns[name], stds[f"{name}_std"] = packed.mean_std(values)
    return columns | stds | {"n": n}


class _Packed:
    """The samples [a, b) of each reading (in order, none overlapping, each of at least 2),
    laid end to end in one scratch buffer that every signal reuses."""

    def __init__(self, a: IndexArray, b: IndexArray) -> None:
        self.a, self.n = a, b - a
        starts = np.concatenate([[0], np.cumsum(self.n)[:-1]])
        self.starts: IndexArray = starts
        """each reading's first sample in the buffer"""
        self.pieces = [
            (slice(i, j), slice(s, s + j - i))
            for i, j, s in zip(a.tolist(), b.tolist(), starts.tolist(), strict=True)
        ]
        """(samples in the signal, the same samples in the buffer) of each reading"""
        self.dev: FloatArray = np.empty(int(self.n.sum()))

    def gather(self, x: FloatArray) -> FloatArray:
        """The readings' samples of ``x`` end to end (the buffer: overwritten by the next
        call of either method)."""
        for signal, packed in self.pieces:
            self.dev[packed] = x[signal]
        return self.dev

    def mean_std(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Mean and sample standard deviation (ddof = 1) of each reading's samples of ``x``,
        taken about the reading's first sample so that constant signals average exactly."""
        first = x[self.a]
        dev = self.dev
        for (signal, packed), f in zip(self.pieces, first.tolist(), strict=True):
            np.subtract(x[signal], f, out=dev[packed])
        shift = np.add.reduceat(dev, self.starts) / self.n
        for (_, packed), s in zip(self.pieces, shift.tolist(), strict=True):
            dev[packed] -= s
        var = np.add.reduceat(np.multiply(dev, dev, out=dev), self.starts) / (self.n - 1)
        return first + shift, np.sqrt(var)


def _circular_mean(degrees: FloatArray, starts: IndexArray) -> FloatArray:
    """Circular mean (deg, [0, 360)) of the angles of each segment (from each of ``starts``
    to the next)."""
    sin, cos = (np.add.reduceat(v, starts) for v in _sin_cos(degrees))
    mean = np.degrees(np.arctan2(sin, cos)) % 360.0
    wrapped: FloatArray = np.where(mean < 360.0, mean, 0.0)  # −tiny % 360 rounds to 360
    return wrapped


def _sin_cos(degrees: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Sine and cosine of each angle (deg), computed once per run of equal values when the
    runs are long (a frame held in a position reads one angle for thousands of samples)."""
    bits = degrees.view(np.int64)  # equal bits, equal results (−0.0 and NaN included)
    new = np.flatnonzero(bits[1:] != bits[:-1]) + 1
    if new.size > degrees.size // 8:
        rad = np.radians(degrees)
        return np.sin(rad), np.cos(rad)
    starts = np.concatenate([[0], new])
    lengths = np.diff(starts, append=degrees.size)
    held = np.radians(degrees[starts])
    return np.repeat(np.sin(held), lengths), np.repeat(np.cos(held), lengths)


def _station_medians(
    md: FloatArray, a: IndexArray, b: IndexArray, label: IndexArray, groups: int
) -> FloatArray:
    """Median MD (m) of each station (``label`` of each reading: 0 … groups − 1, every group
    non-empty) over the samples [a, b) of its readings, taken in place."""
    pieces: list[list[FloatArray]] = [[] for _ in range(groups)]
    for g, i, j in zip(label.tolist(), a.tolist(), b.tolist(), strict=True):
        pieces[g].append(md[i:j])
    median: FloatArray = np.array([exact_median(p) for p in pieces])
    return median


def exact_median(pieces: list[FloatArray]) -> float:
    """``np.median`` of the values of ``pieces`` together, the same number, found among the
    values near it: those between two quantiles of a sparse sample are selected from, the
    rest only counted (when they do not bracket the middle — or a NaN is there — every value
    is)."""
    values = pieces[0] if len(pieces) == 1 else np.concatenate(pieces)
    n = values.size
    if n < 4096:
        return float(np.median(values))
    sample = np.sort(values[:: n // 512])
    lo, hi = sample[int(0.4 * sample.size)], sample[int(0.6 * sample.size)]
    below = int(np.count_nonzero(values < lo))
    near = np.compress((values >= lo) & (values <= hi), values)  # (half the time of values[mask])
    above = int(np.count_nonzero(values > hi))
    middle = ((n - 1) // 2 - below, n // 2 - below)  # of the near values, in order
    if below + near.size + above != n or middle[0] < 0 or middle[1] >= near.size:
        return float(np.median(values))
    picked = np.partition(near, middle)[middle[0] : middle[1] + 1]  # one or two, as NumPy's
    return float(np.mean(picked))

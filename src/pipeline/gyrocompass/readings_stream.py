"""Position readings from a stream of raw-sample record batches, in bounded memory.

The same readings as :func:`~pipeline.gyrocompass.readings.position_readings` on the whole
table (same dwells, stations and numbers: each station is reduced by the same function on
the same samples), from what a pass over the stream finds:

1. the time column and the null counts: sample rate and uniformity exactly as the whole
   table gives them (so the trims and windows are the same), and which columns have data;
2. the dwells, found as the whole-table path finds them, a station's averaged samples kept
   until the station ends, then reduced.

Samples with station/position markers take one pass (each batch decoded once): the marked
runs are cut and reduced in the same pass as the scan, with the trims of the sample rate of
the first batch, and the scan's rate confirms them at the end (the readings' durations are
the scan's). Where it does not — trims of another number of samples, a column without data
— or the dwells are detected, a second pass does step 2 as the scan says.

Each reading is reduced as soon as its samples have passed (those wholly inside a batch
together, by the same function as the whole-table path: the same numbers); what stays in
memory is the current station's averaged MD samples (for its median: views of the MD columns
they lie in), the current marked run or the samples since the last dwell (or the current
dwell), and one batch, whatever the survey's length.

Detection runs the whole-table steps on a sliding buffer: the smoothed MD (a moving
average) and the unwrapped frame angle are recomputed over the buffer, and only samples
whose smoothing window lies inside it are used, so the dwells are those of the whole table
except where a smoothed MD or angle lies within rounding (≈1e-15 of its value) of a
tolerance. Marked positions are exact. A station marked again after another station is a
``ValueError``, as on the whole table (:func:`~pipeline.gyrocompass.readings.remarked_stations`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
import pyarrow as pa

from pipeline.gyrocompass.readings import (
    DEFAULTS,
    NO_ANGLE,
    NO_MD,
    SIGNALS,
    UNIFORM_RTOL,
    FloatArray,
    IndexArray,
    ReadingOptions,
    check_lengths,
    counts,
    end_stop_count,
    exact_median,
    moving_average,
    not_uniform,
    only_stop,
    reading_stats,
    reduce_readings,
    remarked_stations,
    steady_starts,
    steady_tail,
    stop_count,
    stop_terms,
    too_few,
)
from pipeline.gyrocompass.recording_end import RecordingEnd, attach, station_md
from pipeline.gyrocompass.still import still_span
from pipeline.gyrocompass.stops import (
    Dwells,
    Placed,
    Stop,
    UnreadStop,
    attach_unread,
    place,
    unread_records,
)
from pipeline.streams import TableStream
from pipeline.tables import PositionReadings, RawSamples

MARKERS = ("station", "position")


@dataclass
class _Scan:
    """What the first pass finds: rows, first and last time, smallest and largest time step
    (s), null counts."""

    rows: int = 0
    first: float = np.nan
    last: float = np.nan
    low: float = np.inf
    high: float = -np.inf
    nulls: dict[str, int] = field(default_factory=dict)

    def add(self, batch: pa.RecordBatch) -> None:
        time = batch.column("time").to_numpy()
        if time.size == 0:
            return
        if self.rows:
            step = float(time[0] - self.last)  # from the batch before
            self.low, self.high = min(self.low, step), max(self.high, step)
        else:
            self.first = float(time[0])
        if time.size > 1:
            steps = np.diff(time)
            self.low, self.high = min(self.low, steps.min()), max(self.high, steps.max())
        self.last = float(time[-1])
        self.rows += batch.num_rows
        for name in self.nulls:
            self.nulls[name] += batch.column(name).null_count

    def data(self, name: str) -> bool:
        """Whether the column has any value (raises when it is only partly filled, as
        :func:`~pipeline.gyrocompass.readings._optional` does)."""
        if name not in self.nulls or self.nulls[name] == self.rows:
            return False
        if self.nulls[name] and name not in MARKERS:
            raise ValueError(
                f"column {name!r} has {self.nulls[name]} missing values of {self.rows}: "
                "position readings need it complete or absent"
            )
        return True


def stream_position_readings(samples: TableStream, options: ReadingOptions = DEFAULTS) -> pa.Table:
    """:func:`~pipeline.gyrocompass.readings.position_readings` of a stream of
    :class:`RawSamples` batches (each checked against the contract unless the stream holds it
    already), in bounded memory (module docstring). No samples give no readings (an empty
    table)."""
    wanted = ("md", "frame_angle", *MARKERS, *SIGNALS)
    names = samples.schema.names
    scan = _Scan(nulls={n: 0 for n in wanted if n in names})
    marks = all(m in names for m in ("md", *MARKERS))
    ahead = _MarkedAhead(options, names) if marks else None
    for batch in RawSamples.validate_stream(samples):
        scan.add(batch)
        if ahead is not None:
            ahead.add(batch)
    if scan.rows == 0:
        return PositionReadings.compiled().schema().empty_table()
    rate = _rate(samples, scan)
    if not scan.data("md"):
        raise ValueError(NO_MD)
    angle = scan.data("frame_angle")
    marked = [m for m in MARKERS if scan.data(m)]
    if len(marked) == 1:
        lack = "position" if marked == ["station"] else "station"
        raise ValueError(
            f"samples have {marked[0]} markers but no {lack} markers: give both or neither"
        )
    if not marked and not angle:
        raise ValueError(NO_ANGLE)
    columns = ["time", "md", *(["frame_angle"] if angle else []), *_signals(scan)]
    if marked and ahead is not None and ahead.holds(columns, counts(options, rate)):
        return ahead.finish(rate)
    reducer = _Stations(columns, rate)
    if marked:
        return _Marked(options, rate, reducer).run(samples)
    return _Detected(options, rate, reducer).run(samples)


class _MarkedAhead:
    """The marked runs cut and reduced during the scan, with the trims of the first
    batch's sample rate and every column the schema has (module docstring)."""

    def __init__(self, options: ReadingOptions, names: list[str]) -> None:
        self.options = options
        self.columns = [n for n in ("time", "md", "frame_angle", *SIGNALS) if n in names]
        self.marked: _Marked | None = None
        self.missed = False
        """a batch came before one that gives a rate: the second pass does it all"""

    def add(self, batch: pa.RecordBatch) -> None:
        if self.missed:
            return
        if self.marked is None:
            time = batch.column("time").to_numpy()
            if time.size < 2 or not time[-1] > time[0]:
                self.missed = batch.num_rows > 0
                return
            rate = (time.size - 1) / float(time[-1] - time[0])
            self.marked = _Marked(self.options, rate, _Stations(self.columns, rate))
        self.marked.add(batch)

    def holds(self, columns: list[str], trims: tuple[int, int, int, int]) -> bool:
        """Whether the runs cut are those of the scan's ``columns`` and trims ``trims``
        (the smoothing window is the detection's only: not compared)."""
        marked = self.marked
        return (
            marked is not None  # (never set after a batch missed)
            and columns == self.columns
            and trims[:3] == (marked.k_start, marked.k_end, marked.need)
        )

    def finish(self, rate: float) -> pa.Table:
        """The readings, their durations at the scan's sample ``rate`` (Hz)."""
        assert self.marked is not None
        self.marked.stations.rate = rate
        return self.marked.finish()


def _signals(scan: _Scan) -> list[str]:
    return [name for name in SIGNALS if scan.data(name)]


def _rate(samples: TableStream, scan: _Scan) -> float:
    """The sample rate (Hz) as :func:`~pipeline.gyrocompass.readings._sample_rate` gives it
    for the whole column; a non-uniform step is described from one more pass over the times."""
    if scan.rows < 2:
        raise ValueError(too_few(scan.rows))
    dt = float(scan.last - scan.first) / (scan.rows - 1)
    tol = UNIFORM_RTOL * dt
    if abs(scan.high - dt) <= tol and abs(scan.low - dt) <= tol:
        return 1.0 / dt
    time = np.concatenate([batch.column("time").to_numpy() for batch in samples])
    raise ValueError(not_uniform(time))


class _Stations:
    """Readings reduced as their samples arrive; each station's MD (the median over all its
    averaged samples) when the station ends."""

    def __init__(self, columns: list[str], rate: float) -> None:
        self.columns, self.rate = columns, rate
        self.parts: list[dict[str, np.ndarray]] = []
        """the readings so far, a group of them at a time"""
        self.md: list[FloatArray] = []
        """the current station's averaged MD samples (views of the batches' columns)"""
        self.medians: list[FloatArray] = []
        """each station's MD, repeated for its readings"""
        self.station = -1
        self.last: tuple[int, int, float, float, int, float, bool] | None = None
        """the dwell the recording ended in: station, position, first and last time (s),
        samples left after trimming, median MD (m), whether averaged"""
        self.renumber: IndexArray | None = None
        """the station numbers the readings take (``renumber[station]``: unread stops
        counted), when detected"""
        self.unread: list[UnreadStop] = []

    def add(
        self,
        station: IndexArray,
        position: IndexArray,
        values: dict[str, FloatArray],
        a: IndexArray,
        b: IndexArray,
    ) -> None:
        """Readings of the samples [a, b) of the columns ``values`` (in time order, none
        overlapping), of the markers ``station`` and ``position``."""
        signals = {k: values[k] for k in SIGNALS if k in values}
        part: dict[str, np.ndarray] = {"station": station, "position": position}
        part |= reading_stats(signals, values["time"], values.get("frame_angle"), a, b)
        self.parts.append(part)
        md = values["md"]
        for s, i, j in zip(station.tolist(), a.tolist(), b.tolist(), strict=True):
            if s != self.station:
                self.close()
                self.station = s
            self.md.append(md[i:j])

    def close(self) -> None:
        """The current station's MD (as the whole-table path takes it)."""
        if self.md:
            md = exact_median(self.md)
            self.medians.append(np.full(len(self.md), md))
        self.md = []

    def numbered(self, station: IndexArray) -> IndexArray:
        """The numbers the readings give ``station`` (:attr:`renumber`)."""
        return station if self.renumber is None else self.renumber[station]

    def table(self) -> pa.Table:
        """Every station's readings, their durations at the rate set now (:class:`_MarkedAhead`
        reduces at the first batch's rate; the scan's is the run's), and the dwell the
        recording ended in (:attr:`last`) in the schema metadata."""
        self.close()
        if not self.parts and self.last is not None:  # the whole-table path's messages
            _, _, start, end, left, _, _ = self.last
            raise ValueError(only_stop(start, end, left / self.rate))
        if not self.parts:
            none = np.empty(0, np.intp)
            reduce_readings({}, np.empty(0), self.rate, np.empty(0), None, *[none] * 4)
        columns: dict[str, np.ndarray] = {
            k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]
        }
        columns = {
            "station": self.numbered(columns.pop("station")),
            "md": np.concatenate(self.medians),
            "position": columns.pop("position"),
            **columns,
        }
        columns["duration"] = columns["n"] / self.rate
        table = attach_unread(PositionReadings.compiled().make_table(columns), self.unread)
        if self.last is None:
            return table
        s, position, start, end, left, md, kept = self.last
        station = int(self.numbered(np.array([s]))[0])
        md = station_md(table, station, md)
        return attach(
            table, RecordingEnd(station, position, md, start, end, left / self.rate, kept)
        )


def _arrays(batch: pa.RecordBatch, names: Iterable[str]) -> dict[str, FloatArray]:
    return {n: batch.column(n).to_numpy(zero_copy_only=False) for n in names}


class _Marked:
    """Runs of equal (station, position) markers: each run of marked samples a reading."""

    def __init__(self, options: ReadingOptions, rate: float, stations: _Stations) -> None:
        self.k_start, self.k_end, self.need, _ = counts(options, rate)
        self.stations = stations
        self.current: dict[str, FloatArray] = {}
        """the samples of the run that the last batch ended in (marked runs only)"""
        self.key = (-1, -1)
        self.runs: list[tuple[int, int, float, int]] = []
        """every marked run: station, position, first time, samples left after trimming"""
        self.orphans = 0

    def run(self, samples: TableStream) -> pa.Table:
        """Readings of the marked runs of one pass over ``samples`` (:meth:`finish`)."""
        for batch in samples:
            self.add(batch)
        return self.finish()

    def add(self, batch: pa.RecordBatch) -> None:
        """Cut the next batch into runs of equal markers: the runs that end in it are
        reduced (those wholly inside it together), the last one is kept for the next."""
        if batch.num_rows == 0:
            return
        station, position = (
            batch.column(m).fill_null(-1).to_numpy().astype(np.int64, copy=False) for m in MARKERS
        )
        values = _arrays(batch, self.stations.columns)
        change = np.flatnonzero((station[1:] != station[:-1]) | (position[1:] != position[:-1]))
        starts = np.concatenate([[0], change + 1])
        ends = np.concatenate([change + 1, [batch.num_rows]])
        orphan = (station[starts] < 0) & (position[starts] >= 0)  # runs of equal markers
        self.orphans += int((ends - starts)[orphan].sum())
        key = (int(station[0]), int(position[0]))
        if key != self.key:
            self.end_run()
            self.key = key
        self._extend(values, 0, int(ends[0]))
        if starts.size == 1:
            return
        self.end_run()
        inner = slice(1, -1)
        self._reduce(
            values, station[starts[inner]], position[starts[inner]], starts[inner], ends[inner]
        )
        self.key = (int(station[starts[-1]]), int(position[starts[-1]]))
        self._extend(values, int(starts[-1]), batch.num_rows)

    def _extend(self, values: dict[str, FloatArray], a: int, b: int) -> None:
        """The samples [a, b) of the batch's columns added to the current run (if marked)."""
        if self.key[0] < 0 or self.key[1] < 0:
            return  # unmarked samples are not kept
        part = {k: v[a:b] for k, v in values.items()}
        self.current = (
            {k: np.concatenate([self.current[k], part[k]]) for k in part} if self.current else part
        )

    def _reduce(
        self,
        values: dict[str, FloatArray],
        station: IndexArray,
        position: IndexArray,
        starts: IndexArray,
        ends: IndexArray,
    ) -> None:
        """The runs [starts, ends) of the columns ``values``: the marked ones recorded, the
        long enough among them reduced."""
        marked = (station >= 0) & (position >= 0)
        station, position = station[marked], position[marked]
        starts, ends = starts[marked], ends[marked]
        left = ends - starts - self.k_start - self.k_end
        t0 = values["time"][starts]
        self.runs.extend(
            zip(station.tolist(), position.tolist(), t0.tolist(), left.tolist(), strict=True)
        )
        keep = left >= self.need
        if keep.any():
            a, b = starts[keep] + self.k_start, ends[keep] - self.k_end
            self.stations.add(station[keep], position[keep], values, a, b)

    def finish(self) -> pa.Table:
        """The readings; before them the whole-table path's checks of the markers (orphans,
        a position marked twice, positions too short but the last one, which the recording
        ended in), in its order."""
        last = self.current
        self.end_run()
        if last:  # the recording ended in this run
            s, p, start, n = self.runs[-1]
            md, end = float(np.median(last["md"])), float(last["time"][-1])
            self.stations.last = (s, p, start, end, max(n, 0), md, n >= self.need)
        if self.orphans:
            raise ValueError(f"{self.orphans} samples have a position marker but no station marker")
        seen = Counter((s, p) for s, p, _, _ in self.runs)
        repeated = sorted(k for k, times in seen.items() if times > 1)
        if repeated:
            raise ValueError(
                "markers label a (station, position) in separate runs of samples: "
                + "; ".join(
                    f"station {s} position {p} at t = "
                    + ", ".join(f"{t:g}" for s2, p2, t, _ in self.runs if (s2, p2) == (s, p))
                    + " s"
                    for s, p in repeated
                )
            )
        if self.runs:
            station, position, t0, left = (np.array(c) for c in zip(*self.runs, strict=True))
            problem = remarked_stations(station, t0)
            if problem:
                raise ValueError(problem)
            whole = slice(None, -1) if last and left[-1] < self.need else slice(None)
            check_lengths(left[whole], self.need, t0[whole], station[whole], position[whole])
        return self.stations.table()

    def end_run(self) -> None:
        """The current run ended: recorded, and reduced if long enough."""
        run, self.current = self.current, {}
        if not run:
            return
        station, position = (np.array([k], dtype=np.intp) for k in self.key)
        ends = np.array([len(run["time"])], dtype=np.intp)
        self._reduce(run, station, position, np.zeros(1, np.intp), ends)


class _Detected:
    """Dwells found as :func:`~pipeline.gyrocompass.readings._detect_dwells` finds them, on a
    buffer that slides along the stream."""

    def __init__(self, options: ReadingOptions, rate: float, stations: _Stations) -> None:
        self.k_start, self.k_end, self.need, self.window = counts(options, rate)
        self.length = self.k_start + self.need + self.k_end
        self.end_stop = end_stop_count(options, rate)
        self.tolerances = (options.angle_tolerance, options.md_tolerance)
        self.gap = options.station_gap
        self.stations = stations
        self.buffer: dict[str, FloatArray] = {}
        self.base = 0
        """sample number of the buffer's first sample"""
        self.resume = 0
        """the next dwell starts here or later (sample number)"""
        self.open: int | None = None
        """start of a dwell whose end is not yet in the buffer"""
        self.stop = np.nan
        """smoothed MD at the previous dwell's start"""
        self.span = (-np.inf, np.inf)
        """highest and lowest smoothed MD from the previous dwell's start to ``resume``"""
        self.station = self.position = -1
        self.numbering = (self.station, self.position, self.stop, self.span)
        """the numbering before the open dwell's start: taken back if the tool crept
        through it (:meth:`dwell`)"""
        self.found: list[tuple[int, int, float, int]] = []
        """every dwell and the steady end of the recording cut short: first and end sample
        number, smoothed MD at the first (m), station (:class:`~pipeline.gyrocompass.stops.
        Dwells`)"""
        self.stops = _StopFinder(options, rate)
        self.rate, self.terms = rate, stop_terms(options, rate)

    def run(self, samples: TableStream) -> pa.Table:
        for batch in samples:
            fresh = _arrays(batch, self.stations.columns)
            self.buffer = (
                {k: np.concatenate([self.buffer[k], fresh[k]]) for k in fresh}
                if self.buffer
                else fresh
            )
            self.step(final=False)
        self.step(final=True)
        placed = self.placed()
        self.stations.renumber = placed.renumber
        self.stations.unread = unread_records(placed, self.rate, *self.terms)
        return self.stations.table()

    def placed(self) -> Placed:
        """The stops the MD held without a dwell, among the dwells (:func:`~pipeline.
        gyrocompass.stops.place`)."""
        found = self.found

        def column(i: int) -> IndexArray:
            return np.array([d[i] for d in found], dtype=np.intp)

        md = np.array([d[2] for d in found], dtype=np.float64)
        return place(Dwells(column(0), column(1), md, column(3)), self.stops.found, self.gap)

    def step(self, *, final: bool) -> None:
        """Find every dwell the buffer settles, then drop the samples no longer needed."""
        if not self.buffer:
            return
        size = len(self.buffer["time"])
        angle = np.unwrap(self.buffer["frame_angle"], period=360.0)
        smooth = moving_average(self.buffer["md"], self.window)
        signals = (angle, smooth)
        limit = size if final else size - self.window  # smoothing settled below this
        self.stops.step(self.buffer, smooth, self.base, limit, final=final)
        while True:
            if self.open is None:
                start = self.start(signals, smooth, limit, final)
                if start is None:
                    break
                self.open = start
            end = self.end(signals, self.open - self.base, limit, final)
            if end is None:
                break
            self.dwell(self.open - self.base, end, smooth, final=end == size)
            self.open, self.resume = None, self.base + end
        needed = min(self.open if self.open is not None else self.resume, self.stops.needed())
        keep = max(needed - self.window, self.base)
        self.buffer = {k: v[keep - self.base :] for k, v in self.buffer.items()}
        self.base = keep

    def start(
        self, signals: tuple[FloatArray, ...], smooth: FloatArray, limit: int, final: bool
    ) -> int | None:
        """The next dwell's start (sample number), its station and position numbered; None
        when the buffer does not settle it yet (the search resumes farther on)."""
        r = self.resume - self.base
        window = tuple(x[r:limit] for x in signals)
        found = steady_starts(window, self.tolerances, self.length)
        if found.size == 0 and final:
            self.tail(signals, smooth, r, limit)
        if found.size == 0:
            until = limit if final else max(r, limit - self.length + 1)
            self._fold(smooth[r:until])
            self.resume = self.base + until
            return None
        s = r + int(found[0])
        self._fold(smooth[r:s])
        self._number(float(smooth[s]))
        self.resume = self.base + s
        return self.base + s

    def _number(self, stop: float) -> None:
        """Number the dwell whose smoothed MD at its start is ``stop`` (m)."""
        self.numbering = (self.station, self.position, self.stop, self.span)
        high, low = self.span[0] - self.stop, self.stop - self.span[1]
        if self.station < 0 or abs(stop - self.stop) > self.gap or max(high, low) > self.gap:
            self.station, self.position = self.station + 1, 0
        else:
            self.position += 1
        self.stop, self.span = stop, (-np.inf, np.inf)

    def tail(self, signals: tuple[FloatArray, ...], smooth: FloatArray, r: int, end: int) -> None:
        """At the end of the recording, from buffer index ``r`` (after the last dwell) to
        ``end``: a steady end too short for a dwell (as the whole-table path finds it) is
        numbered and recorded, unaveraged."""
        begin = max(r, end - self.length)
        s = begin + steady_tail(tuple(x[begin:end] for x in signals), self.tolerances)
        if end - s < self.end_stop:
            return
        self._fold(smooth[r:s])
        self._number(float(smooth[s]))
        self.found.append((self.base + s, self.base + end, self.stop, self.station))
        self.ended(s, end, kept=False)

    def ended(self, s: int, e: int, *, kept: bool) -> None:
        """Record the dwell of buffer indices [s, e) as the one the recording ended in."""
        time = self.buffer["time"]
        left = max(e - s - self.k_start - self.k_end, 0)
        md = float(np.median(self.buffer["md"][s:e]))
        last = (self.station, self.position, float(time[s]), float(time[e - 1]), left, md, kept)
        self.stations.last = last

    def end(self, signals: tuple[FloatArray, ...], s: int, limit: int, final: bool) -> int | None:
        """Where the dwell from buffer index ``s`` ends (buffer index); None if not yet."""
        begin = s + self.length
        out = np.zeros(max(limit - begin, 0), dtype=bool)
        for x, tol in zip(signals, self.tolerances, strict=True):
            level = float(np.median(x[s:begin]))
            out |= np.abs(x[begin:limit] - level) > tol
        if out.any():
            return begin + int(np.argmax(out))
        return limit if final else None

    def dwell(self, s: int, e: int, smooth: FloatArray, *, final: bool) -> None:
        """The dwell of buffer indices [s, e): its still samples averaged (``final``: the
        recording ended in it), or, too few (the tool crept through it), not a dwell."""
        a, b = still_span(self.buffer["md"], s, e, self.window)
        if b - a - self.k_start - self.k_end < self.need:
            self.station, self.position, self.stop, self.span = self.numbering
            self._fold(smooth[s:e])
            return
        self.found.append((self.base + s, self.base + e, self.stop, self.station))
        self._fold(smooth[s:e])
        first, end = (np.array([i], dtype=np.intp) for i in (a + self.k_start, b - self.k_end))
        station, position = (np.array([k], dtype=np.intp) for k in (self.station, self.position))
        self.stations.add(station, position, self.buffer, first, end)
        if final:
            self.ended(a, b, kept=True)

    def _fold(self, values: FloatArray) -> None:
        if values.size:
            self.span = (max(self.span[0], values.max()), min(self.span[1], values.min()))


class _StopFinder:
    """Stops of the smoothed MD (:func:`~pipeline.gyrocompass.readings.md_stops`, as
    :class:`_Detected` finds dwells) on its buffer: only the samples from :meth:`needed` on
    are looked at again, and an open stop keeps the odometer MD it has passed (its median)."""

    def __init__(self, options: ReadingOptions, rate: float) -> None:
        self.length = stop_count(options, rate)
        self.tolerance = options.md_tolerance
        self.found: list[Stop] = []
        self.resume = 0
        """the next stop starts here or later (sample number)"""
        self.open: tuple[int, float, float] | None = None
        """the open stop's first sample number, its time (s) and its level (m: the median
        smoothed MD over its first ``length`` samples)"""
        self.checked = 0
        """the open stop's end is not before this sample number"""
        self.md: list[FloatArray] = []
        """the open stop's odometer MD up to :attr:`checked`"""

    def needed(self) -> int:
        """The first sample number the next step looks at."""
        return self.checked if self.open is not None else self.resume

    def step(
        self, buffer: dict[str, FloatArray], smooth: FloatArray, base: int, limit: int, final: bool
    ) -> None:
        """Find the stops the buffer (first sample number ``base``; smoothing settled below
        buffer index ``limit``) settles."""
        md, time = buffer["md"], buffer["time"]
        while True:
            if self.open is None:
                r = self.resume - base
                found = steady_starts((smooth[r:limit],), (self.tolerance,), self.length)
                if found.size == 0:
                    self.resume = base + (limit if final else max(r, limit - self.length + 1))
                    return
                s = r + int(found[0])
                level = float(np.median(smooth[s : s + self.length]))
                self.open, self.checked = (base + s, float(time[s]), level), base + s
                self.md = []
            first, t0, level = self.open
            b = max(self.checked - base, first - base + self.length)
            self.md.append(md[self.checked - base : b].copy())
            out = np.abs(smooth[b:limit] - level) > self.tolerance
            if not out.any() and not final:
                self.md.append(md[b:limit].copy())
                self.checked = base + max(b, limit)
                return
            e = b + int(np.argmax(out)) if out.any() else limit
            self.md.append(md[b:e])
            median = float(np.median(np.concatenate(self.md)))
            self.found.append(Stop(first, base + e, median, t0, float(time[e - 1])))
            self.open, self.md, self.resume = None, [], base + e

"""Stops the tool made that gave no reading (a point survey's dwells detected from the
signals, :mod:`pipeline.gyrocompass.readings`).

A *dwell* needs the frame angle and the MD steady together for ``trim_start + min_dwell +
trim_end``. A *stop* is the tool holding its depth, found from the MD alone: it starts at
the first sample from which the smoothed MD stays within ``md_tolerance`` of its value
there for ``stop_hold`` seconds, and ends at the first sample where it leaves
``md_tolerance`` around its median over that first stretch (a dwell's rule, on the MD
only). Every station's stop holds its dwells. A stop is *unread* when:

- it overlaps no dwell and not the steady end of the recording (a frame position the end
  cut short: :mod:`~pipeline.gyrocompass.recording_end` reports it), and
- its MD (the median over the stop) is more than ``station_gap`` from the stop MD of the
  dwell before it and of the dwell after it (else the tool shifted at that station, which
  was read).

Consecutive unread stops within ``station_gap`` of each other are one. Each is numbered
as a station in its place — the later stations' numbers count it, as they would had it
been read — gets no reading, and is recorded (:class:`UnreadStop`) in the readings
table's schema metadata under :data:`KEY`, for the validity checks to drop it by name
(check ``unread_stop``). Marked samples (station/position markers) are not searched: the
markers say where the stations are."""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]

KEY = b"gyropipe.unread_stops"
"""Schema metadata of PositionReadings: the unread stops as a JSON list of
:class:`UnreadStop` (absent: none)."""


@dataclass(frozen=True)
class Stop:
    """A stop found from the MD: its first and end sample (end exclusive), median MD (m)
    and first and last sample time (s)."""

    start: int
    end: int
    md: float
    t0: float
    t1: float


@dataclass(frozen=True)
class UnreadStop:
    """A stop the tool made without a dwell to read: its station number, MD (m, the median
    odometer MD over the stop), first and last sample time (s), how long the depth held (s)
    and, from the readings' options, the steady time a reading needs (s: the trims and
    ``min_dwell``), ``min_dwell`` (s) and the angle (deg) and MD (m) tolerances of a dwell."""

    station: int
    md: float
    start: float
    end: float
    held: float
    need: float
    min_dwell: float
    angle_tolerance: float
    md_tolerance: float

    def reason(self) -> str:
        """Why the stop has no reading, with the numbers."""
        found = (
            f"no dwell of ≥ {self.need:.1f} s (min_dwell {self.min_dwell:g} s after the "
            f"trims) found at MD {self.md:.2f} m"
        )
        if self.held < self.need:
            return (
                f"{found}: the tool held depth there for only {self.held:.1f} s "
                f"(t = {self.start:.1f}–{self.end:.1f} s)"
            )
        return (
            f"{found}: the tool held depth there for {self.held:.1f} s (t = {self.start:.1f}–"
            f"{self.end:.1f} s), but its frame angle did not stay within "
            f"{self.angle_tolerance:g}° (and its MD within {self.md_tolerance:g} m, at rest) for "
            f"{self.need:.1f} s of it: the frame still turning, or the tool vibrating or "
            "creeping"
        )


@dataclass(frozen=True)
class Dwells:
    """The dwells found (with the steady end of the recording, when one is cut short), in
    time order: first and end sample, smoothed MD at the first sample (m), station."""

    start: IndexArray
    end: IndexArray
    md: FloatArray
    station: IndexArray


@dataclass(frozen=True)
class Placed:
    """The unread stops, each with its station number, and the new number of every station
    of the dwells (``renumber[old]``)."""

    unread: list[tuple[Stop, int]]
    renumber: IndexArray


def place(dwells: Dwells, stops: Sequence[Stop], gap: float) -> Placed:
    """Which of ``stops`` are unread and where they are numbered (module docstring);
    ``gap``: ``station_gap``, m."""
    groups: list[tuple[int, list[Stop]]] = []  # (the dwell before, its stops)
    n = dwells.start.size
    for stop in stops:
        k = int(np.searchsorted(dwells.start, stop.end))  # dwells starting before its end
        if k and dwells.end[k - 1] > stop.start:
            continue  # overlaps a dwell: read
        if k and abs(stop.md - dwells.md[k - 1]) <= gap:
            continue
        if k < n and abs(dwells.md[k] - stop.md) <= gap:
            continue
        if groups and groups[-1][0] == k - 1 and abs(groups[-1][1][-1].md - stop.md) <= gap:
            groups[-1][1].append(stop)
        else:
            groups.append((k - 1, [stop]))
    after = np.array([dwells.station[k] if k >= 0 else -1 for k, _ in groups], dtype=np.intp)
    stations = int(dwells.station.max()) + 1 if n else 0
    old = np.arange(stations, dtype=np.intp)
    renumber: IndexArray = old + np.searchsorted(after, old, side="left").astype(np.intp)
    unread = [
        (_merged(members), int(a) + 1 + i)
        for i, (a, (_, members)) in enumerate(zip(after, groups, strict=True))
    ]
    return Placed(unread, renumber)


def _merged(stops: list[Stop]) -> Stop:
    """Consecutive stops of one unread station as one: from the first's start to the last's
    end, at the longest's MD."""
    longest = max(stops, key=lambda s: s.end - s.start)
    return Stop(stops[0].start, stops[-1].end, longest.md, stops[0].t0, stops[-1].t1)


def unread_records(
    placed: Placed,
    rate: float,
    need: float,
    min_dwell: float,
    angle_tolerance: float,
    md_tolerance: float,
) -> list[UnreadStop]:
    """The unread stops of ``placed`` as recorded (``rate``: sample rate, Hz; the rest the
    readings' options, s, deg and m)."""
    return [
        UnreadStop(
            station,
            stop.md,
            stop.t0,
            stop.t1,
            (stop.end - stop.start) / rate,
            need,
            min_dwell,
            angle_tolerance,
            md_tolerance,
        )
        for stop, station in placed.unread
    ]


def attach_unread(readings: pa.Table, unread: Sequence[UnreadStop]) -> pa.Table:
    """``readings`` with ``unread`` recorded in the schema metadata (nothing where none)."""
    if not unread:
        return readings
    text = json.dumps([asdict(u) for u in unread]).encode()
    return readings.replace_schema_metadata({**(readings.schema.metadata or {}), KEY: text})


def unread_stops(readings: pa.Table) -> list[UnreadStop]:
    """The unread stops recorded in ``readings``' schema metadata (none recorded: [])."""
    raw = (readings.schema.metadata or {}).get(KEY)
    if raw is None:
        return []
    return [
        UnreadStop(
            station=int(u["station"]),
            md=float(u["md"]),
            start=float(u["start"]),
            end=float(u["end"]),
            held=float(u["held"]),
            need=float(u["need"]),
            min_dwell=float(u["min_dwell"]),
            angle_tolerance=float(u["angle_tolerance"]),
            md_tolerance=float(u["md_tolerance"]),
        )
        for u in json.loads(raw)
    ]

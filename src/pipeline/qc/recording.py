"""Checks of what a survey's recording of its stops holds (a point survey's stations, a
continuous run's two stops), beside the sensors: the frame position the recording ended in
(``recording_end``), the positions each station has (``missing_positions``) and the stops
that gave no reading (``unread_stop``).

- ``recording_end``: one row for the dwell the readings record as cut off by the end of the
  recording (:mod:`pipeline.gyrocompass.recording_end`): how much less time it was averaged
  over than the survey's usual (the median averaging time of the other readings, s) — all of
  it when it was too short to average — against the limit.
- ``missing_positions``: one row per station (the station of an unaveraged last dwell too,
  when it has no reading): how many frame positions it lacks of the survey's usual number
  (the most common number of positions at its stations); not the unread stops', which
  have their own check.
- ``unread_stop``: one row per stop the readings record as made but not read
  (:mod:`pipeline.gyrocompass.stops`: the depth held, no dwell): 1 stop unread against
  none, the reason with its numbers in the detail; by default its station is dropped, so
  the run names it among the stations it recorded but dropped.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.positions import usual_positions
from pipeline.gyrocompass.recording_end import RecordingEnd, recording_end, shortfall
from pipeline.gyrocompass.stops import UnreadStop, unread_stops
from pipeline.qc.options import QcOptions
from pipeline.qc.vector_checks import IntArray, Keys, Rows, limit_rows


def recording_checks(
    readings: pa.Table, options: QcOptions, station: IntArray, md: FloatArray
) -> tuple[list[Rows], IntArray, FloatArray]:
    """The rows of the checks (module docstring) for the readings of ``station`` at ``md``
    (m, of each reading), and the station and MD of each reading with, after them, the
    station of an unaveraged last dwell that has no reading and those of the unread stops
    (the stations to summarise)."""
    end = recording_end(readings)
    listed, at = station, md
    if end is not None and not np.isin(end.station, station):
        listed, at = np.append(station, end.station), np.append(md, end.md)
    rows = [_positions(station, listed, at, options, end)]
    if end is not None:
        rows.insert(0, _end(readings, end, options))
    unread = unread_stops(readings)
    if unread:
        rows.append(_unread(unread, options))
        listed = np.append(listed, [u.station for u in unread])
        at = np.append(at, [u.md for u in unread])
    return rows, listed, at


def _unread(unread: list[UnreadStop], options: QcOptions) -> Rows:
    """The ``unread_stop`` row of every unread stop."""
    n = len(unread)
    nan = np.full(n, np.nan)
    keys = Keys(
        np.array([u.station for u in unread]), np.full(n, -1), np.array([u.md for u in unread]),
        nan, nan,
    )  # fmt: skip
    zero = np.zeros(n)
    detail = np.array([u.reason() for u in unread], dtype=object)
    tolerance = options.unread_stop.of(zero, zero)
    return Rows("unread_stop", "stops", np.ones(n), zero, tolerance, np.ones(n, bool), detail, keys)


def _end(readings: pa.Table, end: RecordingEnd, options: QcOptions) -> Rows:
    """The ``recording_end`` row of the dwell the recording ended in."""
    usual, short = shortfall(readings, end)
    keys = Keys(
        np.array([end.station]),
        np.array([end.position]),
        np.array([end.md]),
        np.full(1, np.nan),
        np.full(1, np.nan),
    )
    rows = limit_rows("recording_end", "s", "", np.array([short]), options.recording_end, keys)
    ended = f"the recording ended {end.end - end.start:.2f} s into this frame position"
    if np.isnan(usual):
        rows.detail[0] = f"{ended}; no other frame position to compare its averaging time with"
    elif end.kept:
        rows.detail[0] = (
            f"{ended}: averaged over {end.averaged:.2f} s, the survey's other positions over "
            f"{usual:.2f} s (median)"
        )
    else:
        rows.detail[0] = (
            f"{ended}: {end.averaged:.2f} s left after trimming, too short to average, so the "
            f"position is missing (the survey's other positions: {usual:.2f} s, median)"
        )
    return rows


def _positions(
    station: IntArray,
    listed: IntArray,
    md: FloatArray,
    options: QcOptions,
    end: RecordingEnd | None,
) -> Rows:
    """The ``missing_positions`` row of every station of ``listed`` (at ``md``, m), from the
    ``station`` of each reading."""
    ids, first = np.unique(listed, return_index=True)
    held = dict(zip(*np.unique(station, return_counts=True), strict=True))
    have = np.array([held.get(s, 0) for s in ids])
    usual = usual_positions(station)
    missing = np.maximum(usual - have, 0).astype(float)
    nan = np.full(ids.size, np.nan)
    keys = Keys(ids, np.full(ids.size, -1), md[first], nan, nan)
    tolerance = options.missing_positions.of(np.zeros(ids.size), np.zeros(ids.size))
    detail = np.full(ids.size, "", dtype=object)
    rows = Rows(
        "missing_positions",
        "positions",
        missing,
        np.zeros(ids.size),
        tolerance,
        np.ones(ids.size, dtype=bool),
        detail,
        keys,
    )
    for i in np.flatnonzero(rows.failed):
        detail[i] = (
            f"{have[i]} of the survey's usual {usual} frame positions (the most common number "
            "at its stations): "
            + (
                "compassing has fewer positions to solve it from than at its neighbours"
                if have[i]
                else "none was averaged, the station is not surveyed"
            )
        )
        if end is not None and ids[i] == end.station:
            detail[i] += "; the recording ended during it"
    return rows

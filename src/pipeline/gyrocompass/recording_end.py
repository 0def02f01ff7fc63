"""The frame position a survey's recording ended in (a point survey's last station, a
continuous run's closing stop).

When the recording stops while the tool is still at a stop (the logger stopped early, the
file was truncated, the last positions were never recorded), the last dwell ends at the
last sample, not at a frame move or a change of markers: it may be shorter than the
survey's other dwells, or too short to be averaged at all, and its station may lack
positions its neighbours have. Position readings record that dwell (:class:`RecordingEnd`)
in the readings table's schema metadata under :data:`KEY`, so that the validity checks can
flag it: a reading cannot carry a dwell that was never averaged.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass

import numpy as np
import pyarrow as pa

KEY = b"gyropipe.recording_end"
"""Schema metadata of PositionReadings: the :class:`RecordingEnd` as JSON (absent: the
recording did not end during a dwell)."""


@dataclass(frozen=True)
class RecordingEnd:
    """The dwell the recording ended in: its station and position numbers, MD (m: the
    station's reading MD, or the dwell's median MD where the station has no reading), first
    and last sample time (s), the averaging time left after trimming (s, 0 when none) and
    whether it was averaged into a reading (False: shorter than ``min_dwell``, dropped)."""

    station: int
    position: int
    md: float
    start: float
    end: float
    averaged: float
    kept: bool

    def where(self) -> str:
        """The dwell in words: its stop's MD and its position (numbered from 1)."""
        return f"frame position {self.position + 1} of the stop at MD {self.md:.2f} m"


def attach(readings: pa.Table, end: RecordingEnd | None) -> pa.Table:
    """``readings`` with ``end`` recorded in the schema metadata (nothing where None)."""
    if end is None:
        return readings
    meta = {**(readings.schema.metadata or {}), KEY: json.dumps(asdict(end)).encode()}
    return readings.replace_schema_metadata(meta)


def recording_end(readings: pa.Table) -> RecordingEnd | None:
    """The dwell recorded in ``readings``' schema metadata (None: none recorded)."""
    raw = (readings.schema.metadata or {}).get(KEY)
    if raw is None:
        return None
    fields = json.loads(raw)
    return RecordingEnd(
        station=int(fields["station"]),
        position=int(fields["position"]),
        md=float(fields["md"]),
        start=float(fields["start"]),
        end=float(fields["end"]),
        averaged=float(fields["averaged"]),
        kept=bool(fields["kept"]),
    )


def station_md(readings: pa.Table, station: int, fallback: float) -> float:
    """MD (m) of ``station`` in ``readings``; ``fallback`` where it has no reading."""
    ids = readings.column("station").to_numpy()
    rows = np.flatnonzero(ids == station)
    return float(readings.column("md")[int(rows[0])].as_py()) if rows.size else fallback


def shortfall(readings: pa.Table, end: RecordingEnd) -> tuple[float, float]:
    """The survey's usual averaging time (s: the median ``duration`` of the readings other
    than ``end``'s; NaN without any) and how much less ``end`` was averaged over (s, ≥ 0;
    all of it when it was not averaged)."""
    own = (readings.column("station").to_numpy() == end.station) & (
        readings.column("position").to_numpy() == end.position
    )
    if "duration" in readings.column_names:
        duration = readings.column("duration").to_numpy(zero_copy_only=False).astype(float)
    else:
        duration = np.full(readings.num_rows, np.nan)
    others = duration[~own] if end.kept else duration
    usual = float(np.median(others)) if others.size else float("nan")
    return usual, max(usual - end.averaged, 0.0) if end.kept else usual


def dropped_warning(end: RecordingEnd, min_dwell: float) -> str:
    """What a warning says of a dwell too short to average at the end of the recording."""
    return (
        f"the recording ended {end.end - end.start:.2f} s into {end.where()} (station "
        f"{end.station}): {end.averaged:.2f} s left after trimming, less than min_dwell "
        f"{min_dwell:g} s, so it was not averaged; the station lacks that position"
    )

"""A stations (or trajectory) table as arrays: where its surveys start, its angles and the
north reference of a column.

Shared by the stages that integrate or annotate stations and by the writers and report
sections that walk a table survey by survey.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pipeline.contracts import NORTH_KEY


def survey_offsets(stations: pa.Table) -> np.ndarray:
    """CSR offsets of the contiguous surveys of a stations table (one survey if no ids)."""
    n = stations.num_rows
    if "survey" not in stations.column_names or n == 0:
        return np.array([0, n])
    ids = stations.column("survey").to_numpy(zero_copy_only=False)
    starts = np.flatnonzero(ids[1:] != ids[:-1]) + 1
    return np.concatenate(([0], starts, [n]))


def north_reference_of(table: pa.Table, column: str) -> str:
    """The north reference stored in a column's field metadata."""
    raw: bytes = (table.schema.field(column).metadata or {})[NORTH_KEY]
    return raw.decode()


def station_angles(stations: pa.Table) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MD (m), inclination and azimuth (deg, azimuth wrapped into [0, 360)) of a table."""
    md = stations.column("md").to_numpy().astype(np.float64)
    inc = stations.column("inc").to_numpy().astype(np.float64)
    azi = np.mod(stations.column("azi").to_numpy().astype(np.float64), 360.0)
    azi[azi >= 360.0] = 0.0  # mod of a tiny negative number rounds up to 360
    return md, inc, azi


def defined_azimuths(azi: np.ndarray) -> np.ndarray:
    """Azimuths (any angle unit) with each undefined one (NaN, a vertical station) taken as
    the next defined station's — the direction the hole leaves vertical in — else the
    previous one's, else 0. At inclination 0 the azimuth moves nothing, so this only names
    a direction where a formula needs one (an error model's weights); one survey's array."""
    azi = np.asarray(azi, dtype=np.float64)
    undefined = np.isnan(azi)
    if not undefined.any():
        return azi
    if undefined.all():
        return np.zeros_like(azi)
    index = np.arange(azi.size)
    defined = index[~undefined]
    after = np.minimum(np.searchsorted(defined, index), defined.size - 1)
    before = np.maximum(np.searchsorted(defined, index, side="right") - 1, 0)
    take = np.where(defined[after] >= index, defined[after], defined[before])
    return np.where(undefined, azi[take], azi)

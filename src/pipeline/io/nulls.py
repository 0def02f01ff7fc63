"""The null markers of the industry's exports: ``-999.25`` and its family.

LAS writes ``-999.25`` (or ``-9999.25``) where a value is missing, and vendors' CSV and
WITSML exports copy the habit, in angles with either sign (a ``stnGridCorUsed`` of
``999.25`` rad on every station). Every reader takes these numbers, in the file's own unit
(before any conversion), as 'no value', never as a measurement: the negative ones in every
column, the positive ones in angles (and angle rates) only — an MD, TVD or displacement of
999.25 m is a real one. So a writer never writes one as a value (:func:`refuse_null_markers`:
the LAS, CSV and WITSML writers).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from pipeline.io.mnemonics import CURVES
from pipeline.io.precision import blocks

NULL_MARKERS: tuple[float, ...] = (-999.25, -9999.25)
"""Numbers that mean 'no value' in every column of every reader, whatever the header says."""
ANGLE_NULL_MARKERS: tuple[float, ...] = (*NULL_MARKERS, 999.25, 9999.25)
"""Numbers that mean 'no value' in an angle (no unit makes 999.25 a plausible angle)."""
_SMALLEST = 999.25


def is_null_marker(value: float, *, angle: bool) -> bool:
    """Whether ``value`` (in the file's unit) is a null marker of a column (an ``angle``
    or not)."""
    return value in (ANGLE_NULL_MARKERS if angle else NULL_MARKERS)


def value_range(values: Any) -> tuple[float, float] | None:
    """The smallest and largest value of a float64 Arrow array (or chunked array) without
    nulls, NaN if it holds one (by numpy over its buffers: ~20× faster than
    ``pyarrow.compute.min_max``); None when it is empty, holds nulls or is not float64."""
    if len(values) == 0 or values.null_count or not pa.types.is_float64(values.type):
        return None
    chunks = values.chunks if isinstance(values, pa.ChunkedArray) else [values]
    parts = [chunk.to_numpy() for chunk in chunks if len(chunk)]
    lows, highs = np.array([p.min() for p in parts]), np.array([p.max() for p in parts])
    return float(lows.min()), float(highs.max())  # numpy's, which carry a NaN


def null_markers(values: Any, *, angle: bool) -> np.ndarray | None:
    """Where a float Arrow array holds a null marker (of an ``angle`` column or not); None
    when nowhere (a min/max pass first: values within ±999.25 need no comparison each)."""
    if len(values) == 0 or values.null_count == len(values):
        return None
    extremes = value_range(values)
    if extremes is None:
        found = pc.min_max(values).as_py()
        extremes = found["min"], found["max"]
    if extremes[0] > -_SMALLEST and (not angle or extremes[1] < _SMALLEST):
        return None
    markers = ANGLE_NULL_MARKERS if angle else NULL_MARKERS
    mask = pc.is_in(values, value_set=pa.array(markers, values.type))
    found = np.asarray(pc.fill_null(mask, False).to_numpy(zero_copy_only=False), dtype=bool)
    return found if found.any() else None


def marked_rows(values: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Which rows of a 2-D float array (columns of one table as rows; NaN: no value) hold
    a null marker, each of an ``angle`` column (a bool per row) or not: as
    :func:`null_markers` tells a column, the rows' smallest and largest values first (NaN
    skipped), then the values of the rows beyond ±999.25 compared one by one."""
    found = np.zeros(len(values), dtype=bool)
    if values.size == 0:
        return found
    with np.errstate(invalid="ignore"):
        low, high = np.fmin.reduce(values, axis=1), np.fmax.reduce(values, axis=1)
    beyond = ~((low > -_SMALLEST) & (~angle | (high < _SMALLEST)))
    for row in np.flatnonzero(beyond):
        markers = ANGLE_NULL_MARKERS if angle[row] else NULL_MARKERS
        found[row] = bool(np.isin(values[row], markers).any())
    return found


def refuse_null_markers(values: dict[str, pa.Array]) -> None:
    """A value every reader takes for no value (-999.25…, and ±999.25 in an angle, a
    canonical column of an angle or a dogleg severity) cannot be written: it would read back
    as a null. A ValueError names the first column of ``values`` (by name; the float ones
    are looked at) holding one, a block of columns at a time
    (:func:`~pipeline.io.precision.blocks`)."""
    floats = [name for name, array in values.items() if pa.types.is_floating(array.type)]
    rows = len(values[floats[0]]) if floats else 0
    for block in blocks(floats, rows):
        stacked = np.stack([values[name].to_numpy(zero_copy_only=False) for name in block])
        angle = np.array([_is_angle(name) for name in block], dtype=bool)
        for name, marked, is_angle in zip(block, marked_rows(stacked, angle), angle, strict=True):
            if marked:
                markers = ANGLE_NULL_MARKERS if is_angle else NULL_MARKERS
                raise ValueError(
                    f"column {name!r} holds a null marker {markers}: every reader would read "
                    "it back as no value"
                )


def _is_angle(name: str) -> bool:
    return name in CURVES and CURVES[name].quantity in ("angle", "dogleg_severity")

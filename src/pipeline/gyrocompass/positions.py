"""The frame positions of multi-position gyrocompassing (DOMAIN.md §5): the standard scheme,
and a record's stations grouped by their number of positions."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from numpy.typing import NDArray

DEFAULT_POSITIONS = (0.0, 90.0, 180.0, 270.0, 0.0)
"""Frame positions of seed 004's five-position scheme, deg."""

IntArray = NDArray[np.intp]


def stacks(starts: IntArray, sizes: IntArray) -> Iterator[tuple[IntArray, IntArray]]:
    """The stations of each size (``sizes`` positions from row ``starts``, one station after
    the other): their indices and their positions' rows (stations, size). A sum or mean
    along axis 1 of a column taken at those rows is each station's as alone (numpy reduces
    each row as a 1-D array; ``np.add.reduceat`` adds in another order)."""
    for n in np.unique(sizes).tolist():
        members = np.flatnonzero(sizes == n)
        yield members, starts[members, None] + np.arange(n)


def usual_positions(station: IntArray) -> int:
    """The survey's usual number of frame positions per station, from the station of each
    reading: the most common number (the larger of equally common ones); 0 without
    readings."""
    if station.size == 0:
        return 0
    _, sizes = np.unique(station, return_counts=True)
    values, count = np.unique(sizes, return_counts=True)
    return int(values[count == count.max()].max())

"""Full-rate series reduced for drawing: the per-column minimum and maximum envelope.

A line through N samples drawn into a figure a few thousand pixels wide shows, in each
column of pixels, a vertical stroke from the column's lowest to its highest value. Keeping,
for each of :data:`COLUMNS` equal bins of x, the samples at the bin's minimum and maximum
(in their x order) draws the same strokes with at most ``2 × COLUMNS`` points, whatever N.

:class:`Envelope` is built batch by batch (a streamed port's record batches) in bounded
memory: the x range need not be known in advance — bins start narrow at the first batch
and are merged pairwise (their minima and maxima are exact) whenever the data outgrow them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

COLUMNS = 2048
"""Bins of an envelope: at least the device pixels across a report figure's axes as it is
shown or printed (6.5 in of vector line at 300 dpi is 1,950 dots); so a drawn line has at
most 4,096 points."""


class Envelope:
    """Per-bin minimum and maximum of y over equal bins of x, with the x of each."""

    def __init__(self, columns: int = COLUMNS) -> None:
        self.columns = columns
        self.origin = 0.0
        self.width = 0.0
        """bin width in x units (0: no sample yet)"""
        self.low = np.full(columns, np.inf)
        self.high = np.full(columns, -np.inf)
        self.x_low = np.zeros(columns)
        self.x_high = np.zeros(columns)
        self.samples = 0
        """finite samples added"""

    def add(self, x: FloatArray, y: FloatArray) -> None:
        """Fold the samples (x, y) in; non-finite ones are left out."""
        fold((self,), x, (y,))

    def _place(self, lo: float, hi: float) -> None:
        """Bins covering [lo, hi] (the first samples set their width)."""
        if self.width == 0.0:
            self.origin = lo
            self.width = max(hi - lo, abs(lo) * 1e-9, 1e-9) / (self.columns - 1)
        self._cover(lo, hi)

    def _fold(self, bins: NDArray[np.intp], x: FloatArray, y: FloatArray) -> None:
        """Fold in the kept samples (x, y) in ``bins`` (:func:`_bins`)."""
        for reduce, empty, best, beats, at in (
            (np.minimum, np.inf, self.low, np.less, self.x_low),
            (np.maximum, -np.inf, self.high, np.greater, self.x_high),
        ):
            values, first = _extremes(reduce, empty, y, bins, self.columns)
            better = beats(values, best)  # never a bin without samples (±inf)
            best[better] = values[better]
            at[better] = x[first[better]]
        self.samples += len(y)

    def _cover(self, lo: float, hi: float) -> None:
        """Widen the bins (merging 2^k at a time, keeping their edges) and move the origin
        back by whole bins until [lo, hi] is inside."""
        shift, factor = 0, 1
        while True:
            if lo < self.origin:
                shift = int(np.ceil((self.origin - lo) / self.width))
            origin = self.origin - shift * self.width
            if (hi - origin) / (self.width * factor) < self.columns:
                break
            factor *= 2
        if shift == 0 and factor == 1:
            return
        target = (np.arange(self.columns) + shift) // factor
        filled = np.flatnonzero(np.isfinite(self.low) & (target < self.columns))
        merged = []
        for reduce, empty, old, x_old in (
            (np.minimum, np.inf, self.low, self.x_low),
            (np.maximum, -np.inf, self.high, self.x_high),
        ):
            new, first = _extremes(reduce, empty, old[filled], target[filled], self.columns)
            merged += [new, np.append(x_old[filled], 0.0)[first]]  # x 0 in a bin left empty
        self.low, self.x_low, self.high, self.x_high = merged
        self.origin, self.width = origin, self.width * factor

    def points(self) -> tuple[FloatArray, FloatArray]:
        """The line to draw: each bin's minimum and maximum sample, in x order (one point
        where they are the same sample)."""
        used = np.flatnonzero(np.isfinite(self.low))
        x = np.column_stack([self.x_low[used], self.x_high[used]])
        y = np.column_stack([self.low[used], self.high[used]])
        swap = x[:, 1] < x[:, 0]
        x[swap], y[swap] = x[swap][:, ::-1], y[swap][:, ::-1]
        single = (x[:, 0] == x[:, 1]) & (y[:, 0] == y[:, 1])
        keep = np.column_stack([np.ones(len(used), bool), ~single]).ravel()
        return x.ravel()[keep], y.ravel()[keep]


def _bins(envelope: Envelope, x: FloatArray) -> NDArray[np.intp]:
    """The bin of each sample at ``x`` in ``envelope``'s bins (which cover them)."""
    index = ((x - envelope.origin) / envelope.width).astype(np.intp)
    return np.minimum(index, envelope.columns - 1, out=index)


def fold(envelopes: Sequence[Envelope], x: FloatArray, ys: Sequence[FloatArray]) -> None:
    """Fold the samples (x, y) of each of ``ys`` into the envelope beside it, non-finite ones
    left out. Envelopes in the same bins keeping the same samples (the columns of one
    series, as a rule) share the samples' binning, made once."""
    x = np.asarray(x, float)
    finite = np.isfinite(x)
    shared: (
        tuple[
            tuple[int, float, float], NDArray[np.bool_], float, float, FloatArray, NDArray[np.intp]
        ]
        | None
    )
    shared = None
    for envelope, y in zip(envelopes, ys, strict=True):
        y = np.asarray(y, float)
        keep = finite & np.isfinite(y)
        every = bool(keep.all())  # as a rule: then no sample is copied to leave none out
        state = (envelope.columns, envelope.origin, envelope.width)
        if shared is not None and shared[0] == state and np.array_equal(shared[1], keep):
            lo, hi, kept, bins = shared[2:]
            envelope._place(lo, hi)
        else:
            kept = x if every else x[keep]
            if not len(kept):
                continue
            lo, hi = float(kept.min()), float(kept.max())
            envelope._place(lo, hi)
            bins = _bins(envelope, kept)
            shared = state, keep, lo, hi, kept, bins
        envelope._fold(bins, kept, y if every else y[keep])


def _extremes(
    reduce: np.ufunc, empty: float, values: FloatArray, bins: NDArray[np.intp], columns: int
) -> tuple[FloatArray, NDArray[np.intp]]:
    """Each of ``columns`` bins' extreme (``reduce``: ``np.minimum`` or ``np.maximum``;
    ``empty`` for a bin without values) of ``values`` in ``bins`` (in any order: nothing is
    sorted), and the index of the bin's first value at it (``len(values)`` in an empty bin)."""
    extreme = np.full(columns, empty)
    reduce.at(extreme, bins, values)
    hits = np.flatnonzero(values == extreme[bins])
    first = np.full(columns, len(values))
    np.minimum.at(first, bins[hits], hits)
    return extreme, first


@dataclass(frozen=True)
class FullRate:
    """A full-rate series reduced to its drawing envelope: (MD m, value deg) points of
    inclination and azimuth, the samples they stand for and the azimuth's north."""

    inc: tuple[FloatArray, FloatArray]
    azi: tuple[FloatArray, FloatArray]
    samples: int
    north: str
    """e.g. 'true north'"""


def full_rate(batches: Iterable[pa.RecordBatch], north: str) -> FullRate:
    """Envelopes of ``inc`` and ``azi`` (deg) against ``md`` (m) of record batches, one
    batch at a time (a streamed port is never held whole)."""
    inc, azi = Envelope(), Envelope()
    for batch in batches:
        md = batch.column("md").to_numpy(zero_copy_only=False)
        values = [batch.column(c).to_numpy(zero_copy_only=False) for c in ("inc", "azi")]
        fold((inc, azi), md, values)
    return FullRate(inc.points(), azi.points(), inc.samples, north)

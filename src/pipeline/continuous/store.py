"""Full-rate columns of a continuous run kept on disk, read and written by row range, and the
helpers that let the integration work chunk by chunk with carried state.

A survey of any length goes through :mod:`pipeline.continuous` a chunk of rows at a time:
the raw columns it needs are written once to a :class:`ColumnStore` (held in memory up to
:data:`SPOOL_BYTES` in all, past that one unnamed temporary file per column, read with
``pread``, so the operating system's page cache holds them, not the process), and each pass
of the integration reads the rows of one chunk plus the few rows of overlap its filters
need, and writes its per-sample results back. Memory is a few chunks (and at most
:data:`SPOOL_BYTES` of store) whatever the survey's length. Chunking does not change the
numbers: filters read their whole window (:func:`savgol_range`), running sums carry the last
value (:func:`carried_cumsum`, :class:`RunningIntegrals`) and interpolations at given points
see the same two samples (:class:`Interpolation`) as over the whole series.
"""

from __future__ import annotations

import os
import tempfile
import weakref
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import IO

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray

from pipeline.continuous.filters import savgol_filters
from pipeline.earth.frames import FloatArray

__all__ = [
    "CHUNK_ROWS",
    "SPOOL_BYTES",
    "CarriedUnwrap",
    "ColumnStore",
    "Interpolation",
    "RunningIntegrals",
    "carried_cumsum",
    "chunks",
    "median_step",
    "savgol_range",
    "savgol_span",
]

CHUNK_ROWS = 65_536
"""Rows a pass of the integration handles at a time."""


SPOOL_BYTES = 24 << 20
"""bytes: a :class:`ColumnStore` holds its columns in memory up to this much in all (a 1×
well's 18 MiB: the files' creation, writes and closing ≈ 4–8 ms of its CPU), and moves them
all to files when a write would take it past (a day's survey: ≈ 1.2 GB of columns). The
bytes counted are those written; a growing column's buffer may hold up to ~1/8 more."""


@dataclass
class _Column:
    dtype: np.dtype[np.generic]
    rows: int
    data: bytearray
    """the column's bytes while the store is in memory (empty once on disk)"""
    file: IO[bytes] | None = None

    @property
    def fd(self) -> int:
        assert self.file is not None
        return self.file.fileno()


class ColumnStore:
    """Columns of numbers, in memory while they hold at most ``spool_bytes`` in all (default
    :data:`SPOOL_BYTES`), past that on disk: temporary files without a name where the system
    has them (``tempfile.TemporaryFile``: no directory entry made and removed per column),
    closed and gone when the store is garbage collected (when the last stream reading it is
    dropped). The same bits either way."""

    def __init__(self, spool_bytes: int | None = None) -> None:
        self._columns: dict[str, _Column] = {}
        self._spool = SPOOL_BYTES if spool_bytes is None else spool_bytes
        self._held = 0  # bytes in memory (0 once on disk)
        self._on_disk = False
        weakref.finalize(self, _close, self._columns)

    def __contains__(self, name: str) -> bool:
        return name in self._columns

    @property
    def on_disk(self) -> bool:
        """Whether the columns are in files (past ``spool_bytes``), not in memory."""
        return self._on_disk

    def rows(self, name: str) -> int:
        """Rows written to column ``name``."""
        return self._columns[name].rows

    def write(self, name: str, start: int, values: NDArray[np.generic]) -> None:
        """Write ``values`` at rows ``start``… of column ``name`` (created with their type;
        rows skipped read as zeros)."""
        column = self._columns.get(name)
        if column is None:
            column = self._columns[name] = _Column(values.dtype, 0, bytearray())
            if self._on_disk:
                column.file = _column_file()
        data = np.ascontiguousarray(values, dtype=column.dtype)
        if not data.size:  # nothing written: the column's rows as they were (a file's too)
            return
        offset = start * column.dtype.itemsize
        if not self._on_disk:
            grown = max(offset + data.nbytes - len(column.data), 0)
            if self._held + grown > self._spool:
                self._spill()
        if self._on_disk:
            os.pwrite(column.fd, data.data, offset)
        else:
            try:
                _put(column.data, offset, data)
            except BufferError:  # grown while a view of it (floats) lives: the view keeps those
                column.data = bytearray(column.data)
                _put(column.data, offset, data)
            self._held += grown
        column.rows = max(column.rows, start + data.size)

    def _spill(self) -> None:
        """Move every column to its own file."""
        for column in self._columns.values():
            column.file = _column_file()
            os.pwrite(column.fd, column.data, 0)
            column.data = bytearray()
        self._held, self._on_disk = 0, True

    def append(self, name: str, values: NDArray[np.generic]) -> None:
        """Write ``values`` after the rows of column ``name`` (created if new)."""
        self.write(name, self._columns[name].rows if name in self._columns else 0, values)

    def read(self, name: str, lo: int, hi: int) -> NDArray[np.generic]:
        """Rows ``lo``…``hi − 1`` of column ``name`` (a fresh array of its type)."""
        column = self._columns[name]
        lo, hi = max(lo, 0), min(hi, column.rows)
        out = np.empty(max(hi - lo, 0), dtype=column.dtype)
        if not out.size:
            return out
        if not self._on_disk:
            out[:] = np.frombuffer(column.data, column.dtype, out.size, lo * column.dtype.itemsize)
        elif os.preadv(column.fd, [out.data], lo * column.dtype.itemsize) != out.nbytes:
            raise OSError(f"short read of column {name!r} of a continuous run's store")
        return out

    def floats(self, name: str, lo: int, hi: int) -> FloatArray:
        """:meth:`read` as float64, read-only; of a float64 column in memory the store's own
        bytes (no copy: a view, which shows a later write to its rows)."""
        column = self._columns[name]
        lo, hi = max(lo, 0), min(hi, column.rows)
        if self._on_disk or column.dtype != np.float64 or hi <= lo:
            out: FloatArray = self.read(name, lo, hi).astype(np.float64, copy=False)
        else:
            out = np.frombuffer(column.data, np.float64, hi - lo, lo * 8)
        out.flags.writeable = False
        return out

    def ints(self, name: str, lo: int, hi: int) -> NDArray[np.int64]:
        """:meth:`read` as int64."""
        out: NDArray[np.int64] = self.read(name, lo, hi).astype(np.int64, copy=False)
        return out

    def add_batches(self, batches: Iterable[pa.RecordBatch], names: Iterable[str]) -> int:
        """Append the columns ``names`` of every batch as float64 (nulls NaN); rows added.
        Nothing of a batch is kept once it is written."""
        wanted = list(names)
        return sum(self._add_batch(batch, wanted) for batch in batches)

    def _add_batch(self, batch: pa.RecordBatch, names: list[str]) -> int:
        for name in names:
            array = batch.column(batch.schema.get_field_index(name))
            self.append(name, np.asarray(array.to_numpy(zero_copy_only=False), np.float64))
        return int(batch.num_rows)


def _put(buffer: bytearray, offset: int, data: NDArray[np.generic]) -> None:
    """Copy ``data`` (contiguous) into ``buffer`` at byte ``offset``, the buffer extended
    as needed (a gap reads as zeros, as a file's hole): one copy of the bytes (a slice
    assignment from an array would copy them twice: to a bytearray, then in)."""
    inside = min(max(len(buffer) - offset, 0), data.nbytes)  # bytes over existing ones
    raw = data.reshape(-1).view(np.uint8)
    if inside:
        np.frombuffer(buffer, np.uint8, inside, offset)[:] = raw[:inside]
    if inside < data.nbytes:
        if offset > len(buffer):
            buffer.extend(bytes(offset - len(buffer)))
        buffer.extend(raw[inside:])


def _column_file() -> IO[bytes]:
    """An unnamed temporary file for a column (closed by :func:`_close`)."""
    return tempfile.TemporaryFile(prefix="gyropipe-continuous-")


def _close(columns: dict[str, _Column]) -> None:
    for column in columns.values():
        if column.file is not None:
            column.file.close()
    columns.clear()


def chunks(lo: int, hi: int, rows: int, *, reverse: bool = False) -> Iterator[tuple[int, int]]:
    """Consecutive ranges ``[a, b)`` of at most ``rows`` rows covering ``[lo, hi)`` (from the
    end backward if ``reverse``)."""
    starts = range(lo, hi, rows)
    for a in reversed(starts) if reverse else starts:
        yield a, min(a + rows, hi)


def carried_cumsum(values: FloatArray, carry: float) -> FloatArray:
    """``carry + v₀, carry + v₀ + v₁, …`` summed in sequence (as one cumulative sum of the
    whole series would, so the chunks give the same numbers)."""
    out: FloatArray = np.cumsum(np.concatenate([[carry], values]))[1:]
    return out


class CarriedUnwrap:
    """``np.unwrap`` (rad) of a series given in consecutive chunks, called once per chunk:
    each step's correction summed in sequence from the first chunk on, as over the whole
    series (where no step of a chunk reaches π all its corrections are zeros: the sum stays
    the carried one, −0 made +0 as NumPy's cumulative sum makes it)."""

    def __init__(self) -> None:
        self._last: float | None = None
        self._correction = 0.0

    def __call__(self, angle: FloatArray) -> FloatArray:
        """The next chunk's angles unwrapped (a new array)."""
        if angle.size == 0:
            return angle.copy()
        step = np.empty(angle.size)  # from the last angle of the chunk before
        step[0] = angle[0] - (angle[0] if self._last is None else self._last)
        np.subtract(angle[1:], angle[:-1], out=step[1:])
        within = np.abs(step) < np.pi
        if within.all():  # one correction throughout: added as a scalar
            self._last, self._correction = float(angle[-1]), self._correction + 0.0
            same: FloatArray = angle + self._correction
            return same
        # np.unwrap's correction at the steps that reach π (or NaN), zeros elsewhere
        wraps = np.flatnonzero(~within)
        jump = step[wraps]
        fix = np.mod(jump + np.pi, 2 * np.pi) - np.pi
        fix[(fix == -np.pi) & (jump > 0)] = np.pi
        fixes = np.zeros(angle.size)
        fixes[wraps] = fix - jump
        corrections = carried_cumsum(fixes, self._correction)
        self._last, self._correction = float(angle[-1]), float(corrections[-1])
        out: FloatArray = angle + corrections
        return out


def savgol_span(lo: int, hi: int, a: int, b: int, points: int) -> tuple[int, int]:
    """Rows of the series ``[lo, hi)`` that a Savitzky–Golay filter of ``points`` samples
    (mode ``interp``) needs to give its values at rows ``[a, b)`` as over the whole series:
    the half window on each side, and the series' own edge windows where they are near."""
    half = points // 2
    wlo = max(lo, min(a - half, hi - points))
    whi = min(hi, max(b + half, lo + points))
    return wlo, whi


def savgol_range(
    values: FloatArray,
    wlo: int,
    a: int,
    b: int,
    points: int,
    order: int,
    derivs: Sequence[int],
    dt: float,
) -> list[FloatArray]:
    """The Savitzky–Golay fit (each ``derivs``-th derivative, sample interval ``dt``) at rows
    ``[a, b)`` from ``values`` over the rows :func:`savgol_span` gave, starting at ``wlo``:
    inside the series each value is the same filter of the same samples (within its
    rounding: the FFT's blocks fall elsewhere in a chunk), and the edge polynomial is fitted
    to the same first or last ``points`` samples."""
    half = points // 2
    ends = (a - wlo < half, b - wlo > values.size - half)  # the series' own edge windows
    fits = savgol_filters(values, points, order, derivs, delta=dt, ends=ends)
    return [fit[a - wlo : b - wlo] for fit in fits]


class Interpolation:
    """``np.interp(x, xp, f)`` for points ``x`` known up front while ``xp`` (strictly
    increasing) and the values ``f`` (one row per quantity) come in consecutive chunks: each
    point is interpolated between the same two samples as over the whole series. Only those
    samples of a chunk are copied, whatever its length."""

    def __init__(self, x: FloatArray, quantities: int) -> None:
        self._order = np.argsort(x, kind="stable")
        self._x = np.asarray(x, dtype=np.float64)[self._order]
        self._out = np.full((quantities, self._x.size), np.nan)
        self._next = 0
        self._last: tuple[float, FloatArray] | None = None

    def feed(self, xp: FloatArray, *values: FloatArray) -> None:
        """The next chunk of samples: ``xp`` and one array per quantity."""
        if xp.size == 0:
            return
        stop = int(np.searchsorted(self._x, xp[-1], side="right"))
        here = slice(self._next, stop)
        # the samples around each point (np.interp reads only those two): at or before it,
        # and after it; the one before the chunk is the last of the chunk before
        after = np.searchsorted(xp, self._x[here], side="right")
        picked = np.unique(
            np.concatenate([after - 1, np.minimum(after, xp.size - 1), [xp.size - 1]])
        )
        picked = picked[picked >= 0]
        sub_xp, f = xp[picked], np.stack([v[picked] for v in values])
        if self._last is not None:
            sub_xp = np.concatenate([[self._last[0]], sub_xp])
            f = np.concatenate([self._last[1][:, None], f], axis=1)
        for row in range(f.shape[0]):
            self._out[row, here] = np.interp(self._x[here], sub_xp, f[row])
        self._next = stop
        self._last = (float(sub_xp[-1]), f[:, -1].copy())

    def result(self) -> FloatArray:
        """Rows of interpolated values (quantity, point) in the points' given order; points
        past the last sample take its values."""
        if self._last is not None:
            self._out[:, self._next :] = self._last[1][:, None]
        out: FloatArray = np.empty_like(self._out)
        out[:, self._order] = self._out
        return out


class RunningIntegrals:
    """Trapezoid-rule integrals, from the first sample, of several quantities at points ``x``
    known up front, while the samples come in chunks: each chunk starts on the sample the
    one before ended on, so the steps tile. A point's integral is the whole steps before it,
    summed a cell (between consecutive points) at a time, and the part of its own step, the
    running integral taken linear there (as ``np.interp`` of the running integral would).
    Points before the first sample have 0, after the last the whole integral."""

    def __init__(self, x: FloatArray, quantities: int) -> None:
        self._order = np.argsort(x, kind="stable")
        self._x = np.asarray(x, dtype=np.float64)[self._order]
        self._out = np.zeros((quantities, self._x.size))
        self._next = 0
        self._total = np.zeros(quantities)

    def add(self, xp: FloatArray, *values: FloatArray) -> None:
        """The next chunk: ``xp`` (increasing; its first the last sample of the chunk before)
        and one array of samples per quantity."""
        if xp.size == 0:
            return
        stop = int(np.searchsorted(self._x, xp[-1], side="right"))
        here = slice(self._next, stop)
        # the step [xp[j], xp[j + 1]) holding each point: −1 before the first sample (first
        # chunk only), xp.size − 1 at the last sample
        step = np.searchsorted(xp, self._x[here], side="right") - 1
        inside = (step >= 0) & (step < xp.size - 1)
        j = step[inside]
        part = (self._x[here][inside] - xp[j]) / (xp[j + 1] - xp[j])
        starts = np.unique(np.concatenate([[0], j]))  # cells: from each point's step
        at = np.searchsorted(starts, j)
        # width·(f[1:] + f[:-1])/2 as (f[1:] + f[:-1])·(width/2), in place: the same numbers
        # (halving is exact and commutes with the rounding of the product but for subnormals)
        half_width = np.diff(xp)
        half_width *= 0.5
        steps = np.empty(half_width.size)
        for row, f in enumerate(values):
            np.add(f[1:], f[:-1], out=steps)
            steps *= half_width
            cells = np.add.reduceat(steps, starts) if steps.size else np.zeros(0)
            before = self._total[row] + np.concatenate([[0.0], np.cumsum(cells)])
            out = np.where(step < 0, 0.0, before[-1])
            out[inside] = before[at] + part * steps[j]
            self._out[row, here] = out
            self._total[row] = before[-1]
        self._next = stop

    def result(self) -> FloatArray:
        """Rows of integrals (quantity, point) in the points' given order."""
        self._out[:, self._next :] = self._total[:, None]
        out: FloatArray = np.empty_like(self._out)
        out[:, self._order] = self._out
        return out


_WHOLE_CHUNKS = 2
"""Chunks of steps that :func:`median_step` reads at once (a 65,536-row chunk: 512 KiB)."""


def median_step(store: ColumnStore, name: str, lo: int, hi: int, rows: int) -> float:
    """Median of the steps ``x[k+1] − x[k]`` of column ``name`` over rows ``[lo, hi)``, exactly
    as ``np.median(np.diff(x))``: a histogram pass finds the bins holding the middle steps,
    a second pass collects the steps in them. Steps of up to :data:`_WHOLE_CHUNKS` chunks are
    read whole and given to ``np.median`` itself (a 120,000-sample run: 0.4 ms, against 2 ms
    by the passes, most of it their histograms)."""
    count = hi - lo - 1
    if count < 1:
        return float("nan")
    if count <= _WHOLE_CHUNKS * rows:
        return float(np.median(np.diff(store.floats(name, lo, hi))))

    def steps() -> Iterator[FloatArray]:
        for a, b in chunks(lo, hi - 1, rows):
            yield np.diff(store.floats(name, a, b + 1))

    bounds = [(float(s.min()), float(s.max())) for s in steps()]  # one pass for both
    low = min(b[0] for b in bounds)
    high = max(b[1] for b in bounds)
    if not low < high:
        return low
    n_bins = 4096
    edges = np.linspace(low, high, n_bins + 1)  # NumPy's edges of the equal bins below
    hist = np.zeros(n_bins, dtype=np.int64)
    for s in steps():
        hist += np.histogram(s, bins=n_bins, range=(low, high))[0]
    ranks = ((count - 1) // 2, count // 2)
    below = np.concatenate([[0], np.cumsum(hist)])
    bins = sorted({int(np.searchsorted(below, r, side="right")) - 1 for r in ranks})
    picked: dict[float, int] = {}
    for s in steps():
        # a bin holds edges[b] ≤ s < edges[b + 1], the last one its right edge too
        inside = [
            (s >= edges[b]) & (s < edges[b + 1]) if b < n_bins - 1 else s >= edges[b] for b in bins
        ]
        chosen = s[inside[0] | inside[-1]]
        for value, n in zip(*np.unique(chosen, return_counts=True), strict=True):
            picked[float(value)] = picked.get(float(value), 0) + int(n)
    keys = sorted(picked)
    cumulative = np.cumsum([picked[k] for k in keys])
    base = int(below[bins[0]])
    middle = [keys[int(np.searchsorted(cumulative, r - base, side="right"))] for r in ranks]
    return (middle[0] + middle[1]) / 2

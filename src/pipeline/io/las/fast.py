"""The fast path of the LAS ``~A`` reader (:mod:`pipeline.io.las.rows`): plain blocks of
numbers parsed by ``pyarrow.csv`` block by block, up to the first block it cannot prove it
reads as the careful path would (the careful path reads from there and locates any error).

The data section is copied one block of lines (about :data:`BLOCK` bytes) at a time into a
reused buffer, rewritten so that a comma separates the values of each line, and parsed
from there in one chunk while it is in the processor's cache (the file's text is never
copied whole):

* a block of fixed-width lines (every line as long; columns blank on its first
  :data:`SAMPLE` lines split it into one group of columns per curve, as LAS writers lay
  values out; the lines after are guarded by the parse, where a line parses only with
  each separator column a space) keeps its bytes: the first column after each group, a
  space on every line, becomes a comma by an XOR that
  makes a comma of a space only. The layout found in one block is applied to the next as
  it is copied (one pass over its bytes; no check: where it does not fit, a line has a
  value too few, which the parse refuses), and ``pyarrow.csv`` trims the padding of each
  value (spaces and tabs; CRLF ends a line);
* any other block has tabs made spaces and CRLF made LF, each run of spaces made one comma
  and the spaces at line starts and ends dropped (a vectorised pass).

A block holding a comma is left to the careful path, which splits lines at blanks only
(``1.0,2.0`` is one cell, not a number). Every value, read or not, is parsed as a float64
(correctly rounded, as Python's ``float``): a cell that is not exactly one number (a blank
line, a wrong value count, a token like ``1-2``, text, a control byte other than a tab)
fails the parse, and a row count other than the line count (a lone CR) or a non-finite
value (``1e999``, ``nan``; found by each curve's smallest and largest value, which the
null check then uses) declines, so the careful path reports it with its line.

With more than one reader thread (:func:`~pipeline.io.threads.reader_threads`), that many
threads read (copy, rewrite, parse) the next blocks while the caller uses one, each with its
own buffer: the parse of a block is serial, blocks are parsed in parallel.
"""

from __future__ import annotations

import mmap
from collections import deque
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
from numpy.typing import NDArray

from pipeline.io import threads as io_threads
from pipeline.io.arrow_text import release

Floats = NDArray[np.float64]
Bytes = NDArray[np.uint8]
Text = bytes | mmap.mmap
"""A file's bytes, read or mapped."""
Layout = tuple[int, tuple[int, ...]]
"""A fixed-width block's line width (with its LF) and separator columns."""

BLOCK = 4 << 20
"""Bytes of lines rewritten at a time."""
KEEP = 4
"""Block buffers kept between reads (:data:`BLOCK` × 2 bytes each, of which a block's are
touched): a fresh one costs the zeroing of its pages as a read first writes them."""
_KEPT: list[Bytes] = []
SAMPLE = 4096
"""Lines of a block whose columns find a layout (the lines after guarded by the parse)."""
TILE = 32 << 10
"""Bytes of lines (about) of the separators' XOR pattern laid over a block at a time."""
SPACE, COMMA, NEWLINE = 32, 44, 10
FLIP = SPACE ^ COMMA
"""XOR making a space a comma and any other byte no comma (nor a tab, LF or CR)."""
_TAB_TO_SPACE = bytes.maketrans(b"\t", b" ")
_BLANK = b" \t\r\n"


@dataclass(frozen=True)
class Block:
    """The values of one block of rows (by curve position), their count and the smallest
    and largest value of each curve."""

    values: dict[int, Floats]
    rows: int
    ranges: dict[int, tuple[float, float]]


@dataclass(frozen=True)
class Declined:
    """A block the fast path cannot prove it reads right: ``raw[start:end]``, whole lines,
    for the careful path to read (and locate any error in)."""

    start: int
    end: int


def fast_blocks(raw: Text, start: int, n: int, wanted: list[int]) -> Iterator[Block | Declined]:
    """Values of the ``wanted`` of ``n`` curves in ``raw[start:]``, a block of rows at a
    time; a :class:`Declined` block for the careful path where the fast path cannot read
    one (every line of it, blank and comment lines too, is left to the careful path). Each
    block is copied into a reused buffer, rewritten and parsed there, so the section's text
    is never held whole; with more than one reader thread, blocks are read ahead on them."""
    end = _content_end(raw, start)
    if n == 0:
        yield Declined(start, end)
        return
    parser = _Parser(raw, n, wanted)
    spans = _spans(raw, start, end)
    threads = io_threads.reader_threads()
    if end - start <= BLOCK or threads < 2:
        buffer = _buffer(0)
        layout: Layout | None = None
        try:
            for first, last in spans:
                block, found, buffer = parser.read(first, last, buffer, layout)
                layout = found or layout
                yield block
        finally:
            _keep([buffer])
        return
    yield from _ahead(parser, spans, threads)


def _ahead(
    parser: _Parser, spans: Iterator[tuple[int, int]], ahead: int
) -> Iterator[Block | Declined]:
    """:meth:`_Parser.read` of each span in order, ``ahead`` blocks read by as many other
    threads while this one's block is used (each read in flight has its own buffer)."""
    free: list[Bytes] = []  # buffers no thread uses
    try:
        with ThreadPoolExecutor(ahead, thread_name_prefix="las-block") as pool:
            layout: Layout | None = None
            pending: deque[Future[tuple[Block | Declined, Layout | None, Bytes]]] = deque()
            for first, last in spans:
                done = None
                if len(pending) == ahead:
                    done = pending.popleft().result()
                    layout = done[1] or layout
                    free.append(done[2])
                buffer = free.pop() if free else _buffer(0)
                pending.append(pool.submit(parser.read, first, last, buffer, layout))
                if done is not None:
                    yield done[0]
            while pending:
                done = pending.popleft().result()
                free.append(done[2])
                yield done[0]
    finally:  # after the pool's threads are done
        _keep(free)


def fast_values(raw: Text, start: int, n: int, wanted: list[int]) -> list[Block] | None:
    """:func:`fast_blocks` whole: every block of values, or None when the careful path
    must read any."""
    blocks = []
    for block in fast_blocks(raw, start, n, wanted):
        if isinstance(block, Declined):
            return None
        blocks.append(block)
    return blocks


def _floats(column: pa.ChunkedArray) -> Floats:
    """A parsed column (one chunk) as an array, without a copy."""
    values: Floats = column.chunk(0).to_numpy()
    return values


def _content_end(raw: Text, start: int) -> int:
    """Index after the last byte of ``raw[start:]`` that is no space, tab or line end."""
    for begin in (max(start, len(raw) - 4096), start):
        stripped = len(raw[begin:].rstrip(_BLANK))
        if stripped:
            return begin + stripped
    return start


def _spans(text: Text, begin: int, end: int) -> Iterator[tuple[int, int]]:
    """Where each block of ``text[begin:end]`` starts and ends: whole lines of about
    :data:`BLOCK` bytes (the last line may lack its LF)."""
    while begin < end:
        stop = text.find(b"\n", begin + BLOCK, end) + 1
        stop = end if stop <= 0 else stop
        yield begin, stop
        begin = stop


def _buffer(size: int) -> Bytes:
    """A buffer for blocks of ``size`` bytes (at least twice :data:`BLOCK`): one kept from
    a read before where one is as large."""
    need = max(size, 2 * BLOCK)
    try:
        kept = _KEPT.pop()  # atomic: reads on other threads take others
    except IndexError:
        return np.empty(need, np.uint8)
    if kept.size >= need:
        return kept
    _KEPT.append(kept)  # too small for this read: kept for another
    return np.empty(need, np.uint8)


def _keep(buffers: list[Bytes]) -> None:
    """Keep ``buffers`` (no longer used) for the next reads, up to :data:`KEEP`."""
    for buffer in buffers:
        if len(_KEPT) < KEEP and buffer.size == 2 * BLOCK:
            _KEPT.append(buffer)


class _Parser:
    """Reads blocks of ``text`` holding rows of ``n`` values: the ``wanted`` ones."""

    def __init__(self, text: Text, n: int, wanted: list[int]) -> None:
        self.text, self.n, self.wanted = text, n, wanted
        self.names = [f"c{i}" for i in range(n)]
        self.parse = pacsv.ParseOptions(
            delimiter=",", quote_char=False, double_quote=False, ignore_empty_lines=False
        )
        self.convert = pacsv.ConvertOptions(
            column_types=dict.fromkeys(self.names, pa.float64()),
            null_values=[],
            strings_can_be_null=False,
            check_utf8=False,
        )

    def read(
        self, first: int, last: int, buffer: Bytes, known: Layout | None
    ) -> tuple[Block | Declined, Layout | None, Bytes]:
        """The block ``text[first:last]`` copied into ``buffer`` (or a larger one), each
        line ending with LF, rewritten there so that one comma separates the values of a
        line and parsed (``known``: the layout of a block before, tried first); with the
        block's layout (None unless fixed-width) and the buffer used."""
        if buffer.size <= last - first:
            buffer = _buffer(last - first + 1)
        try:
            block, layout = self._read(first, last, buffer, known)
        finally:
            release(self.text, first, last)
        return block or Declined(first, last), layout, buffer

    def _read(
        self, first: int, last: int, buffer: Bytes, known: Layout | None
    ) -> tuple[Block | None, Layout | None]:
        text, size = self.text, last - first
        if text.find(b",", first, last) >= 0:
            return None, None  # the careful path splits at blanks only: "1,2" is one cell
        width = text.find(b"\n", first, last) + 1 - first
        block = buffer[: size + (text[last - 1] != NEWLINE)]
        block[-1] = NEWLINE  # the last line's (a no-op elsewhere)
        width = width if width > 0 else block.size  # the last line, without its LF
        source = np.frombuffer(text, np.uint8, count=size, offset=first)
        rows = block.size // width
        if known is not None and known[0] == width:
            _flipped(source, block, known)  # copied with the commas: one pass
            if _same_width(block, width):
                parsed = self._parsed(block, rows)
                if parsed is not None:
                    return parsed, known
        block[:size] = source
        layout = _fixed_width(block, width, self.n)
        if layout is not None and layout != known:  # new, or a layout that changed
            _flipped(block[:size], block, layout)
            parsed = self._parsed(block, rows)
            if parsed is not None:
                return parsed, layout
            block[:size] = source  # bad cells (packing fails them too) or lines
        if np.count_nonzero(block < SPACE) != np.count_nonzero(block == NEWLINE):
            spaced = _spaced(block.tobytes())  # tabs or CRs
            if spaced is None:
                return None, None
            block = spaced
        rows = int(np.count_nonzero(block == NEWLINE))
        return self._parsed(_packed(block), rows), None

    def _parsed(self, data: Bytes, rows: int) -> Block | None:
        """The values of ``rows`` lines rewritten in ``data``, parsed in one chunk; or None
        (declined)."""
        try:
            table = pacsv.read_csv(
                pa.BufferReader(pa.py_buffer(data)),
                read_options=pacsv.ReadOptions(
                    column_names=self.names, use_threads=False, block_size=data.size + 1
                ),
                parse_options=self.parse,
                convert_options=self.convert,
            )
        except pa.ArrowInvalid:
            return None
        if table.num_rows != rows:
            return None
        values = {i: _floats(table.column(self.names[i])) for i in self.wanted}
        ranges = {i: (float(v.min()), float(v.max())) for i, v in values.items()}
        if not np.isfinite(list(ranges.values())).all():
            return None  # a NaN (numpy's min and max carry it) or an infinity
        return Block(values, rows, ranges)


def _spaced(lines: bytes) -> Bytes | None:
    """``lines`` with tabs made spaces and CRLF made LF; None for a lone CR."""
    if lines.count(b"\r") != lines.count(b"\r\n"):
        return None
    return np.frombuffer(lines.translate(_TAB_TO_SPACE, b"\r"), np.uint8)


def _fixed_width(block: Bytes, width: int, n: int) -> Layout | None:
    """The layout of a block of lines all ``width`` bytes long (with their LF): the first
    column after each of the ``n`` groups of columns holding values (on the first
    :data:`SAMPLE` lines) but the last, where it is a space on every one of them; None when the
    lines differ in length or have another number of groups. Tabs and CRs count as blanks
    (``pyarrow.csv`` trims tabs around a value and ends a line at CRLF; a lone CR makes a
    row too many, declined). The values read do not depend on the layout: a line parses
    only where each of its separator columns was a space (see :data:`FLIP`)."""
    if not _same_width(block, width):
        return None
    grid = block.reshape(-1, width)
    filled = np.concatenate(([False], _column_max(grid[:SAMPLE, :-1]) > SPACE, [False]))
    edges = np.flatnonzero(filled[1:] != filled[:-1])  # where each group starts and ends
    if edges.size != 2 * n:
        return None
    separators = edges[1:-2:2]
    if not (grid[:, separators] == SPACE).all():
        return None
    return width, tuple(int(column) for column in separators)


def _same_width(block: Bytes, width: int) -> bool:
    """Whether ``block`` is lines all ``width`` bytes long (with their LF)."""
    if width < 2 or block.size % width:
        return False
    ends = block[width - 1 :: width].tobytes()  # a gather and a memcmp: ~40 % less than ==
    return ends == b"\n" * len(ends)


def _flipped(source: Bytes, out: Bytes, layout: Layout) -> None:
    """``out[:source.size]``: the lines ``source`` (whole lines from a line start; the last
    may lack its LF) with the layout's separator columns XORed by :data:`FLIP`, a space
    made a comma and any other byte no comma (``source`` may be ``out``'s own bytes). One
    vectorised pass: the XOR pattern of :data:`TILE` bytes of lines is laid over the lines
    a tile at a time (a separate XOR per column strides through every line, 3× slower)."""
    width, separators = layout
    lines = max(1, TILE // width)
    tile = np.zeros((lines, width), np.uint8)
    tile[:, list(separators)] = FLIP
    pattern = tile.reshape(-1)
    whole = source.size // pattern.size * pattern.size
    np.bitwise_xor(
        source[:whole].reshape(-1, pattern.size),
        pattern,
        out=out[:whole].reshape(-1, pattern.size),
    )
    np.bitwise_xor(source[whole:], pattern[: source.size - whole], out=out[whole : source.size])


def _column_max(grid: Bytes) -> Bytes:
    """The largest byte of each column (folding halves: contiguous, vectorised)."""
    while len(grid) > 1:
        half = len(grid) // 2
        folded = np.maximum(grid[:half], grid[half : 2 * half])
        if len(grid) % 2:
            np.maximum(folded[0], grid[-1], out=folded[0])
        grid = folded
    top: Bytes = grid[0]
    return top


def _packed(block: Bytes) -> Bytes:
    """A block of lines with each run of spaces made one comma, none at line starts or
    ends (a line of spaces becomes empty, which the parse refuses)."""
    keep = np.empty(block.size, dtype=bool)
    np.greater(block[:-1], SPACE, out=keep[1:])  # a space after a value
    keep[:1] = False
    keep |= block != SPACE
    packed = block[keep]
    before_end = packed[1:] == NEWLINE
    before_end &= packed[:-1] == SPACE
    if before_end.any():  # a space ending a line
        packed = packed[np.append(~before_end, True)]
    packed[packed == SPACE] = COMMA
    return packed

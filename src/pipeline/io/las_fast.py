"""The fast path of the LAS ``~A`` reader (:mod:`pipeline.io.las_rows`): plain blocks of
numbers parsed by ``pyarrow.csv`` block by block, up to the first block it cannot prove it
reads as the careful path would (the careful path reads from there and locates any error).

The data section is copied one block of lines (about :data:`BLOCK` bytes) at a time into
one reused buffer, and each block is rewritten there while it is in the processor's cache
(CRLF made LF and tabs spaces, if any) so that a comma separates the values of each line,
then parsed from it (the file's text is never copied whole):

* a block of fixed-width lines (every line as long; columns that are a space on every line
  split it into one group of columns per curve, as LAS writers lay values out) keeps its
  bytes: the first blank column after each group becomes a comma, and ``pyarrow.csv``
  trims the padding of each value;
* any other block has each run of spaces made one comma and the spaces at line starts and
  ends dropped (a vectorised pass).

Every value, read or not, is parsed as a float64 (correctly rounded, as Python's ``float``):
a cell that is not exactly one number (a blank line, a wrong value count, a token like
``1-2``, text) fails the parse, and a row count other than the line count or a non-finite
value (``1e999``) declines, so the careful path reports it with its line.
"""

from __future__ import annotations

import mmap
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
from numpy.typing import NDArray

from pipeline.io.arrow_text import read_options, release

Floats = NDArray[np.float64]
Bytes = NDArray[np.uint8]
Text = bytes | mmap.mmap
"""A file's bytes, read or mapped."""

BLOCK = 4 << 20
"""Bytes of lines rewritten at a time."""
SPACE, COMMA, NEWLINE = 32, 44, 10
_TAB_TO_SPACE = bytes.maketrans(b"\t", b" ")
_BLANK = b" \t\r\n"


@dataclass(frozen=True)
class Block:
    """The values of one block of rows (by curve position) and their count."""

    values: dict[int, Floats]
    rows: int


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
    block is rewritten in one reused buffer and parsed from it, so the section's text is
    never held whole."""
    end = _content_end(raw, start)
    if n == 0:
        yield Declined(start, end)
        return
    names = [f"c{i}" for i in range(n)]
    parse = pacsv.ParseOptions(
        delimiter=",", quote_char=False, double_quote=False, ignore_empty_lines=False
    )
    convert = pacsv.ConvertOptions(
        column_types=dict.fromkeys(names, pa.float64()),
        null_values=[],
        strings_can_be_null=False,
        check_utf8=False,
    )
    for first, last, delimited in _delimited(raw, start, end, n):
        if delimited is None:
            yield Declined(first, last)
            continue
        data, rows = delimited
        try:
            table = pacsv.read_csv(
                pa.BufferReader(pa.py_buffer(data)),
                read_options=read_options(names),
                parse_options=parse,
                convert_options=convert,
            )
        except pa.ArrowInvalid:
            yield Declined(first, last)
            continue
        values = {i: _floats(table.column(names[i])) for i in wanted}
        if table.num_rows != rows or not all(np.isfinite(v).all() for v in values.values()):
            yield Declined(first, last)
            continue
        yield Block(values, rows)


def fast_values(
    raw: Text, start: int, n: int, wanted: list[int]
) -> tuple[dict[int, Floats], int] | None:
    """:func:`fast_blocks` whole: the values and the row count, or None when the careful
    path must read them."""
    blocks = []
    for block in fast_blocks(raw, start, n, wanted):
        if isinstance(block, Declined):
            return None
        blocks.append(block)
    if len(blocks) == 1:
        return blocks[0].values, blocks[0].rows
    values = {i: np.concatenate([b.values[i] for b in blocks] or [np.empty(0)]) for i in wanted}
    return values, sum(b.rows for b in blocks)


def _floats(column: pa.ChunkedArray) -> Floats:
    """A parsed column as one array (no copy when it is one chunk)."""
    values: Floats = column.chunk(0).to_numpy() if column.num_chunks == 1 else column.to_numpy()
    return values


def _content_end(raw: Text, start: int) -> int:
    """Index after the last byte of ``raw[start:]`` that is no space, tab or line end."""
    for begin in (max(start, len(raw) - 4096), start):
        stripped = len(raw[begin:].rstrip(_BLANK))
        if stripped:
            return begin + stripped
    return start


def _delimited(
    text: Text, begin: int, end: int, n: int
) -> Iterator[tuple[int, int, tuple[Bytes, int] | None]]:
    """The lines of ``text[begin:end]``, a block at a time: where it starts and ends in
    ``text``, then its lines each ending with LF, rewritten so that one comma separates
    the values of a line (``n`` in a good one), and its line count; or None for a lone CR
    line end. Every block is copied into one reused buffer and rewritten there while in
    the cache: a yielded block is valid until the next is asked for."""
    source = np.frombuffer(text, np.uint8, count=end - begin, offset=begin)
    out = np.empty(0, np.uint8)
    read = 0
    layout: tuple[int, NDArray[np.intp]] | None = None
    while read < source.size:
        stop = text.find(b"\n", begin + read + BLOCK, end) + 1 - begin
        stop = source.size + 1 if stop <= 0 else stop
        if out.size < stop - read:
            out = np.empty(max(stop - read, 2 * BLOCK), np.uint8)
        block = out[: stop - read]
        block[: source.size - read] = source[read:stop]
        block[-1] = NEWLINE  # the last line's (a no-op elsewhere)
        width = text.find(b"\n", begin + read, begin + stop) + 1 - begin - read
        release(text, begin + read, begin + min(stop, source.size))
        width = width if width > 0 else block.size  # the last line, without its LF
        separators = _fixed_width(block, width, n, layout)
        if separators is None and (block < SPACE).sum() != (block == NEWLINE).sum():
            spaced = _spaced(block.tobytes())  # tabs or CRs
            if spaced is None:
                yield begin + read, begin + min(stop, source.size), None
                read = stop
                continue
            block = out[: spaced.size]
            block[:] = spaced
            width = int(np.argmax(block == NEWLINE)) + 1
            separators = _fixed_width(block, width, n, layout)
        if separators is not None:
            layout = width, separators
            block.reshape(-1, width)[:, separators] = COMMA
            yield begin + read, begin + min(stop, source.size), (block, block.size // width)
        else:
            rows = int(np.count_nonzero(block == NEWLINE))
            yield begin + read, begin + min(stop, source.size), (_packed(block), rows)
        read = stop


def _spaced(lines: bytes) -> Bytes | None:
    """``lines`` with tabs made spaces and CRLF made LF; None for a lone CR."""
    if lines.count(b"\r") != lines.count(b"\r\n"):
        return None
    return np.frombuffer(lines.translate(_TAB_TO_SPACE, b"\r"), np.uint8)


def _fixed_width(
    block: Bytes, width: int, n: int, known: tuple[int, NDArray[np.intp]] | None
) -> NDArray[np.intp] | None:
    """The separator columns of a block of lines all ``width`` bytes long (with their LF):
    the first always-blank column after each of the ``n`` groups of columns holding values
    but the last (those of the ``known`` layout of the block before when they are blank
    on every line); None when the lines differ in length, hold control bytes or have
    another number of groups."""
    if width < 2 or block.size % width:
        return None
    grid = block.reshape(-1, width)
    if np.count_nonzero(block < SPACE) != len(grid) or not (grid[:, -1] == NEWLINE).all():
        return None  # lines of other lengths, or a control byte in a line
    if known is not None and known[0] == width and (grid[:, known[1]] == SPACE).all():
        return known[1]
    filled = np.concatenate(([False], _column_max(grid[:, :-1]) > SPACE, [False]))
    edges = np.flatnonzero(filled[1:] != filled[:-1])  # where each group starts and ends
    if edges.size != 2 * n:
        return None
    return edges[1:-2:2]


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

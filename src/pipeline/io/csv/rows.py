"""Bytes, lines and data rows of a CSV file (see :mod:`pipeline.io.csv` for the layout).

The start of the file is checked to be text (:func:`load`). A larger file is then mapped
into memory, not copied, and each block of rows checked just before it is parsed
(:func:`checked`: no NUL byte, UTF-8, CR line ends made LF); one whose start holds a
byte-order mark or CR line ends is read and checked as bytes instead.
Only its first lines (where the title block and the header row are) are decoded to text;
the data rows stay bytes and are handed to ``pyarrow.csv`` a block of about
:data:`ROWS_BLOCK` bytes of whole lines at a time (:func:`parse_blocks`: a stream's
batches; the pages of the mapped file let go once read), which parses them with the
declared column types, one thread per block; when the readers have more than one thread
(:func:`~pipeline.io.threads.reader_threads`), blocks are parsed on as many, a few ahead
of the one handed on (each scanned first on the thread that hands them on). A block that
does not parse that way (a bad cell, a wrong cell count, decimal commas to detect) is
parsed again as strings on one thread, in order (its first line then known), which
locates every problem on its file line.
"""

from __future__ import annotations

import codecs
import mmap
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
from numpy.typing import NDArray

from pipeline.errors import InputFileError, warn_input
from pipeline.io import threads as io_threads
from pipeline.io.arrow_text import in_order, read_options, release
from pipeline.io.csv.header import Cell, Header, cells_of, is_footer
from pipeline.io.nulls import value_range

SHOWN = 5
"""Bad cells quoted in one error message."""
BLOCK = 64 * 1024
"""Bytes of a file checked (text, not binary) before the whole file is read."""
SCAN = 4 << 20
"""Bytes of a mapped file searched at a time when looking for one byte in all its rows."""
CHECK = 256 << 10
"""Bytes of a block checked at a time (:func:`checked`: they stay in the cache)."""
MARKED = (b"\0", b"\r", b"#", b'"')
"""Bytes a block is checked for: NUL, CR (line ends), comment marks and quotes."""
BOM = b"\xef\xbb\xbf"

_NUMBER = {
    ".": r"^[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?$",
    ",": r"^[+-]?([0-9]+(,[0-9]*)?|,[0-9]+)([eE][+-]?[0-9]+)?$",
}
_INTEGER = r"^-?[0-9]{1,18}$"
_BLANKS = (ord(" "), ord("\t"))


Data = bytes | mmap.mmap
"""A file's bytes, read or mapped."""


@dataclass(frozen=True)
class Text:
    """A readable CSV file: its bytes with LF line ends, its first lines decoded and the
    byte offset where each of those lines starts."""

    data: Data
    head: list[str]
    starts: list[int]


@dataclass(frozen=True)
class Rows:
    """The data rows: ``data[start:end]``, LF-separated, without blank or comment lines.
    Row 0 is file line ``first_line`` (1-based); ``lines`` holds each row's file line when
    skipped lines lay between them (else rows are consecutive lines)."""

    data: Data
    start: int
    end: int
    first_line: int
    lines: NDArray[np.int64] | None = None
    marked: frozenset[bytes] | None = None
    """which of :data:`MARKED` the rows hold, when known (:func:`checked`)"""

    def holds(self, byte: bytes) -> bool:
        """Whether the rows hold ``byte``."""
        if self.marked is not None and byte in MARKED:
            return byte in self.marked
        return self.data.find(byte, self.start, self.end) >= 0

    def anywhere(self, byte: bytes) -> bool:
        """:meth:`holds` for all the rows of a file: a mapped file is searched a block at
        a time, its pages let go once searched."""
        for at in range(self.start, self.end, SCAN):
            found = self.data.find(byte, at, min(at + SCAN, self.end))
            release(self.data, at, min(at + SCAN, self.end))
            if found >= 0:
                return True
        return False

    def buffer(self) -> pa.Buffer:
        """The rows' bytes, without a copy."""
        return pa.py_buffer(memoryview(self.data)[self.start : self.end])

    def count(self) -> int:
        """Number of rows (lines)."""
        if self.lines is not None:
            return len(self.lines)
        if isinstance(self.data, bytes):
            return self.data.count(b"\n", self.start, self.end) + 1
        block = np.frombuffer(self.data, np.uint8, count=self.end - self.start, offset=self.start)
        return int(np.count_nonzero(block == ord("\n"))) + 1

    def source_lines(self, count: int) -> NDArray[np.int64]:
        """File line of each of the first ``count`` rows."""
        if self.lines is not None:
            return self.lines[:count]
        return np.arange(self.first_line, self.first_line + count, dtype=np.int64)

    def line(self, row: int) -> int:
        """File line of row ``row`` (0-based)."""
        return int(self.lines[row]) if self.lines is not None else self.first_line + row

    def text_lines(self) -> list[str]:
        return self.data[self.start : self.end].decode("utf-8").split("\n")


def load(path: Path, head_lines: int) -> Text:
    """Read ``path``: UTF-8 (optional BOM), any line ends; the first ``head_lines`` lines
    decoded. NUL bytes, invalid UTF-8 and blank files are errors naming the line.

    The first :data:`BLOCK` bytes are checked before the rest is looked at: a binary file
    (a NUL byte, bytes that are not UTF-8) is refused without reading it all. A larger file
    whose start has LF line ends, no byte-order mark and some text is then mapped into
    memory, not copied: its lines past the head are checked a block at a time as they are
    parsed (:func:`checked`). Any other is read and checked as a whole."""
    try:
        with path.open("rb") as fh:
            first = fh.read(BLOCK)
            _check_text(path, first, complete=len(first) < BLOCK)
            data: Data = first
            mapped = _mapped(fh) if len(first) == BLOCK and _mappable(first) else None
            if mapped is not None:
                data = mapped
            elif len(first) == BLOCK:
                fh.seek(0)
                data = fh.read()
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc.strerror or exc}") from None
    if isinstance(data, bytes):
        data = _check_text(path, data, complete=True)
        if not data or data.isspace():
            raise InputFileError(path, "the file is empty")
    head, starts = split_head(data, head_lines)
    if isinstance(data, mmap.mmap):  # the head past the first block is checked too
        end = data.find(b"\n", starts[-1])
        _check_text(path, data[: len(data) if end < 0 else end], complete=True)
    return Text(data, head, starts)


def _mappable(first: bytes) -> bool:
    """Whether a file starting with ``first`` is mapped: LF line ends, no byte-order mark,
    some text besides white space."""
    return b"\r" not in first and not first.startswith(BOM) and not first.isspace()


def _mapped(fh: BinaryIO) -> mmap.mmap | None:
    """The file mapped into memory (read-only); None if it cannot be (not a regular file)."""
    try:
        return mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
    except (OSError, ValueError):
        return None


def scan(data: Data, start: int, end: int) -> tuple[frozenset[bytes], bool]:
    """Which of :data:`MARKED` ``data[start:end]`` holds, and whether it is all ASCII: one
    pass, :data:`CHECK` bytes at a time (they stay in the cache)."""
    found: set[bytes] = set()
    ascii_only = True
    for at in range(start, end, CHECK):
        stop = min(at + CHECK, end)
        found.update(byte for byte in MARKED if data.find(byte, at, stop) >= 0)
        ascii_only = ascii_only and int(np.frombuffer(data, np.uint8, stop - at, at).max()) < 0x80
    return frozenset(found), ascii_only


def checked(path: Path, block: Rows) -> Rows:
    """A block of the rows of a mapped file checked as text (no NUL byte, UTF-8: an error
    names the line), noting which of :data:`MARKED` it holds; its CR line ends made LF
    (then a copy). One pass (:func:`scan`). Any other block as it is."""
    data = block.data
    if not isinstance(data, mmap.mmap):
        return block
    found, ascii_only = scan(data, block.start, block.end)
    if b"\0" in found:
        nul = data.find(b"\0", block.start, block.end)
        line = block.first_line + _line_ends(data, block.start, nul)
        raise InputFileError(path, "NUL byte: this is not a text CSV file", line=line)
    if not ascii_only:  # checked as UTF-8
        try:
            data[block.start : block.end].decode("utf-8")
        except UnicodeDecodeError as exc:
            line = block.first_line + _line_ends(data, block.start, block.start + exc.start)
            raise InputFileError(path, f"not UTF-8 text: {exc.reason}", line=line) from None
    if b"\r" in found:
        text = newlines(data[block.start : block.end])
        return Rows(text, 0, len(text), block.first_line)
    return Rows(data, block.start, block.end, block.first_line, marked=found)


def _line_ends(data: Data, start: int, end: int) -> int:
    """Line ends in ``data[start:end]``."""
    return int(np.count_nonzero(np.frombuffer(data, np.uint8, end - start, start) == 10))


def _check_text(path: Path, data: bytes, *, complete: bool) -> bytes:
    """``data`` (the whole file, or its start unless ``complete``) without BOM and with LF
    line ends; a NUL byte or invalid UTF-8 raises, naming its line."""
    data = newlines(data.removeprefix(BOM))
    nul = data.find(b"\0")
    if nul >= 0:
        line = data.count(b"\n", 0, nul) + 1
        raise InputFileError(path, "NUL byte: this is not a text CSV file", line=line)
    if not data.isascii():
        try:  # a character cut at the end of an incomplete start is no error
            codecs.getincrementaldecoder("utf-8")().decode(data, final=complete)
        except UnicodeDecodeError as exc:
            line = data.count(b"\n", 0, exc.start) + 1
            raise InputFileError(path, f"not UTF-8 text: {exc.reason}", line=line) from None
    return data


def newlines(data: bytes) -> bytes:
    """``data`` with CRLF and lone CR line ends made LF (as pyarrow.csv splits rows)."""
    return data.replace(b"\r\n", b"\n").replace(b"\r", b"\n") if b"\r" in data else data


def split_head(data: Data, limit: int) -> tuple[list[str], list[int]]:
    """The first ``limit`` lines of LF-separated ``data`` as text, and their byte offsets."""
    starts = [0]
    while len(starts) < limit:
        nl = data.find(b"\n", starts[-1])
        if nl < 0:
            break
        starts.append(nl + 1)
    end = data.find(b"\n", starts[-1])
    head = data[: len(data) if end < 0 else end].decode("utf-8", "replace").split("\n")
    return head, starts


def data_rows(path: Path, text: Text, header: Header, required: list[int]) -> Rows:
    """The data rows: every line after the header up to the footer (a trailing run of text
    lines, :func:`~pipeline.io.csv.header.is_footer`, told in a warning), blank and comment
    lines left out. ``required`` are the indices of the cells a data row must fill."""
    data = text.data
    after = data.find(b"\n", text.starts[header.last_line])
    start = len(data) if after < 0 else after + 1
    end = None
    footer: list[tuple[int, bytes]] = []  # (start, line), last line first
    for line_start, line_end in _lines_backwards(data, start):
        line = data[line_start:line_end]
        if _skipped(line):
            continue
        try:
            cells = cells_of(line.decode("utf-8"), header.delimiter)
        except UnicodeDecodeError as exc:  # a mapped file's lines are checked when parsed
            where = _line_ends(data, 0, line_start) + 1
            raise InputFileError(path, f"not UTF-8 text: {exc.reason}", line=where) from None
        if not is_footer(cells, len(header.cells), required):
            end = line_end
            break
        footer.append((line_start, line))
    if end is None:
        raise InputFileError(path, "no data rows after the header", line=header.index + 1)
    if footer:  # told at its first line: a row left out is never left out quietly
        (at, first), n = footer[-1], len(footer)
        lines = f"{n} trailing lines" if n > 1 else "a trailing line"
        shown = first.decode()[:60].strip()
        message = f"{lines} after the last data row read as a footer (text, no number where a"
        message += f" row has one) and left out, the first: {shown!r}"
        warn_input(path, message, line=_line_ends(data, 0, at) + 1)
    first_line = header.last_line + 2
    while _skipped(data[start : (nl := _line_end(data, start, end))]):
        start, first_line = nl + 1, first_line + 1
    return Rows(data, start, end, first_line)


def _line_end(data: Data, start: int, end: int) -> int:
    nl = data.find(b"\n", start, end)
    return end if nl < 0 else nl


def _lines_backwards(data: Data, start: int) -> Iterator[tuple[int, int]]:
    """``(start, end)`` byte offsets of the lines of ``data[start:]``, last line first."""
    end = len(data)
    while True:
        nl = data.rfind(b"\n", start, end)
        yield (start if nl < 0 else nl + 1), end
        if nl < 0:
            return
        end = nl


def _skipped(line: bytes) -> bool:
    """A blank line or a ``#`` comment line."""
    return line.lstrip(b" \t")[:1] in (b"", b"#")


def _without_skipped(rows: Rows) -> Rows:
    """``rows`` without blank and comment lines (vectorised: files can be large); ``rows``
    itself when it has none (no rows, ``lines`` empty, when it has nothing else)."""
    block = np.frombuffer(rows.data, np.uint8, count=rows.end - rows.start, offset=rows.start)
    padded = np.append(block, np.uint8(ord("\n")))  # the last line's end: walks stop there
    starts = np.concatenate(([0], np.flatnonzero(block == ord("\n")) + 1))
    first = starts.copy()  # first byte of each line that is not a space or tab
    pending = np.flatnonzero(np.isin(padded[first], _BLANKS))
    while len(pending):
        first[pending] += 1
        pending = pending[np.isin(padded[first[pending]], _BLANKS)]
    keep = ~np.isin(padded[first], (ord("\n"), ord("#")))
    if keep.all():
        return rows
    if not keep.any():  # every line skipped (a block of a stream)
        return Rows(b"", 0, 0, rows.first_line, np.empty(0, np.int64))
    lengths = np.diff(np.append(starts, len(block) + 1))  # each line with its newline
    kept = block[np.repeat(keep, lengths)[: len(block)]].tobytes()
    lines = rows.source_lines(len(keep))[keep]
    return Rows(kept, 0, len(kept), int(lines[0]), lines)


# ------------------------------------------------------------------------- parsing


ROWS_BLOCK = 16 << 20
"""Bytes of whole data lines parsed at a time (one block, one batch of a stream)."""


def _block_end(rows: Rows, start: int) -> int:
    """End of the block of whole lines starting at ``start`` (at a line end, or the rows')."""
    stop = rows.data.find(b"\n", min(start + ROWS_BLOCK, rows.end), rows.end)
    return rows.end if stop < 0 else stop


def _spans(rows: Rows) -> Iterator[tuple[int, int]]:
    """``(start, end)`` of each block of whole lines of about :data:`ROWS_BLOCK` bytes."""
    start = rows.start
    while start < rows.end:
        stop = _block_end(rows, start)
        yield start, stop
        start = stop + 1


def _blocks(rows: Rows) -> Iterator[Rows]:
    """``rows`` in blocks (:func:`_spans`), each numbered from its first line (counted)."""
    line = rows.first_line
    for start, stop in _spans(rows):
        block = Rows(rows.data, start, stop, line)
        yield block
        line += block.count()


def _column_names(header: Header, cells: dict[str, Cell]) -> tuple[list[str], dict[str, str]]:
    """The names pyarrow gives the header's columns (c0, c1, …) and, per column of ``cells``,
    the name of the one it is read from."""
    names = [f"c{i}" for i in range(len(header.cells))]
    return names, {name: names[cell.index] for name, cell in cells.items()}


PLAIN_ONLY = (b"\0", b"\r", b"#")
"""Bytes of a block parsed on a worker thread that leave it to :func:`parse` (which names
lines): NUL, CR line ends, comment marks."""


def parse_blocks(
    path: Path,
    rows: Rows,
    header: Header,
    chosen: dict[str, Cell],
    types: dict[str, pa.DataType],
    blanks: frozenset[str],
    decimal: str | None,
) -> Iterator[tuple[dict[str, Any], Rows]]:
    """:func:`parse` a block of about :data:`ROWS_BLOCK` bytes of whole lines at a time:
    each block's columns and the rows they came from (file lines right across blocks), so
    the file is never parsed whole. ``decimal`` None: ',' is tried first when the delimiter
    is not ',' and the rows hold one; at the first block that does not parse so, the mark
    is found over all the rows (:func:`decimal_of`), and if it is '.' the blocks before
    are parsed again with it (an error if one held a decimal comma).

    With more than one reader thread (:func:`~pipeline.io.threads.reader_threads`), blocks
    are scanned here and parsed on that many threads, a few blocks ahead of the one handed
    on: a block's lines are known only once the blocks before it are counted, so a block
    that is not plain ASCII rows of good cells is left to :func:`checked` and :func:`parse`
    in order."""
    mark = decimal or ("," if header.delimiter != "," and rows.anywhere(b",") else ".")
    numbers = {n: c for n, c in chosen.items() if not pa.types.is_string(types[n])}
    names, wanted = _column_names(header, chosen)
    workers = io_threads.reader_threads()
    single = _block_end(rows, rows.start) >= rows.end  # one block: pyarrow's threads
    start, line = rows.start, rows.first_line

    def resolve() -> str:
        nonlocal decimal, mark
        decimal = mark = decimal_of(path, rows, header, numbers)
        if mark == "." and start > rows.start:  # the blocks before must read so too
            before = Rows(rows.data, rows.start, start - 1, rows.first_line)
            for _ in parse_blocks(path, before, header, chosen, types, blanks, mark):
                pass
        return mark

    def scanned() -> Iterator[tuple[int, int, frozenset[bytes] | None]]:
        """Each block's span and the markers it holds, None if it is not plain rows
        (:data:`PLAIN_ONLY`, non-ASCII). Scanned here, on the thread that hands the
        blocks on (the scan holds the GIL; the parses on the workers do not)."""
        for start, stop in _spans(rows):
            found, ascii_only = scan(rows.data, start, stop)
            plain = ascii_only and not any(byte in found for byte in PLAIN_ONLY)
            yield start, stop, found if plain else None

    def attempt(span: tuple[int, int, frozenset[bytes] | None]) -> tuple[str, Any]:
        """The decimal mark used and the block's typed columns (any thread: no line is
        known here), None if the block is not plain rows or a cell does not parse."""
        used, (begin, end, found) = mark, span
        if found is None:
            return used, None
        block = Rows(rows.data, begin, end, rows.first_line, marked=found)  # lines not used
        threads = single and workers > 1
        return used, _typed(block, header, names, wanted, types, blanks, used, threads=threads)

    for (start, stop, _), (used, typed) in in_order(scanned(), attempt, 1 if single else workers):
        block = Rows(rows.data, start, stop, line)
        count = None
        if typed is not None and used == mark:
            count = len(next(iter(typed.values())))
            release(rows.data, start, stop)
            yield _finished(typed, types), block
        else:
            block = checked(path, block)
            # A comment line could parse as a row (a commented-out row); blank lines cannot.
            kept = _without_skipped(block) if block.holds(b"#") else block
            if kept.lines is None or len(kept.lines):
                guessed = resolve if decimal is None and mark == "," else None
                values, used_rows = parse(path, kept, header, chosen, types, blanks, mark, guessed)
                if used_rows is block:  # every line a row
                    count = len(next(iter(values.values())))
                release(rows.data, start, stop)
                yield values, used_rows
        line += block.count() if count is None else count


def decimal_of(path: Path, rows: Rows, header: Header, numbers: dict[str, Cell]) -> str:
    """',' when the ``numbers`` columns' values hold ',' but never '.' (read as strings, a
    block at a time), else '.'."""
    names, wanted = _column_names(header, numbers)
    comma = dot = False
    for block in _blocks(rows):
        kept = _without_skipped(block)
        if kept.lines is not None and not len(kept.lines):
            continue
        found = _decimal_marks(_strings(path, kept, header, names, wanted).values())
        comma, dot = comma or found[0], dot or found[1]
    return "," if comma and not dot else "."


def parse(
    path: Path,
    rows: Rows,
    header: Header,
    chosen: dict[str, Cell],
    types: dict[str, pa.DataType],
    blanks: frozenset[str],
    decimal: str,
    guessed: Callable[[], str] | None = None,
) -> tuple[dict[str, Any], Rows]:
    """Columns ``chosen`` of the rows as arrays of ``types`` (float64, int64 or string), and
    the rows they came from (blank and comment lines left out).

    Floats must be finite decimal numbers with the ``decimal`` mark, integers integers; an
    empty cell is null in the ``blanks`` columns, an error elsewhere. Strings are trimmed,
    empty ones null. When ``decimal`` was a guess, ``guessed`` gives the right mark if the
    rows do not parse with it. Any bad cell or row raises :class:`InputFileError` naming
    its line and column.
    """
    names, wanted = _column_names(header, chosen)
    typed = _typed(rows, header, names, wanted, types, blanks, decimal)
    if typed is None and (kept := _without_skipped(rows)) is not rows:
        rows = kept
        typed = _typed(rows, header, names, wanted, types, blanks, decimal)
    if typed is None:
        strings = _strings(path, rows, header, names, wanted)
        if guessed is not None:
            decimal = guessed()
        typed = {
            name: _converted(
                path, strings[name], types[name], name in blanks, decimal, rows, chosen[name].text
            )
            for name in wanted
        }
    return _finished(typed, types), rows


def _finished(typed: dict[str, Any], types: dict[str, pa.DataType]) -> dict[str, Any]:
    """Parsed columns with their strings trimmed, empty ones null."""
    return {
        name: _blank_to_null(values) if pa.types.is_string(types[name]) else values
        for name, values in typed.items()
    }


def _typed(
    rows: Rows,
    header: Header,
    names: list[str],
    wanted: dict[str, str],
    types: dict[str, pa.DataType],
    blanks: frozenset[str],
    decimal: str,
    *,
    threads: bool = False,
) -> dict[str, Any] | None:
    """The columns parsed by pyarrow with their types (in one pass, on pyarrow's threads
    if ``threads``; quotes only looked for when the rows hold one); None when that does
    not give exactly the rows' values (then :func:`_strings` finds out why). A blank line
    is an invalid row here, so it cannot go unnoticed."""
    quoted = rows.holds(b'"')
    try:
        table = pacsv.read_csv(
            pa.BufferReader(rows.buffer()),
            read_options=read_options(names, threads=threads),
            parse_options=pacsv.ParseOptions(
                delimiter=header.delimiter,
                quote_char='"' if quoted else False,
                double_quote=quoted,
                ignore_empty_lines=False,
            ),
            convert_options=pacsv.ConvertOptions(
                column_types={wanted[n]: types[n] for n in wanted},
                include_columns=list(wanted.values()),
                null_values=[""],
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
                decimal_point=decimal,
            ),
        )
    except pa.ArrowException:
        return None
    if quoted and table.num_rows != rows.count():  # a quoted cell spans lines
        return None
    columns = {name: table.column(col) for name, col in wanted.items()}
    for name, values in columns.items():
        if values.null_count and name not in blanks and not pa.types.is_string(types[name]):
            return None
        if pa.types.is_floating(types[name]) and not _finite(values):
            return None
    return columns


def _finite(values: pa.ChunkedArray) -> bool:
    """Whether every value of a float column is finite (nulls aside)."""
    extremes = value_range(values)
    if extremes is None:
        return bool(pc.all(pc.is_finite(values)).as_py())
    return bool(np.isfinite(extremes[0]) and np.isfinite(extremes[1]))


def _strings(
    path: Path, rows: Rows, header: Header, names: list[str], wanted: dict[str, str]
) -> dict[str, pa.Array]:
    """The wanted columns as strings (one thread, so bad rows are located)."""
    invalid: list[tuple[int, int]] = []

    def on_invalid(row: Any) -> str:
        invalid.append((row.number, row.actual_columns))
        return "skip"

    size = rows.end - rows.start
    try:
        table = pacsv.read_csv(
            pa.BufferReader(rows.buffer()),
            read_options=pacsv.ReadOptions(
                column_names=names, use_threads=False, block_size=min(size + 1, 1 << 30)
            ),
            parse_options=pacsv.ParseOptions(
                delimiter=header.delimiter, invalid_row_handler=on_invalid
            ),
            convert_options=pacsv.ConvertOptions(
                column_types=dict.fromkeys(names, pa.string()),
                include_columns=list(wanted.values()),
                strings_can_be_null=False,
                quoted_strings_can_be_null=False,
            ),
        )
    except pa.ArrowException as exc:
        raise InputFileError(path, f"cannot parse the data rows: {exc}") from None
    if table.num_rows + len(invalid) != rows.count():
        lines = rows.text_lines()
        odd = next((i for i, line in enumerate(lines) if line.count('"') % 2), 0)
        raise InputFileError(
            path, "unbalanced double quote: a quoted cell spans lines", line=rows.line(odd)
        )
    if invalid:
        number, got = invalid[0]
        raise InputFileError(
            path,
            f"expected {len(names)} cells as in the header (line {header.index + 1}), got {got}"
            + (f"; {len(invalid)} such rows" if len(invalid) > 1 else ""),
            line=rows.line(number - 1),
        )
    return {name: table.column(col).combine_chunks() for name, col in wanted.items()}


def _decimal_marks(columns: Iterable[pa.Array]) -> tuple[bool, bool]:
    """Whether some value holds a ',', and whether some holds a '.'."""
    cols = list(columns)
    comma = any(pc.any(pc.match_substring(c, ",")).as_py() for c in cols)
    dot = any(pc.any(pc.match_substring(c, ".")).as_py() for c in cols)
    return comma, dot


def _converted(
    path: Path,
    strings: pa.Array,
    kind: pa.DataType,
    blank: bool,
    decimal: str,
    rows: Rows,
    column: str,
) -> pa.Array:
    """A column of strings as ``kind``; a bad cell (an empty one too unless ``blank``: then
    it is null) raises with its line. Accepted around whitespace: decimal numbers with
    optional sign and exponent (not nan/inf) and integers with an optional '-'."""
    if pa.types.is_string(kind):
        return strings
    integer = pa.types.is_integer(kind)
    cells = _blank_to_null(strings) if blank else pc.utf8_trim_whitespace(strings)
    bad = pc.invert(pc.match_substring_regex(cells, _INTEGER if integer else _NUMBER[decimal]))
    found = np.flatnonzero(pc.fill_null(bad, False).to_numpy(zero_copy_only=False))
    if len(found):
        shown = ", ".join(
            f"{_cell_text(cells[int(i)].as_py())} (line {rows.line(int(i))})" for i in found[:SHOWN]
        )
        hint = " (for decimal commas set the option decimal=',')"
        raise InputFileError(
            path,
            f"expected {'an integer' if integer else 'a number'}, got "
            f"{_cell_text(cells[int(found[0])].as_py())}"
            + (hint if decimal == "." and not integer else "")
            + (f"; {len(found)} bad cells: {shown}" if len(found) > 1 else ""),
            line=rows.line(int(found[0])),
            column=column,
        )
    if decimal == "," and not integer:
        cells = pc.replace_substring(cells, ",", ".")
    values = pc.cast(cells, kind)
    if not integer:
        _refuse_overflow(path, strings, values, rows, column)
    return values


def _refuse_overflow(
    path: Path, strings: pa.Array, values: pa.Array, rows: Rows, column: str
) -> None:
    """A decimal number too large for a float (``1e999``, 400 digits) is ±inf: an error
    naming its line and column, as a ``nan`` cell is."""
    infinite = np.flatnonzero(pc.fill_null(pc.is_inf(values), False).to_numpy(zero_copy_only=False))
    if not len(infinite):
        return
    first = int(infinite[0])
    text = str(strings[first].as_py()).strip()
    shown = text if len(text) <= 40 else f"{text[:20]}…{text[-10:]} ({len(text)} characters)"
    raise InputFileError(
        path,
        f"expected a finite number, got {shown!r}: too large for a 64-bit float (±inf)"
        + (f"; {len(infinite)} such cells" if len(infinite) > 1 else ""),
        line=rows.line(first),
        column=column,
    )


def _blank_to_null(strings: Any) -> Any:
    """Trimmed strings, empty ones null."""
    trimmed = pc.utf8_trim_whitespace(strings)
    return pc.if_else(pc.equal(trimmed, ""), pa.scalar(None, pa.string()), trimmed)


def _cell_text(value: str) -> str:
    return "an empty cell" if value == "" else repr(value)

"""The ``~A`` data rows of a LAS file: the values of the curves read, with the file line of
each row, their nulls, and the index checked against STRT/STOP/STEP.

The rows come a block at a time (:func:`data_blocks`, for a stream):
:func:`~pipeline.io.las.fast.fast_blocks` (numpy + ``pyarrow.csv``; see
``benchmarks/bench_las.py``) reads plain blocks of numbers; :func:`_slow_values`, the
careful path, reads the blocks it declines, or the whole section when it cannot apply
(wrapped files, comment or blank lines, lone CR line ends, text in unread curves, LAS 3
delimiters, quoted text) and locates every error by line. Both give every number correctly
rounded, so values equal lasio's. For a log
(:mod:`pipeline.io.las.log`), :func:`read_all` reads every curve by the fast path, else
:func:`read_cells` gives the text of every cell. ``NULL`` items and the option
``null_values`` become nulls (compared as numbers: ``-999.2500`` is ``-999.25``). A row
with too many or too few values, a cell that is not a finite number, a null index value and
an index contradicting STRT/STOP/STEP (a truncated file, a lost row) are errors with their
line: no value is ever dropped or shifted. Each row keeps its file line (the table's
``source_line``).
"""

from __future__ import annotations

import csv as stdcsv
import re
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from numpy.typing import NDArray

from pipeline.errors import InputFileError, UnitError, warn_input
from pipeline.io.las.fast import Declined, fast_blocks, fast_values
from pipeline.io.las.header import (
    NUMBER,
    Header,
    Source,
    decode,
    header_number,
    mnemonics,
    section_role,
    split_lines,
)
from pipeline.io.las.options import LasOptions
from pipeline.io.nulls import NULL_MARKERS
from pipeline.units import conversion_factor

Floats = NDArray[np.float64]
Lines = NDArray[np.int64]
Mask = NDArray[np.bool_]
Bytes = NDArray[np.uint8]


@dataclass(frozen=True)
class Data:
    """Values of the curves read (by ~Curve position), the file line of each row and,
    where known (the fast path), the smallest and largest value of each curve."""

    values: dict[int, Floats]
    lines: Lines
    ranges: dict[int, tuple[float, float]] = field(default_factory=dict)


# ------------------------------------------------------------------------------ data


def data_blocks(path: Path, source: Source, header: Header, wanted: list[int]) -> Iterator[Data]:
    """Values of the ``wanted`` curves a block of rows at a time: by the fast path, and by
    the careful path the blocks it declines (any error located there)."""
    line = source.title_line + 1
    if header.version < 3 and not header.wrapped and header.delimiter == "SPACE":
        for block in fast_blocks(source.raw, source.start, len(header.curves), wanted):
            if isinstance(block, Declined):
                piece = source.raw[block.start : block.end]
                lines = split_lines(decode(path, piece, line))
                yield _slow_values(path, header, lines, source.title_line, wanted, first=line)
                line += len(lines) - 1  # a block ends with its last line's LF
            else:
                rows = np.arange(line, line + block.rows, dtype=np.int64)
                yield Data(block.values, rows, block.ranges)
                line += block.rows
        return
    text = decode(path, source.raw[source.start :], line)
    yield _slow_values(path, header, split_lines(text), source.title_line, wanted)


def _slow_values(
    path: Path,
    header: Header,
    lines: list[str],
    title_line: int,
    wanted: list[int],
    *,
    first: int | None = None,
) -> Data:
    """The careful path: rows from lines (wrapped or not, any delimiter; comment and blank
    lines skipped), every value checked as a number with its line. ``lines`` start on file
    line ``first`` (default: the one after the title)."""
    n = len(header.curves)
    cells = _slow_cells(path, header, lines, title_line, wanted, n, first=first)
    return Data(
        {
            i: _numbers(path, column, cells.lines, header.curves[i].mnemonic)
            for i, column in zip(wanted, cells.columns, strict=True)
        },
        cells.lines,
    )


@dataclass(frozen=True)
class Cells:
    """The text of the cells of the curves read (``''``: an empty or unknowable cell) and
    the file line of each row."""

    columns: list[list[str]]
    lines: Lines


def read_all(path: Path, source: Source, header: Header) -> list[Data] | Cells:
    """Every curve of a log: their values a block of rows at a time when the fast path
    reads them all (blocks of numbers), else the text of every cell (:func:`read_cells`)."""
    n = len(header.curves)
    if n and header.version < 3 and not header.wrapped and header.delimiter == "SPACE":
        blocks = fast_values(source.raw, source.start, n, list(range(n)))
        if blocks is not None:
            line, data = source.title_line + 1, []
            for block in blocks:
                rows = np.arange(line, line + block.rows, dtype=np.int64)
                data.append(Data(block.values, rows, block.ranges))
                line += block.rows
            return data
    return read_cells(path, source, header)


def read_cells(path: Path, source: Source, header: Header) -> Cells:
    """The text of every cell of the data section, for a log: rows as :func:`data_blocks`
    reads them, except that a short row whose fixed-width values ran together is split as
    lasio splits it (``7.330-19508.961``: 7.330 and -19508.961; ``7.020101130.188``: two
    values whose border cannot be known, read as empty cells with a warning). Without a
    ~Curve section the first row sets the number of columns."""
    first = source.title_line + 1
    text = decode(path, source.raw[source.start :], first)
    n = len(header.curves)
    return _slow_cells(path, header, split_lines(text), source.title_line, None, n, repair=True)


def _slow_cells(
    path: Path,
    header: Header,
    lines: list[str],
    title_line: int,
    wanted: list[int] | None,
    n: int,
    *,
    repair: bool = False,
    first: int | None = None,
) -> Cells:
    """Cells of the ``wanted`` curves (None: all) of rows of ``n`` values (0: as many as
    the first row has); ``lines`` start on file line ``first`` (default: after the title)."""
    numbered = _data_lines(path, header, lines, title_line, first)
    if n == 0:
        if header.wrapped:
            raise InputFileError(path, "wrapped data (WRAP YES) without a ~Curve section")
        numbered = _first_row_sets_count(path, numbered)
    rows = (
        _wrapped_rows(path, numbered, n)
        if header.wrapped
        else _unwrapped_rows(path, header, numbered, n, repair=repair)
    )
    starts: list[int] = []
    if wanted is None:
        table: list[list[str]] = []
        for line, row in rows:
            starts.append(line)
            table.append(row)
        count = len(table[0]) if table else n
        columns = [list(c) for c in zip(*table, strict=True)] if table else [[]] * count
    else:
        columns = [[] for _ in wanted]
        for line, row in rows:
            starts.append(line)
            for column, i in zip(columns, wanted, strict=True):
                column.append(row[i])
    return Cells(columns, np.asarray(starts, dtype=np.int64))


def _first_row_sets_count(
    path: Path, numbered: Iterator[tuple[int, list[str]]]
) -> Iterator[tuple[int, list[str]]]:
    """Rows checked against the value count of the first (a file without ~Curve)."""
    n = 0
    for number, values in numbered:
        n = n or len(values)
        if len(values) != n:
            raise InputFileError(
                path, f"expected {n} values (as many as the first row), got {len(values)}", number
            )
        yield number, values


def _data_lines(
    path: Path, header: Header, lines: list[str], title_line: int, first: int | None
) -> Iterator[tuple[int, list[str]]]:
    """(file line, values) of each data line up to the end of the data section; ``lines``
    start on file line ``first`` (None: the one after the title)."""
    split = _splitter(header)
    for number, line in enumerate(lines, start=first or title_line + 1):
        text = line.replace("\x1a", "").strip()  # ^Z: an old DOS end-of-file mark
        if not text or text.startswith("#"):
            continue
        if text.startswith("~"):
            if section_role(text) == "data":
                raise InputFileError(
                    path,
                    f"a second data section (the first starts on line {title_line}): a LAS "
                    "file has one",
                    line=number,
                )
            if header.version >= 3:
                return
            raise InputFileError(
                path,
                f"section {text.split()[0]!r} after the ~A section: ~A must be the last",
                line=number,
            )
        yield number, split(text)


_SPACE_CELLS = re.compile(r"""([^\s"']+)|"([^"]*)"|'([^']*)'""")
_TAB_CELLS = re.compile(r"""([^\t"']+)|"([^"]*)"|'([^']*)'""")


def _splitter(header: Header) -> Callable[[str], list[str]]:
    """Splits a data line into values as lasio does: at whitespace (DLM SPACE, the
    default) or tabs (DLM TAB), a value in double or single quotes may hold them; at
    commas (DLM COMMA; a value in double quotes may hold one)."""
    if header.delimiter == "COMMA":
        return lambda text: [cell.strip() for cell in next(stdcsv.reader([text]))]
    pattern = _TAB_CELLS if header.delimiter == "TAB" else _SPACE_CELLS

    def split(text: str) -> list[str]:
        if header.delimiter == "SPACE" and '"' not in text and "'" not in text:
            return text.split()
        return ["".join(groups).strip() for groups in pattern.findall(text)]

    return split


def _unwrapped_rows(
    path: Path,
    header: Header,
    numbered: Iterable[tuple[int, list[str]]],
    n: int,
    *,
    repair: bool = False,
) -> Iterator[tuple[int, list[str]]]:
    for number, values in numbered:
        if len(values) < n and repair:
            values = _run_on(path, header, number, values, n)
        if n and len(values) != n:
            names = f"one per curve: {mnemonics(header.curves)}" if header.curves else "per row"
            raise InputFileError(
                path, f"expected {n} values ({names}), got {len(values)}", line=number
            )
        yield number, values


_RUN_ON_MINUS = re.compile(r"(?<=[0-9.])(?=-[0-9.])")
_RUN_ON_DOTS = re.compile(r"-?[0-9]*\.[0-9]*(?:\.[0-9]*)+")


def _run_on(path: Path, header: Header, line: int, values: list[str], n: int) -> list[str]:
    """A row of ``n`` values from one whose fixed-width values ran together, or ``values``
    unchanged: ``1.5-2.0`` is 1.5 and -2.0; ``7.020101130.188`` is two values whose border
    cannot be known (as many as it has decimal points), read as empty cells with a
    warning."""
    fixed: list[str] = []
    unknown: list[int] = []
    for value in values:
        parts = _RUN_ON_MINUS.split(value)
        if len(parts) > 1 and all(re.fullmatch(NUMBER, p) for p in parts):
            fixed += parts
        elif _RUN_ON_DOTS.fullmatch(value):
            unknown += range(len(fixed), len(fixed) + value.count("."))
            fixed += [""] * value.count(".")
        else:
            fixed.append(value)
    if len(fixed) != n:
        return values
    if unknown:
        at = 0
        for value in values:
            if _RUN_ON_DOTS.fullmatch(value):
                break
            at += 1
        names = [header.curves[i].mnemonic if header.curves else str(i + 1) for i in unknown]
        warn_input(
            path,
            f"{values[at]!r} holds {len(unknown)} values run together ({', '.join(names)}) "
            "and where one ends cannot be known: read as nulls",
            line,
        )
    return fixed


def _wrapped_rows(
    path: Path, numbered: Iterable[tuple[int, list[str]]], n: int
) -> Iterator[tuple[int, list[str]]]:
    """Rows of wrapped data: each starts with its index value alone on a line and takes
    the next lines until it has ``n`` values; a row's line is its index line."""
    row: list[str] = []
    start = 0
    for number, values in numbered:
        if not row:
            if len(values) != 1:
                raise InputFileError(
                    path,
                    f"wrapped data (WRAP YES): a row starts with its index value alone on a "
                    f"line, got {len(values)} values",
                    line=number,
                )
            start = number
        row += values
        if len(row) > n:
            raise InputFileError(
                path,
                f"wrapped data: the row of line {start} has {len(row)} values here, more "
                f"than the {n} curves",
                line=number,
            )
        if len(row) == n:
            yield start, row
            row = []
    if row:
        raise InputFileError(
            path,
            f"wrapped data: the last row has {len(row)} of {n} values (truncated file?)",
            line=start,
        )


def _numbers(path: Path, cells: list[str], lines: Lines, mnemonic: str) -> Floats:
    """float64 values of one curve's cells; a cell that is not a finite decimal number
    raises with its line."""
    strings = pa.array(cells, pa.string())
    bad = pc.invert(pc.match_substring_regex(strings, NUMBER))
    if pc.any(bad).as_py():
        row = int(np.flatnonzero(bad.to_numpy(zero_copy_only=False))[0])
        raise InputFileError(
            path, f"expected a number, got {cells[row]!r}", line=int(lines[row]), column=mnemonic
        )
    values: Floats = pc.cast(strings, pa.float64()).to_numpy()
    infinite = np.flatnonzero(~np.isfinite(values))
    if infinite.size:
        row = int(infinite[0])
        raise InputFileError(
            path, f"{cells[row]!r} is out of range", line=int(lines[row]), column=mnemonic
        )
    return values


# ----------------------------------------------------------------- nulls and the index


def null_values(path: Path, header: Header, opts: LasOptions) -> list[float]:
    """Values meaning 'no value': every NULL item of ~Well/~Parameter, the option's and the
    null markers of every reader (-999.25…, :data:`~pipeline.io.nulls.NULL_MARKERS`)."""
    items = [i for i in header.well + header.parameters if i.mnemonic == "NULL" and i.value]
    found = [header_number(path, item) for item in items] + list(opts.null_values)
    return found + [m for m in NULL_MARKERS if m not in found]


def null_mask(
    values: Floats, nulls: list[float], extremes: tuple[float, float] | None = None
) -> Mask:
    """Where ``values`` equal any of ``nulls`` (a comparison each of those within the
    values' range, ``extremes`` when known: a list is short, and most columns hold none)."""
    mask = np.zeros(values.shape, dtype=bool)
    if values.size:
        low, high = extremes or (float(values.min()), float(values.max()))
        if np.isfinite(low) and np.isfinite(high):
            nulls = [null for null in nulls if low <= null <= high]
    for null in nulls:
        mask |= values == null
    return mask


def check_index(
    path: Path, header: Header, data: Data, masks: dict[int, Mask], keys: list[int]
) -> None:
    """The index (first curve) and the kind's key column have no nulls in these rows."""
    for i in keys:
        nulls = np.flatnonzero(masks[i])
        if nulls.size:
            curve = header.curves[i]
            raise InputFileError(
                path,
                f"null value {data.values[i][nulls[0]]:g} in curve {curve.mnemonic}: every row "
                f"needs its {'index' if i == 0 else curve.mnemonic} value"
                + (f" ({nulls.size} null rows)" if nulls.size > 1 else ""),
                line=int(data.lines[nulls[0]]),
                column=curve.mnemonic,
            )


class IndexRange:
    """The index (first curve, in its unit) agrees with STRT, STOP and STEP where they are
    given and not null, within the rounding of their written digits (STEP: or 1 %),
    checked over the rows a block at a time (:meth:`feed`, then :meth:`finish`; errors in
    the order STRT, STOP, STEP whatever block they are in). No rows is an error."""

    def __init__(self, path: Path, header: Header, nulls: list[float]) -> None:
        self.path, self.curve = path, header.curves[0]
        self.declared: dict[str, tuple[float, float, int]] = {}
        for mnemonic in ("STRT", "STOP", "STEP"):
            item = header.find(path, mnemonic)
            ratio = _unit_ratio(item.unit, self.curve.unit) if item else None
            if item is None or ratio is None or header_number(path, item) in nulls:
                continue
            value = header_number(path, item) * ratio
            self.declared[mnemonic] = (value, _half_unit(item.value) * abs(ratio), item.line)
        self.last: tuple[float, int] | None = None
        self.step_error: InputFileError | None = None

    def feed(self, index: Floats, lines: Lines) -> None:
        """The next rows' index values and file lines."""
        if index.size == 0:
            return
        previous, self.last = self.last, (float(index[-1]), int(lines[-1]))
        if previous is None:
            self._bound("STRT", float(index[0]), int(lines[0]))
        step, tolerance, _ = self.declared.get("STEP", (0.0, 0.0, 0))
        if step == 0 or self.step_error is not None:
            return
        limit = max(tolerance, 0.01 * abs(step))
        if previous is not None:  # the step from the rows before
            self._steps(
                np.array([previous[0], index[0]]), [previous[1], int(lines[0])], step, limit
            )
        if index.size > 1 and self.step_error is None:
            self._steps(index, lines, step, limit)

    def _steps(self, index: Floats, lines: Lines | list[int], step: float, limit: float) -> None:
        """The first step of ``index`` (rows on file ``lines``) more than ``limit`` off
        ``step``, kept as the error. The smallest and largest step bound every other
        (rounding keeps their order), so only where they are off is each step compared."""
        with np.errstate(over="ignore", invalid="ignore"):  # a step past the float range
            steps = np.diff(index)  # is ±inf, unequal to any STEP: reported
            low, high = float(steps.min()), float(steps.max())
            if abs(low - step) <= limit and abs(high - step) <= limit:
                return  # (a NaN fails both: compared)
            bad = np.flatnonzero(np.abs(steps - step) > limit)
        if bad.size:
            k = int(bad[0])
            by = f"{steps[k]:g}" if np.isfinite(steps[k]) else "more than the float range"
            self.step_error = InputFileError(
                self.path,
                f"STEP is {step:g} but the index steps by {by} from line {lines[k]} to "
                "this line: a row may be missing or repeated (STEP 0 means irregular steps)",
                line=int(lines[k + 1]),
            )

    def finish(self) -> None:
        """After the last rows: STOP, then the first wrong step."""
        if self.last is None:
            raise InputFileError(self.path, "no data rows in the ~A section")
        self._bound("STOP", *self.last)
        if self.step_error is not None:
            raise self.step_error

    def _bound(self, mnemonic: str, value: float, line: int) -> None:
        if mnemonic not in self.declared:
            return
        declared, tolerance, item_line = self.declared[mnemonic]
        if abs(value - declared) > tolerance + 1e-12 * abs(declared):
            first = mnemonic == "STRT"
            raise InputFileError(
                self.path,
                f"{mnemonic} is {declared:g} but the {'first' if first else 'last'} index "
                f"value ({self.curve.mnemonic}) is {value:g} on line {line}"
                + ("" if first else ": the file may be truncated"),
                line=item_line if first else line,
            )


def _unit_ratio(unit: str, index_unit: str) -> float | None:
    """Factor from ``unit`` to ``index_unit`` (1 when either is blank); None if unknown."""
    if not unit or not index_unit or unit.casefold() == index_unit.casefold():
        return 1.0
    for quantity in ("length", "time"):
        try:
            return conversion_factor(unit, quantity) / conversion_factor(index_unit, quantity)
        except UnitError:
            continue
    return None


def _half_unit(text: str) -> float:
    """Half a unit of the last written digit of a number (its rounding)."""
    try:
        exponent = Decimal(text).as_tuple().exponent
    except InvalidOperation:
        return 0.0
    if not isinstance(exponent, int):
        return 0.0
    return 0.5 * 10.0 ** min(exponent, 308)  # past 1e308 a number is ±inf: refused before

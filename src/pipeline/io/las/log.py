"""The ``log`` kind of the LAS reader: any LAS 1.2, 2.0 or 3.0 log as a table of its curves.

* **Columns** — one per ~Curve (LAS 3: ~Log_Definition) line, in file order, the first being
  the index (depth, time or whatever the file is indexed by). A column is named by its
  mnemonic in upper case, as lasio names it: a mnemonic given several times becomes
  ``NAME:1``, ``NAME:2``…; an empty one ``UNKNOWN``; a file without a ~Curve section has
  columns ``UNKNOWN:1``… (as many as the first row has values, with a warning). Then
  ``source_line``, the file line of each row.
* **Units** — each field's ``unit`` metadata is the curve's unit exactly as written (none
  when the file gives none), and its ``description`` metadata the curve's description
  (without a LAS 3 format or association: ``{F}``, ``| Run[1]``). A
  log's values are kept in the file's units, never converted: its curves are any of
  hundreds of quantities (GAPI, OHMM, K/M3, CFCF), most without a canonical unit, and a
  table half converted would be worse than one left as logged. Read the file as
  ``stations`` or ``samples`` for canonical units.
* **Values** — a curve whose cells are all numbers (or nulls) is float64; any other is a
  string column with its cells as written (surrounding spaces and quotes removed), such as
  times of day (``00:00:00``) and dates, which are left as text, not guessed into seconds:
  the file does not say which day or time zone they belong to. A LAS 3 curve whose format
  is ``{S}`` or a date/time pattern (``{DD/MM/YYYY}``, ``{hh:mm:ss}``) is always text.
  A decimal comma (``123,45``) reads as a decimal point where commas cannot delimit values
  (DLM SPACE or TAB), as lasio does.
* **Nulls** — NaN in float columns, null in string columns: an empty cell, the NULL value of
  ~Well/~Parameter and the option ``null_values`` (compared as numbers), and the text nulls
  ``(null)``, ``NULL``, ``NaN``, ``#N/A``, Windows' ``-1.#IND``/``1.#INF``/``1.#QNAN`` and
  runs of dashes (``-``, ``--``). The NULL value is not applied to the index, as lasio does
  not: a row's index value is its key (a depth of -999.25 is not "no depth").
* **Rows** — a row with too few or too many values is an error naming its line: lasio
  reshapes the values into rows silently, shifting every value after the mistake. Values
  that ran together in fixed-width columns are split as lasio splits them (see
  :func:`pipeline.io.las.rows.read_cells`). STRT, STOP and STEP that contradict the index
  are warnings naming their line (the data are kept: a log's header is often stale), as
  are well metadata items that cannot be read. An index that is not finite and strictly
  monotonic (:class:`~pipeline.tables.LogTable`) and a cell spelling an infinite number
  (``-inf``, ``Infinity``) are errors naming their line.
"""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from pipeline.contracts import DESCRIPTION_KEY, SOURCE_LINE, UNIT_KEY
from pipeline.errors import ContractViolation, InputFileError, UnitError, warn_input
from pipeline.io.las.header import NUMBER, SHOWN, Header, Item, Source
from pipeline.io.las.options import LasOptions
from pipeline.io.las.rows import Cells, Data, IndexRange, null_mask, null_values, read_all
from pipeline.io.mnemonics import canonical_name
from pipeline.tables import LogTable
from pipeline.units import conversion_factor

TEXT_NULL = r"^(?:\(null\)|null|[+-]?nan|#n/a|[+-]?1\.#(?:ind|inf|qnan|snan|io)[0-9]*|-+)$"
"""Cells meaning 'no value' whatever the NULL item says (compared ignoring case)."""
_INFINITE = r"^[+-]?(?:inf|infinity)$"
"""Cells spelling an infinite number: a number out of range, not text (compared ignoring
case)."""
_DECIMAL_COMMA = r"^([+-]?[0-9]*),([0-9]+(?:[eE][+-]?[0-9]+)?)$"
_FORMAT = re.compile(r"\{([^}]*)\}\s*(?:\|.*)?$")
_TEXT_FORMAT = re.compile(r"S|A[0-9]*|.*[/:].*|[DMYhms]+", re.IGNORECASE)


def read_log(path: Path, source: Source, header: Header, opts: LasOptions) -> pa.Table:
    """The log's table (see the module docstring)."""
    for option in ("columns", "units"):
        if getattr(opts, option):
            raise InputFileError(
                path,
                f"option {option} names canonical columns of stations or samples, not "
                "the curves of a log (a log keeps every curve, in its own unit)",
            )
    nulls = null_values(path, header, opts)
    if source.title_line == 0:
        warn_input(path, "no ~A (data) section: the log has no rows")
        data: list[Data] | Cells = Cells([[] for _ in header.curves], np.empty(0, np.int64))
    else:
        data = read_all(path, source, header)
    arrays: list[pa.Array | pa.ChunkedArray]
    if isinstance(data, list):  # blocks of numbers
        arrays = [
            pa.chunked_array(
                [_floats(d.values[i], nulls, i == 0, d.ranges.get(i)) for d in data],
                pa.float64(),
            )
            for i in range(len(header.curves))
        ]
        index = [(d.values[0], d.lines) for d in data]
        lines: pa.Array | pa.ChunkedArray = pa.chunked_array([d.lines for d in data], pa.int64())
    else:
        arrays = [
            _typed(path, cells, data.lines, _curve(header, i), nulls, header, i == 0)
            for i, cells in enumerate(data.columns)
        ]
        floating = arrays and data.lines.size and pa.types.is_floating(arrays[0].type)
        index = [(arrays[0].to_numpy(zero_copy_only=False), data.lines)] if floating else []
        lines = pa.array(data.lines, pa.int64())
    if not header.curves and arrays:
        warn_input(
            path,
            f"no ~Curve section: the {len(arrays)} columns are named UNKNOWN:1… (as lasio "
            "names them), with no units",
        )
    _check_range(path, header, index, nulls)
    table = _table(header, arrays, lines)
    try:  # an index that is no key (not finite, out of order, text in a depth unit)
        LogTable.validate_table(table)
    except ContractViolation as exc:
        lines_at = [n for failure in exc.failures for n in failure.lines]
        rules = "; ".join(map(str, exc.failures))
        raise InputFileError(path, f"not valid as a log: {rules}", min(lines_at)) from None
    return table


def _curve(header: Header, i: int) -> Item | None:
    return header.curves[i] if i < len(header.curves) else None


def _floats(
    values: np.ndarray,
    nulls: list[float],
    index: bool,
    extremes: tuple[float, float] | None = None,
) -> pa.Array:
    if not index and nulls:
        null = null_mask(values, nulls, extremes)
        if null.any():
            values = np.where(null, np.nan, values)
    return pa.array(values, pa.float64())


def _typed(
    path: Path,
    cells: list[str],
    lines: np.ndarray,
    curve: Item | None,
    nulls: list[float],
    header: Header,
    index: bool,
) -> pa.Array:
    """A float64 column if every cell is a number or a null (and the curve is not declared
    text), else a string column."""
    strings = pa.array(cells, pa.string())
    if header.delimiter != "COMMA":
        strings = pc.replace_substring_regex(strings, _DECIMAL_COMMA, r"\1.\2")
    empty = pc.or_(
        pc.equal(pc.utf8_length(strings), 0),
        pc.match_substring_regex(strings, TEXT_NULL, ignore_case=True),
    )
    numeric = pc.or_(
        pc.match_substring_regex(strings, NUMBER),
        pc.match_substring_regex(strings, _INFINITE, ignore_case=True),
    )
    if not _declared_text(curve) and pc.all(pc.or_(numeric, empty)).as_py() is not False:
        values = pc.cast(pc.if_else(empty, pa.scalar(None, pa.string()), strings), pa.float64())
        floats = values.to_numpy(zero_copy_only=False)
        infinite = np.flatnonzero(np.isinf(floats))
        if infinite.size:
            row = int(infinite[0])
            raise InputFileError(
                path,
                f"{cells[row]!r} is out of range",
                line=int(lines[row]),
                column=curve.mnemonic if curve else "",
            )
        return _floats(floats, nulls, index)
    if nulls:
        parsed = pc.cast(pc.if_else(numeric, strings, pa.scalar(None, pa.string())), pa.float64())
        is_null = pc.is_in(parsed, pa.array(nulls, pa.float64())).fill_null(False)
        empty = pc.or_(empty, is_null)
    return pc.if_else(empty, pa.scalar(None, pa.string()), pa.array(cells, pa.string()))


def _declared_text(curve: Item | None) -> bool:
    """Whether a LAS 3 curve's format (``{S}``, ``{DD/MM/YYYY}``) declares text."""
    if curve is None:
        return False
    found = _FORMAT.search(curve.descr)
    return found is not None and _TEXT_FORMAT.fullmatch(found[1].strip()) is not None


def _check_range(
    path: Path, header: Header, index: list[tuple[np.ndarray, np.ndarray]], nulls: list[float]
) -> None:
    """STRT/STOP/STEP against the index (its values and file lines, a block at a time): a
    contradiction is a warning, the data are kept."""
    if not header.curves or not index or np.isnan([index[0][0][0], index[-1][0][-1]]).any():
        return
    checked = IndexRange(path, header, nulls)
    try:
        for values, lines in index:
            checked.feed(values, lines)
        checked.finish()
    except InputFileError as exc:
        warn_input(path, f"{exc.reason}; the data are kept", exc.line)


def column_names(header: Header, n: int) -> list[str]:
    """Column names as lasio gives them (see the module docstring)."""
    if not header.curves:
        return [f"UNKNOWN:{i}" for i in range(1, n + 1)] if n > 1 else ["UNKNOWN"] * n
    names = [c.mnemonic or "UNKNOWN" for c in header.curves]
    counts = Counter(names)
    seen: Counter[str] = Counter()
    unique = []
    for name in names:
        if counts[name] > 1:
            seen[name] += 1
            name = f"{name}:{seen[name]}"
        unique.append(name)
    return unique


def _table(
    header: Header, arrays: list[pa.Array | pa.ChunkedArray], lines: pa.Array | pa.ChunkedArray
) -> pa.Table:
    names = column_names(header, len(arrays))
    fields = []
    for i, (name, array) in enumerate(zip(names, arrays, strict=True)):
        curve = _curve(header, i)
        meta: dict[bytes, bytes] = {}
        if curve is not None and curve.unit:
            meta[UNIT_KEY] = curve.unit.encode()
        descr = _FORMAT.sub("", curve.descr).strip() if curve is not None else ""
        if descr:
            meta[DESCRIPTION_KEY] = descr.encode()
        fields.append(pa.field(name, array.type, metadata=meta or None))
    fields.append(pa.field(SOURCE_LINE, pa.int64()))
    return pa.Table.from_arrays([*arrays, lines], schema=pa.schema(fields))


# ------------------------------------------------------------------------- description


def index_kind(header: Header) -> str:
    """``depth``, ``time`` or ``MNEMONIC`` (what the first curve indexes the log by)."""
    if not header.curves:
        return ""
    first = header.curves[0]
    name = canonical_name(first.mnemonic)
    for kind, quantity in (("depth", "length"), ("time", "time")):
        if name == ("md" if kind == "depth" else "time"):
            return kind
        try:
            conversion_factor(first.unit, quantity)
        except UnitError:
            continue
        return kind
    return first.mnemonic


def describe(header: Header) -> str:
    """What the file looks like, in a few words: ``a depth-indexed LAS log with curves GR,
    RHOB, NPHI``."""
    if not header.curves:
        return "a LAS file without a ~Curve section"
    curves = [c.mnemonic or "UNKNOWN" for c in header.curves[1:]]
    more = f" and {len(curves) - SHOWN} more" if len(curves) > SHOWN else ""
    listed = f" with curves {', '.join(curves[:SHOWN])}{more}" if curves else " with no curve"
    return f"a {index_kind(header)}-indexed LAS log{listed}"

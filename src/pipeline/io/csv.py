"""Built-in CSV plugin: a reader of survey-station CSV files and a CSV writer of any table.

Reading (``kind: stations``) finds the header row, reads the title block above it, parses
the data rows with ``pyarrow.csv`` as strings and converts measured depth to metres and
angles to degrees. File layout, in order:

* **title block** (optional): lines before the header — free text, ``key: value`` or
  ``key=value`` lines (optionally behind ``#``); keys naming well metadata fields fill the
  returned :class:`WellMetadata`, ``north_reference`` declares the azimuth reference;
* **header row**: the first line (within :data:`HEADER_SEARCH_LINES`, never a ``#`` line)
  whose cells, split by one of :data:`DELIMITERS`, name md, inc and azi (see
  :data:`COLUMN_ALIASES`), with units in brackets: ``MD [m]``, ``Measured Depth ( ft )``;
* **data rows**: every later line; blank lines and ``#`` lines are skipped;
* **footer** (optional): a trailing run of lines after the last data row, each of which has
  a non-numeric first cell and either fewer cells than the header or no numeric md/inc/azi
  cell (``End of survey``, ``Total,,,1234``). Any other non-numeric cell is an error naming
  its file line — a truncated or corrupt last row is never dropped as a footer.

Delimiters are detected (``,`` ``;`` tab ``|``; runs of spaces are not supported: names like
``Measured Depth`` make them ambiguous); line ends may be LF, CRLF or CR; text is UTF-8 with
or without a BOM. Decimal commas are read with ``decimal=","`` or when the delimiter is not
``,`` and no md/inc/azi value contains a dot. Units come from the header or the options
``md_unit``/``angle_unit`` (which win), never assumed; the azimuth north reference from the
header, a ``north_reference`` title line or the option, which must agree.

Values are not range-checked here (the engine checks the Stations contract); the table's
``source_line`` column gives each row's 1-based file line so later errors can cite it.

Writing puts ``# gyropipe <well>``, ``# north_reference=<ref>`` and ``# well.<field>=<value>``
lines above a ``name[unit]`` header; the reader reads this back exactly.
"""

from __future__ import annotations

import csv as stdcsv
import io
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import InputFileError, UnitError
from pipeline.hookspecs import hookimpl
from pipeline.registry import ReaderDef, WriterDef
from pipeline.tables import Stations
from pipeline.units import conversion_factor
from pipeline.well import NorthReference, WellMetadata

DELIMITERS = (",", ";", "\t", "|")
HEADER_SEARCH_LINES = 500
SNIFF_BYTES = 64 * 1024
SNIFF_SUFFIXES = (".csv", ".txt", ".tsv")
SHOWN = 5

Canonical = Literal["survey", "md", "inc", "azi"]
REQUIRED: tuple[Canonical, ...] = ("md", "inc", "azi")
COLUMN_ALIASES: dict[Canonical, tuple[str, ...]] = {
    "survey": ("SURVEY", "SURVEY ID"),
    "md": ("MD", "DEPTH", "DEPT", "MEASURED DEPTH", "MEAS DEPTH"),
    "inc": ("INC", "INCL", "INCLINATION", "DEVI", "SDEV", "DEVIATION"),
    "azi": ("AZI", "AZIM", "AZIMUTH", "HAZI"),
}
"""Header names of each column, compared case- and punctuation-insensitively. An azimuth
name may also carry its north reference as a word: ``Azimuth True``, ``AZI GN``,
``Grid Azimuth``, ``Azimuth (MN)``."""

NORTH_WORDS: dict[str, NorthReference] = {
    "true": "true",
    "tn": "true",
    "grid": "grid",
    "gn": "grid",
    "magnetic": "magnetic",
    "mag": "magnetic",
    "mn": "magnetic",
}
WELL_ALIASES = {
    "wellname": "well",
    "api": "uwi",
    "uwiapi": "uwi",
    "operator": "company",
    "lat": "latitude",
    "long": "longitude",
    "lon": "longitude",
    "date": "survey_date",
    "tool": "tool_type",
    "serial": "tool_serial",
}
"""Title-block keys naming WellMetadata fields besides the field names themselves."""
NORTH_KEYS = ("northreference", "azimuthreference")
"""Title-block keys declaring the azimuths' north reference (``north_reference: grid``);
``well.north_reference`` is well metadata instead."""
UNIT_FIELDS = {"latitude": "angle", "longitude": "angle", "elevation": "length"}
"""Well fields whose title-block value may carry a unit (``Elevation: 82 ft``)."""

_BRACKETS = re.compile(r"[\[(]([^\[\]()]*)[\])]")
_TITLE_KEY = re.compile(r"[A-Za-z][\w .\-/]*")
_TITLE_SEPARATOR = re.compile(r"[:=]")
_SKIPPED = re.compile(r"^\s*(#|$)", re.MULTILINE)
"""A blank or ``#`` comment line (skipped wherever it is)."""
_SKIPPED_INSIDE = re.compile(r"\n\s*(#|$)", re.MULTILINE)
_NUMBERISH = re.compile(r"^[+-]?([0-9]+([.,][0-9]*)?|[.,][0-9]+)([eE][+-]?[0-9]+)?$")
_NUMBER = {
    ".": r"^[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+-]?[0-9]+)?$",
    ",": r"^[+-]?([0-9]+(,[0-9]*)?|,[0-9]+)([eE][+-]?[0-9]+)?$",
}


class CsvStationsOptions(BaseModel):
    """Options of the CSV stations reader; every one may be left to detection."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    delimiter: Literal[",", ";", "\t", "|"] | None = Field(
        None, description="field delimiter (default: detected from the header row)"
    )
    decimal: Literal[".", ","] | None = Field(
        None, description="decimal mark (default: ',' only when no value uses '.')"
    )
    columns: dict[Canonical, str] = Field(
        default_factory=dict, description="header text of a column, by canonical name"
    )
    md_unit: str | None = Field(None, description="unit of md; overrides the header's")
    angle_unit: str | None = Field(None, description="unit of inc and azi; overrides the header's")
    north_reference: NorthReference | None = Field(
        None, description="north reference of the azimuths (true, grid or magnetic)"
    )
    default_north_reference: NorthReference | None = Field(
        None,
        description="north reference used only when neither the file nor north_reference "
        "declares one (the engine passes the well metadata's)",
    )

    @field_validator("md_unit")
    @classmethod
    def _length(cls, unit: str | None) -> str | None:
        return _checked_unit(unit, "length")

    @field_validator("angle_unit")
    @classmethod
    def _angle(cls, unit: str | None) -> str | None:
        return _checked_unit(unit, "angle")

    @model_validator(mode="after")
    def _decimal_not_delimiter(self) -> CsvStationsOptions:
        if self.decimal == "," and self.delimiter == ",":
            raise ValueError("decimal ',' needs a delimiter other than ','")
        return self


def _checked_unit(unit: str | None, quantity: str) -> str | None:
    if unit is not None:
        try:
            conversion_factor(unit, quantity)
        except UnitError as exc:
            raise ValueError(str(exc)) from None
    return unit


@dataclass(frozen=True)
class Cell:
    """One header cell: its text, unit and the north references it names."""

    index: int
    text: str
    unit: str | None
    north: tuple[NorthReference, ...]


@dataclass(frozen=True)
class Header:
    """The header row: 0-based line index, delimiter, cells and recognised columns."""

    index: int
    delimiter: str
    cells: list[Cell]
    found: dict[Canonical, list[Cell]]


# ---------------------------------------------------------------------------- reader


def read_stations(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read survey stations: md in m, inc and azi in deg, plus ``source_line`` (file line)."""
    if kind != "stations":
        raise ValueError(f"the csv reader reads kind 'stations', not {kind!r}")
    opts = CsvStationsOptions.model_validate(options or {})
    lines = _split_lines(_decode(path))
    header = _find_header(path, lines, opts)
    well, title_north = _read_title(path, lines[: header.index], header.delimiter)
    declared = title_north + (
        [("option north_reference", opts.north_reference)] if opts.north_reference else []
    )
    chosen = {name: _choose(path, header, name, declared) for name in header.found}
    azi = chosen["azi"]
    north = _north_reference(path, header, azi, declared) or opts.default_north_reference
    if north is None:
        raise InputFileError(
            path,
            "no north reference for the azimuths: name it in the header ('Azimuth True', "
            "'AZI (GN)'), add a line 'north_reference: grid' above the header, or set the "
            "option north_reference (or the well's north_reference)",
            line=header.index + 1,
            column=azi.text,
        )

    rows, block = _data_rows(path, lines, header, chosen)
    strings = _parse_rows(path, lines, rows, block.encode(), header, chosen)
    source_line = rows.astype(np.int64) + 1
    decimal = opts.decimal or _detect_decimal(header.delimiter, [strings[n] for n in REQUIRED])
    units = {"md": opts.md_unit, "inc": opts.angle_unit, "azi": opts.angle_unit}
    data: dict[str, Any] = {}
    if "survey" in strings:
        survey = pc.utf8_trim_whitespace(strings["survey"])
        data["survey"] = pc.if_else(pc.equal(survey, ""), pa.scalar(None, pa.string()), survey)
    for name in REQUIRED:
        cell = chosen[name]
        factor = _factor(path, header, cell, units[name], "length" if name == "md" else "angle")
        values = _numbers(path, strings[name], decimal, source_line, cell.text)
        data[name] = pc.multiply(values, factor)
    data["source_line"] = pa.array(source_line)
    return Stations.compiled().make_table(data, north_reference=north), well


def sniff(path: Path) -> bool:
    """True for a .csv/.txt/.tsv file or one whose first 64 KiB hold a stations header."""
    try:
        if path.suffix.lower() in SNIFF_SUFFIXES:
            return True
        with path.open("rb") as fh:
            head = fh.read(SNIFF_BYTES)
        _find_header(path, _split_lines(head.decode("utf-8-sig", "replace")), CsvStationsOptions())
        return True
    except Exception:  # sniffing never raises: any failure means "not a CSV I can read"
        return False


def _decode(path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc.strerror or exc}") from None
    data = data.removeprefix(b"\xef\xbb\xbf")
    if b"\0" in data:
        line = len(_split_lines(data[: data.index(b"\0")].decode("utf-8", "replace")))
        raise InputFileError(path, "NUL byte: this is not a text CSV file", line=line)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = len(_split_lines(data[: exc.start].decode("utf-8", "replace")))
        raise InputFileError(path, f"not UTF-8 text: {exc.reason}", line=line) from None
    if not text.strip():
        raise InputFileError(path, "the file is empty")
    return text


def _split_lines(text: str) -> list[str]:
    """Lines of ``text`` split at LF, CRLF or a lone CR (as pyarrow.csv splits rows)."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _cells(line: str, delimiter: str) -> list[str]:
    try:
        return next(stdcsv.reader([line], delimiter=delimiter), [])
    except stdcsv.Error:  # e.g. a field over the csv module's size limit: not a header
        return [line]


def _norm(text: str) -> str:
    """Lower case, letters and digits only: ``'Meas. Depth'`` → ``'measdepth'``."""
    return re.sub(r"[^0-9a-z]", "", text.casefold())


_ALIAS_KEYS = {_norm(a): name for name, aliases in COLUMN_ALIASES.items() for a in aliases}


def _parse_cell(index: int, text: str) -> tuple[Cell, Canonical | None]:
    """A header cell and the column its name recognises (None when it names none)."""
    text = text.strip()
    units: list[str] = []
    north: list[NorthReference] = []
    for inner in _BRACKETS.findall(text):
        ref = NORTH_WORDS.get(_norm(inner))
        if ref:
            north.append(ref)
        elif inner.strip():
            units.append(inner.strip())
    words = [w for w in re.split(r"[^0-9a-z]+", _BRACKETS.sub(" ", text).casefold()) if w]
    name = _ALIAS_KEYS.get("".join(words))
    if name is None:
        refs = [NORTH_WORDS[w] for w in words if w in NORTH_WORDS]
        rest = "".join(w for w in words if w not in NORTH_WORDS and w != "north")
        if refs and _ALIAS_KEYS.get(rest) == "azi":
            name, north = "azi", north + refs
    cell = Cell(index, text, units[-1] if units else None, tuple(north))
    return cell, name


def _recognise(
    cells: list[str], opts: CsvStationsOptions
) -> tuple[list[Cell], dict[Canonical, list[Cell]]]:
    parsed = [_parse_cell(i, text) for i, text in enumerate(cells)]
    found: dict[Canonical, list[Cell]] = {}
    explicit = {name: " ".join(text.split()).casefold() for name, text in opts.columns.items()}
    claimed: set[int] = set()
    for name, wanted in explicit.items():
        for cell, _ in parsed:
            bare = _BRACKETS.sub(" ", cell.text)
            if wanted in (
                " ".join(cell.text.split()).casefold(),
                " ".join(bare.split()).casefold(),
            ):
                found.setdefault(name, []).append(cell)
                claimed.add(cell.index)
    for cell, guess in parsed:
        if guess is not None and guess not in explicit and cell.index not in claimed:
            found.setdefault(guess, []).append(cell)
    return [cell for cell, _ in parsed], found


def _find_header(path: Path, lines: list[str], opts: CsvStationsOptions) -> Header:
    """The first line naming md, inc and azi; the delimiter giving most cells wins a tie."""
    delimiters = (
        [opts.delimiter]
        if opts.delimiter
        else [d for d in DELIMITERS if not (opts.decimal == "," and d == ",")]
    )
    best: Header | None = None
    for index, line in enumerate(lines[:HEADER_SEARCH_LINES]):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        candidates = []
        for delimiter in delimiters:
            cells, found = _recognise(_cells(line, delimiter), opts)
            candidates.append(Header(index, delimiter, cells, found))
        for header in sorted(candidates, key=lambda h: -len(h.cells)):
            if all(n in header.found for n in REQUIRED):
                return header
            if _score(header) > max(_score(best), 0):
                best = header
    accepted = (
        "; ".join(f"{name}: {', '.join(COLUMN_ALIASES[name])}" for name in REQUIRED)
        + " (azimuth names may add True/Grid/Magnetic; or set the option columns)"
    )
    if best is None:
        raise InputFileError(
            path,
            f"no header row with md, inc and azi columns in the first {HEADER_SEARCH_LINES} "
            f"lines; accepted names: {accepted}",
        )
    missing = [n for n in REQUIRED if n not in best.found]
    raise InputFileError(
        path,
        f"missing column(s) {', '.join(missing)} in the header row; found "
        f"{', '.join(repr(c.text) for c in best.cells)}; accepted names: {accepted}",
        line=best.index + 1,
    )


def _score(header: Header | None) -> int:
    return -1 if header is None else sum(1 for n in REQUIRED if n in header.found)


def _choose(
    path: Path, header: Header, name: Canonical, declared: list[tuple[str, NorthReference]]
) -> Cell:
    """The one cell of column ``name``; among azimuths, the one of the declared reference."""
    cells = header.found[name]
    if len(cells) > 1 and name == "azi":
        matching = [c for c in cells if set(c.north) & {ref for _, ref in declared}]
        if len(matching) == 1:
            return matching[0]
    if len(cells) > 1:
        raise InputFileError(
            path,
            f"several columns look like {name}: {', '.join(repr(c.text) for c in cells)}; "
            f"choose one with the option columns (e.g. columns: {{{name}: {cells[0].text!r}}})"
            + (" or north_reference" if name == "azi" else ""),
            line=header.index + 1,
        )
    return cells[0]


def _north_reference(
    path: Path, header: Header, azi: Cell, declared: list[tuple[str, NorthReference]]
) -> NorthReference | None:
    sources = [(f"header cell {azi.text!r}", ref) for ref in azi.north] + declared
    refs = sorted({ref for _, ref in sources})
    if len(refs) > 1:
        raise InputFileError(
            path,
            "conflicting north references: " + ", ".join(f"{r} ({s})" for s, r in sources),
            line=header.index + 1,
            column=azi.text,
        )
    return refs[0] if refs else None


def _factor(path: Path, header: Header, cell: Cell, declared: str | None, quantity: str) -> float:
    """Factor to canonical units of the column's unit: declared in the options, else the
    header's."""
    option, one, other = (
        ("md_unit", "m", "ft") if quantity == "length" else ("angle_unit", "deg", "rad")
    )
    unit = declared or cell.unit
    if unit is None:
        raise InputFileError(
            path,
            f"no unit for this column: write it in the header (e.g. '{cell.text} [{one}]' or "
            f"'{cell.text} ({other})') or set the option {option}",
            line=header.index + 1,
            column=cell.text,
        )
    try:
        return conversion_factor(unit, quantity)
    except UnitError as exc:
        raise InputFileError(
            path, f"{exc} (or set the option {option})", line=header.index + 1, column=cell.text
        ) from None


# ------------------------------------------------------------------------ title block


def _read_title(
    path: Path, lines: list[str], delimiter: str
) -> tuple[WellMetadata, list[tuple[str, NorthReference]]]:
    """Well metadata and north-reference declarations of the lines above the header."""
    fields = {_norm(name): name for name in WellMetadata.model_fields}
    keys = {k: v for k, v in fields.items() if k != "northreference"} | WELL_ALIASES
    values: dict[str, tuple[Any, int]] = {}
    north: list[tuple[str, NorthReference]] = []
    for number, line in enumerate(lines, start=1):
        entry = _key_value(line, delimiter)
        if entry is None:
            continue
        key, value = entry
        prefixed = key[:5].casefold() == "well."
        name = _norm(key[5:] if prefixed else key)
        field = fields.get(name) if prefixed else keys.get(name)
        if not prefixed and name in NORTH_KEYS:
            north.append((f"line {number}", _north_word(path, value, number)))
        elif field is not None:
            parsed = _well_value(path, field, value, number)
            if field in values and values[field][0] != parsed:
                raise InputFileError(
                    path,
                    f"{field} is given twice with different values (also on line "
                    f"{values[field][1]})",
                    line=number,
                )
            values[field] = (parsed, number)
    return WellMetadata(**{f: v for f, (v, _) in values.items()}), north


def _key_value(line: str, delimiter: str) -> tuple[str, str] | None:
    """``(key, value)`` of a ``key: value`` / ``# key=value`` line with a non-empty value."""
    comment = line.lstrip().startswith("#")
    junk = " \t" if comment else ' \t"' + delimiter
    text = line.strip().lstrip("#").strip(junk)
    separator = _TITLE_SEPARATOR.search(text)
    if separator is None:
        return None
    key, value = text[: separator.start()].strip(), text[separator.end() :].strip(junk)
    return (key, value) if value and _TITLE_KEY.fullmatch(key) else None


def _north_word(path: Path, value: str, line: int) -> NorthReference:
    words = [w for w in re.split(r"[^0-9a-z]+", value.casefold()) if w and w != "north"]
    if len(words) == 1 and words[0] in NORTH_WORDS:
        return NORTH_WORDS[words[0]]
    raise InputFileError(
        path, f"north reference {value!r} is not one of true, grid, magnetic", line=line
    )


def _well_value(path: Path, field: str, value: str, line: int) -> Any:
    """The validated value of one well field; a number may carry a unit for UNIT_FIELDS."""
    parsed: Any = value
    quantity = UNIT_FIELDS.get(field)
    number = re.match(r"^([+-]?[0-9.]+(?:[eE][+-]?[0-9]+)?)\s*(\S.*)?$", value)
    try:
        if quantity and number:
            factor = conversion_factor(number[2], quantity) if number[2] else 1.0
            parsed = float(number[1]) * factor
        return getattr(WellMetadata.model_validate({field: parsed}), field)
    except (ValueError, UnitError) as exc:  # pydantic's ValidationError is a ValueError
        reason = exc.errors()[0]["msg"] if isinstance(exc, ValidationError) else str(exc)
        raise InputFileError(path, f"invalid {field} {value!r}: {reason}", line=line) from None


# ------------------------------------------------------------------------- data rows


def _data_rows(
    path: Path, lines: list[str], header: Header, chosen: dict[Canonical, Cell]
) -> tuple[np.ndarray, str]:
    """0-based line indices of the data rows (after the header, before the footer) and
    those rows joined by newlines."""
    required = [chosen[n].index for n in REQUIRED]
    for last in range(len(lines) - 1, header.index, -1):
        if _SKIPPED.match(lines[last]):
            continue
        if not _is_footer(_cells(lines[last], header.delimiter), len(header.cells), required):
            break
    else:
        raise InputFileError(path, "no data rows after the header", line=header.index + 1)
    first = header.index + 1
    block = "\n".join(lines[first : last + 1])
    if not (_SKIPPED.match(block) or _SKIPPED_INSIDE.search(block)):  # no blank/comment line
        return np.arange(first, last + 1), block
    rows = [i for i in range(first, last + 1) if not _SKIPPED.match(lines[i])]
    return np.asarray(rows), "\n".join(lines[i] for i in rows)


def _is_footer(cells: list[str], width: int, required: list[int]) -> bool:
    """A line after the data that is text: non-numeric first cell, and fewer cells than the
    header or no numeric md/inc/azi cell."""
    first = next((c.strip() for c in cells if c.strip()), "")
    if _NUMBERISH.match(first):
        return False
    numeric = any(i < len(cells) and _NUMBERISH.match(cells[i].strip()) for i in required)
    return len(cells) < width or not numeric


def _parse_rows(
    path: Path,
    lines: list[str],
    rows: np.ndarray,
    block: bytes,
    header: Header,
    chosen: dict[Canonical, Cell],
) -> dict[Canonical, pa.Array]:
    """The chosen columns of ``block`` (the data rows) as strings; row i is line rows[i] + 1."""
    names = [f"c{i}" for i in range(len(header.cells))]
    wanted = {name: names[cell.index] for name, cell in chosen.items()}
    invalid: list[tuple[int, int]] = []

    def on_invalid(row: Any) -> str:
        invalid.append((row.number, row.actual_columns))
        return "skip"

    try:
        table = pacsv.read_csv(
            io.BytesIO(block),
            read_options=pacsv.ReadOptions(
                column_names=names, use_threads=False, block_size=min(len(block) + 1, 1 << 30)
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
    except pa.ArrowInvalid as exc:
        raise InputFileError(path, f"cannot parse the data rows: {exc}") from None
    if table.num_rows + len(invalid) != len(rows):
        odd = next((int(i) for i in rows if lines[i].count('"') % 2), int(rows[0]))
        raise InputFileError(
            path, "unbalanced double quote: a quoted cell spans lines", line=odd + 1
        )
    if invalid:
        number, got = invalid[0]
        raise InputFileError(
            path,
            f"expected {len(names)} cells as in the header (line {header.index + 1}), got {got}"
            + (f"; {len(invalid)} such rows" if len(invalid) > 1 else ""),
            line=int(rows[number - 1]) + 1,
        )
    return {name: table.column(col).combine_chunks() for name, col in wanted.items()}


def _detect_decimal(delimiter: str, columns: Iterable[pa.Array]) -> str:
    """',' when the delimiter is not ',' and the values use ',' but never '.'; else '.'."""
    if delimiter == ",":
        return "."
    cols = list(columns)
    comma = any(pc.any(pc.match_substring(c, ",")).as_py() for c in cols)
    dot = any(pc.any(pc.match_substring(c, ".")).as_py() for c in cols)
    return "," if comma and not dot else "."


def _numbers(
    path: Path, strings: pa.Array, decimal: str, source_line: np.ndarray, column: str
) -> pa.Array:
    """float64 values of a column of strings; a bad or empty cell raises with its line.

    Accepted: decimal numbers with optional sign and exponent, surrounded by optional
    whitespace (not ``nan``/``inf``, which pyarrow's cast alone would accept).
    """
    if decimal == ".":  # fast path: a plain cast that gives finite values only
        try:
            values = pc.cast(strings, pa.float64())
            if pc.all(pc.is_finite(values)).as_py():
                return values
        except pa.ArrowInvalid:
            pass
    trimmed = pc.utf8_trim_whitespace(strings)
    bad = pc.invert(pc.match_substring_regex(trimmed, _NUMBER[decimal]))
    if pc.any(bad).as_py():
        rows = np.flatnonzero(bad.to_numpy(zero_copy_only=False))
        shown = ", ".join(
            f"{_cell_text(trimmed[int(i)].as_py())} (line {source_line[i]})" for i in rows[:SHOWN]
        )
        hint = " (for decimal commas set the option decimal=',')" if decimal == "." else ""
        raise InputFileError(
            path,
            f"expected a number, got {_cell_text(trimmed[int(rows[0])].as_py())}{hint}"
            + (f"; {len(rows)} bad cells: {shown}" if len(rows) > 1 else ""),
            line=int(source_line[rows[0]]),
            column=column,
        )
    if decimal == ",":
        trimmed = pc.replace_substring(trimmed, ",", ".")
    return pc.cast(trimmed, pa.float64())


def _cell_text(value: str) -> str:
    return "an empty cell" if value == "" else repr(value)


# ---------------------------------------------------------------------------- writer


def write_csv(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` as CSV: comment lines (well, north reference), ``name[unit]`` header,
    then the values (floats in shortest round-trip form)."""
    refs = sorted(
        {
            f.metadata[NORTH_KEY].decode()
            for f in table.schema
            if f.metadata and NORTH_KEY in f.metadata
        }
    )
    if len(refs) > 1:
        raise ValueError(f"columns have different north references {refs}: one file holds one")
    meta = well.model_dump(mode="json", exclude_none=True)
    for key, value in meta.items():
        if "\n" in str(value) or "\r" in str(value):
            raise ValueError(f"well metadata {key} contains a line break: cannot write it as CSV")
    comments = [f"# gyropipe {well.well or '-'}"]
    comments += [f"# north_reference={ref}" for ref in refs]
    comments += [f"# well.{key}={value}" for key, value in meta.items()]
    head = io.StringIO()
    stdcsv.writer(head, lineterminator="\n").writerow([_header_cell(f) for f in table.schema])
    with path.open("wb") as fh:
        fh.write(("\n".join(comments) + "\n" + head.getvalue()).encode())
        pacsv.write_csv(table, fh, pacsv.WriteOptions(include_header=False))


def _header_cell(field: pa.Field) -> str:
    unit = (field.metadata or {}).get(UNIT_KEY)
    return f"{field.name}[{unit.decode()}]" if unit else str(field.name)


# ---------------------------------------------------------------------------- hooks


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="csv",
            description="survey stations (MD, inclination, azimuth) from a delimited text file",
            kinds={"stations": Stations},
            read=read_stations,
            sniff=sniff,
            options=CsvStationsOptions,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="csv",
            description="any table as CSV with units in the header and well metadata comments",
            extension="csv",
            write=write_csv,
        )
    )

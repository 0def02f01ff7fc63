"""Header row, title block and footer of a CSV file (see :mod:`pipeline.io.csv`, the layout).

Header cells name canonical columns through :mod:`pipeline.io.mnemonics` (the ``aliases``
option is consulted first), carry units in brackets (``MD [ft]``, ``Rate X (deg/h)``) and,
for azimuths, their north reference as a word (``Azimuth True``, ``AZI (GN)``,
``Azimuth (Grid North)``).
"""

from __future__ import annotations

import csv as stdcsv
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from pipeline.errors import InputFileError, UnitError, warn_input
from pipeline.io.csv.options import SHORTHANDS, CsvOptions
from pipeline.io.dates import header_date
from pipeline.io.limits import HEADER_LINE_MAX, MAX_COLUMNS, TEXT_MAX, too_long
from pipeline.io.mnemonics import CURVES, canonical_name, normalise
from pipeline.io.nulls import is_null_marker
from pipeline.units import canonical_unit, conversion_factor, is_unit_of, quantity_of
from pipeline.well import DATUM_WORDS, NORTH_WORDS, NorthReference, WellMetadata

DELIMITERS = (",", ";", "\t", "|")
_NUMBERISH = re.compile(r"^[+-]?([0-9]+([.,][0-9]*)?|[.,][0-9]+)([eE][+-]?[0-9]+)?$")
HEADER_SEARCH_LINES = 500

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
    "magneticdeclination": "declination",
    "magdeclination": "declination",
    "magdec": "declination",
    "convergence": "grid_convergence",
    "gridconv": "grid_convergence",
}
"""Title-block keys naming WellMetadata fields besides the field names themselves (the
site's declination as vendors title it, ``Magnetic Declination:``, ``Mag Dec:``, and
convergence, ``Convergence:``, as LAS MAGDEC and CONV)."""
NORTH_KEYS = ("northreference", "azimuthreference")
"""Title-block keys declaring the azimuths' north reference (``north_reference: grid``);
``well.north_reference`` is well metadata instead."""
UNIT_FIELDS = {
    "latitude": "angle",
    "longitude": "angle",
    "elevation": "length",
    "easting": "length",
    "northing": "length",
    "declination": "angle",
    "grid_convergence": "angle",
}
"""Well fields whose title-block value may carry a unit, after it or in brackets after the
key (``Elevation: 82 ft``, ``Easting (usft): 1640000``). Without one, an angle is in degrees
and a length in the file's length unit, the one unit of its length columns (``Elevation:
82`` above ``MD [ft]`` is 82 ft; none or several: an error), a map coordinate only where that
is metres (:data:`MAP_FIELDS`); a ``well.<field>`` key spells gyropipe's own field, in its
unit (m, deg), as the writer writes it."""
MAP_FIELDS = ("easting", "northing")
"""Map coordinates: in their CRS's unit, which a file's lengths in feet do not tell (US survey
or international feet, 2 ppm apart: 4 ft at an easting of 2,000,000 ft), so one without a
unit beside lengths in feet is refused."""
HEMISPHERES = {"latitude": "NS", "longitude": "EW", "declination": "EW", "grid_convergence": "EW"}
"""Well fields whose title value may end in a hemisphere letter (positive, negative), as
vendors write them: ``Latitude: 33.5 S``, ``Magnetic Declination: 2.5° W`` (−2.5°: east of
true north is positive); a value with both a sign and a letter is refused."""
ELEVATION_WORDS = ("elevation", "elev")
UNIT_HINTS = {"length": ("m", "ft"), "angle": ("deg", "rad"), "dogleg_severity": ("deg/30m",)}

_BRACKETS = re.compile(r"[\[(]([^\[\]()]*)[\])]")
_TITLE_KEY = re.compile(r"[A-Za-z][\w .\-/]*(?:[\[(][^\[\]()]*[\])])?")
_TITLE_SEPARATOR = re.compile(r"[:=]")
KEY_ROOM = HEADER_LINE_MAX - TEXT_MAX
"""Characters of a title line its key's separator lies within (a key is a name: tens)."""


@dataclass(frozen=True)
class Cell:
    """One header cell: its index, text, unit and the north references it names."""

    index: int
    text: str
    unit: str | None
    north: tuple[NorthReference, ...]


@dataclass(frozen=True)
class Header:
    """The header row: 0-based line index, delimiter, cells and the cells naming each
    canonical column; ``units_line``: the 0-based index of a units row or rule line under it
    (:func:`with_units_row`), None if the data follow the header."""

    index: int
    delimiter: str
    cells: list[Cell]
    found: dict[str, list[Cell]]
    units_line: int | None = None

    @property
    def last_line(self) -> int:
        """0-based index of the header's last line (the data begin after it)."""
        return self.index if self.units_line is None else self.units_line


def cells_of(line: str, delimiter: str) -> list[str]:
    """The cells of one line (quotes as in CSV)."""
    try:
        return next(stdcsv.reader([line], delimiter=delimiter), [])
    except stdcsv.Error:  # e.g. a field over the csv module's size limit: not a header
        return [line]


def _words(text: str) -> list[str]:
    return [w for w in re.split(r"[^0-9a-z]+", text.casefold()) if w]


def _parse_cell(index: int, text: str, aliases: dict[str, str]) -> tuple[Cell, str | None]:
    """A header cell and the canonical column its name recognises (None when none)."""

    def name_of(words: list[str]) -> str | None:
        key = normalise("".join(words))
        return aliases.get(key) or canonical_name(key)

    text = text.strip()
    units: list[str] = []
    north: list[NorthReference] = []
    for inner in _BRACKETS.findall(text):
        ref = NORTH_WORDS.get("".join(w for w in _words(inner) if w != "north"))
        if ref:
            north.append(ref)
        elif inner.strip():
            units.append(inner.strip())
    words = _words(_BRACKETS.sub(" ", text))
    name = name_of(words)
    if name is None:
        refs = [NORTH_WORDS[w] for w in words if w in NORTH_WORDS]
        rest = [w for w in words if w not in NORTH_WORDS and w != "north"]
        if refs and name_of(rest) == "azi":
            name, north = "azi", north + refs
    return Cell(index, text, units[-1] if units else None, tuple(north)), name


def _spaced(text: str) -> str:
    return " ".join(text.split()).casefold()


def _recognise(cells: list[str], opts: CsvOptions) -> tuple[list[Cell], dict[str, list[Cell]]]:
    aliases = {normalise(text): name for text, name in opts.aliases.items()}
    parsed = [_parse_cell(i, text, aliases) for i, text in enumerate(cells)]
    found: dict[str, list[Cell]] = {}
    explicit = {name: _spaced(text) for name, text in opts.columns.items()}
    claimed: set[int] = set()
    for name, wanted in explicit.items():
        for cell, _ in parsed:
            bare = _BRACKETS.sub(" ", cell.text)
            if wanted in (_spaced(cell.text), _spaced(bare)):
                found.setdefault(name, []).append(cell)
                claimed.add(cell.index)
    for cell, guess in parsed:
        if guess is not None and guess not in explicit and cell.index not in claimed:
            found.setdefault(guess, []).append(cell)
    return [cell for cell, _ in parsed], found


def find_header(
    path: Path, lines: list[str], opts: CsvOptions, required: tuple[str, ...]
) -> Header:
    """The header row: line ``header_line`` if set, else the first non-comment line naming
    every ``required`` column; the delimiter giving most cells wins a tie."""
    delimiters = (
        [opts.delimiter]
        if opts.delimiter
        else [d for d in DELIMITERS if not (opts.decimal == "," and d == ",")]
    )
    if opts.header_line is not None:
        searched = range(opts.header_line - 1, min(opts.header_line, len(lines)))
    else:
        searched = range(min(HEADER_SEARCH_LINES, len(lines)))
    best: Header | None = None
    for index in searched:
        line = lines[index]
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        candidates = []
        for delimiter in delimiters:
            raw = cells_of(line, delimiter)
            if len(raw) > MAX_COLUMNS:
                raise InputFileError(
                    path,
                    f"{len(raw):,} columns separated by {delimiter!r}, more than "
                    f"{MAX_COLUMNS:,}: refused",
                    line=index + 1,
                )
            cells, found = _recognise(raw, opts)
            candidates.append(Header(index, delimiter, cells, found))
        for header in sorted(candidates, key=lambda h: -len(h.cells)):
            if all(n in header.found for n in required):
                return header
            if _score(header, required) > max(_score(best, required), 0):
                best = header
    accepted = (
        "; ".join(f"{name}: {', '.join(CURVES[name].aliases)}" for name in required)
        + (" (azimuth names may add True/Grid/Magnetic)" if "azi" in required else "")
        + "; or set the option columns or aliases"
    )
    if best is None:
        where = (
            f"on line {opts.header_line} (option header_line)"
            if opts.header_line is not None
            else f"in the first {HEADER_SEARCH_LINES} lines"
        )
        raise InputFileError(
            path,
            f"no header row with {', '.join(required)} columns {where}; accepted names: "
            + accepted,
            line=opts.header_line or 0,
        )
    missing = [n for n in required if n not in best.found]
    raise InputFileError(
        path,
        f"missing column(s) {', '.join(missing)} in the header row; found "
        f"{', '.join(repr(c.text) for c in best.cells)}; accepted names: {accepted}",
        line=best.index + 1,
    )


_RULE = re.compile(r"^[-=_~*]+$")


def with_units_row(path: Path, lines: list[str], header: Header) -> Header:
    """``header`` with the line under it read as its units row (``MD,Inc,Azi`` over
    ``m,deg,deg`` or ``(m),(deg),(deg)``, as survey programs export) or passed over as a
    rule (``-----,-----``); unchanged where that line holds a number or no known unit. A
    column's unit there that its header cell contradicts, or that is no unit of a
    recognised column's quantity, is refused at that line."""
    at = header.index + 1
    raw = [c.strip() for c in cells_of(lines[at], header.delimiter)] if at < len(lines) else []
    filled = [c for c in raw if c]
    if not filled or any(_NUMBERISH.match(c) for c in filled):
        return header
    if all(_RULE.match(c) for c in filled):
        return replace(header, units_line=at)
    stated = [_BRACKETS.sub(r"\1", c).strip() for c in raw]
    if not any(quantity_of(u) for u in stated if u):
        return header
    names = {cell.index: name for name, cells in header.found.items() for cell in cells}
    cells = [
        _with_unit(path, cell, stated[cell.index] if cell.index < len(stated) else "", names, at)
        for cell in header.cells
    ]
    found = {name: [cells[c.index] for c in found] for name, found in header.found.items()}
    return Header(header.index, header.delimiter, cells, found, units_line=at)


def _with_unit(path: Path, cell: Cell, unit: str, names: dict[int, str], at: int) -> Cell:
    quantity = CURVES[names[cell.index]].quantity if cell.index in names else None
    if not unit or _RULE.match(unit) or quantity is None:
        return cell
    try:
        given = conversion_factor(unit, quantity)
    except UnitError as exc:
        raise InputFileError(path, f"units row: {exc}", line=at + 1, column=cell.text) from None
    if cell.unit is not None and is_unit_of(cell.unit, quantity):
        if conversion_factor(cell.unit, quantity) != given:
            raise InputFileError(
                path,
                f"the header says {cell.unit!r}, the units row under it {unit!r}",
                line=at + 1,
                column=cell.text,
            )
        return cell
    return replace(cell, unit=unit)


def _score(header: Header | None, required: tuple[str, ...]) -> int:
    return -1 if header is None else sum(1 for n in required if n in header.found)


def choose(
    path: Path, header: Header, name: str, declared: list[tuple[str, NorthReference]]
) -> Cell:
    """The one cell of column ``name``; among azimuths, the one of the declared reference."""
    cells = header.found[name]
    if len(cells) > 1 and name == "azi":
        matching = [c for c in cells if set(c.north) & {ref for _, ref in declared}]
        if len(matching) == 1:
            return matching[0]
    quantity = CURVES[name].quantity
    if len(cells) > 1 and quantity is not None:  # the one whose unit fits: dogleg[deg] no DLS
        fitting = [c for c in cells if c.unit is not None and is_unit_of(c.unit, quantity)]
        if len(fitting) == 1:
            return fitting[0]
    if len(cells) > 1:
        raise InputFileError(
            path,
            f"several columns look like {name}: {', '.join(repr(c.text) for c in cells)}; "
            f"choose one with the option columns (e.g. columns: {{{name}: {cells[0].text!r}}})"
            + (" or north_reference" if name == "azi" else ""),
            line=header.index + 1,
        )
    return cells[0]


def north_reference(
    path: Path, header: Header, azi: Cell, declared: list[tuple[str, NorthReference]]
) -> NorthReference | None:
    """The one north reference the azimuth cell and the declarations agree on, if any."""
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


def factor(
    path: Path, header: Header, cell: Cell, name: str, opts: CsvOptions, profiled: frozenset[str]
) -> float:
    """Factor from the unit of column ``name`` (declared in the options, else the header's)
    to its canonical unit; ``profiled``: the columns whose declared unit is a profile's, which
    a header stating another contradicts."""
    quantity = CURVES[name].quantity
    assert quantity is not None, name
    shorthand = next((opt for opt, names in SHORTHANDS.items() if name in names), None)
    example = UNIT_HINTS.get(quantity, (canonical_unit(quantity),))[-1]
    option = f"units: {{{name}: {example}}}" + (f" or {shorthand}: {example}" if shorthand else "")
    unit = opts.unit_of(name) or cell.unit
    if name in profiled and cell.unit is not None and unit is not None:
        _agreeing(path, header, cell, unit, quantity)
    if unit is None:
        one, *other = UNIT_HINTS.get(quantity, (canonical_unit(quantity),))
        spelled = f"'{cell.text} [{one}]'" + (f" or '{cell.text} ({other[0]})'" if other else "")
        raise InputFileError(
            path,
            f"no unit for this column: write it in the header (e.g. {spelled}) or set the "
            f"reader option {option}",
            line=header.index + 1,
            column=cell.text,
        )
    try:
        return conversion_factor(unit, quantity)
    except UnitError as exc:
        raise InputFileError(
            path,
            f"{exc} (or set the reader option {option})",
            line=header.index + 1,
            column=cell.text,
        ) from None


def _agreeing(path: Path, header: Header, cell: Cell, unit: str, quantity: str) -> None:
    """Refuse a header unit that differs from the profile's ``unit`` for its column (text in
    brackets that is no unit of it, ``Depth (MD)``, leaves the profile's)."""
    assert cell.unit is not None
    try:
        stated = conversion_factor(cell.unit, quantity)
    except UnitError:
        return
    if stated != conversion_factor(unit, quantity):
        raise InputFileError(
            path,
            f"the header says {cell.unit!r}, the profile's unit for this column is {unit!r}: "
            "a profile gives the units its files' headers lack, not one they state (set the "
            "unit as a reader option to override the header)",
            line=header.index + 1,
            column=cell.text,
        )


# ------------------------------------------------------------------------ title block


def length_units(header: Header, opts: CsvOptions, columns: tuple[str, ...]) -> dict[str, str]:
    """The units of the file's length columns among ``columns``: the options', else the
    header's (a column cell without one, or of unknown unit, is left out)."""
    units: dict[str, str] = {}
    for name in columns:
        curve = CURVES.get(name)
        for cell in header.found.get(name, []) if curve and curve.quantity == "length" else []:
            unit = opts.unit_of(name) or cell.unit
            if unit is not None and is_unit_of(unit, "length"):
                units[cell.text] = unit
    return units


def check_title(path: Path, lines: list[str], delimiter: str) -> None:
    """Refuse, at its line, a title line longer than :func:`title_problem` allows."""
    for number, line in enumerate(lines, start=1):
        if (reason := title_problem(line, delimiter)) is not None:
            raise InputFileError(path, reason, line=number)


def title_problem(line: str, delimiter: str) -> str | None:
    """Why a title-block line is refused for its length, else None: a ``key: value`` line's
    value over :data:`~pipeline.io.limits.TEXT_MAX` characters (naming the key), any line
    over :data:`~pipeline.io.limits.HEADER_LINE_MAX` (a megabyte well name was read and
    copied into every table, header and file written from it)."""
    if len(line) <= TEXT_MAX:
        return None
    entry = _key_value(line, delimiter)
    if entry is not None and (reason := too_long(entry[1], f"the value of {entry[0]!r}")):
        return reason
    return too_long(line, "the title line", HEADER_LINE_MAX)


def read_title(
    path: Path, lines: list[str], delimiter: str, lengths: dict[str, str]
) -> tuple[WellMetadata, list[tuple[str, NorthReference]]]:
    """Well metadata and north-reference declarations of the lines above the header;
    ``lengths``: the units of the file's length columns, by header cell
    (:func:`length_units`), the unit of a length given without one. A datum's elevation
    (``KB Elevation``, ``RKB``, ``Ground Level``) is the elevation where no ``Elevation`` is
    given: the depth reference's, else the one given (implying the depth reference)."""
    fields = {"".join(_words(name)): name for name in WellMetadata.model_fields}
    keys = {k: v for k, v in fields.items() if k != "northreference"} | WELL_ALIASES
    values: dict[str, tuple[Any, int]] = {}
    datums: dict[str, tuple[Any, int]] = {}
    north: list[tuple[str, NorthReference]] = []
    for number, line in enumerate(lines, start=1):
        entry = _key_value(line, delimiter)
        if entry is None:
            continue
        key, value = entry
        prefixed = key[:5].casefold() == "well."
        words = _words(_BRACKETS.sub(" ", key[5:] if prefixed else key))
        name = "".join(words)
        datum = None if prefixed else _datum(words)
        field = "elevation" if datum else fields.get(name) if prefixed else keys.get(name)
        if not prefixed and name in NORTH_KEYS:
            north.append((f"line {number}", _north_word(path, value, number)))
        elif field is not None:
            unit = _key_unit(path, key, field, number)
            if unit == "":  # brackets holding no unit of the field: the line is not read
                continue
            parsed = _well_value(path, field, value, number, None if prefixed else lengths, unit)
            if parsed is None:  # a null marker: no value
                continue
            found = datums if datum else values
            label = datum or field
            if label in found and found[label][0] != parsed:
                raise InputFileError(
                    path,
                    f"{label if datum is None else label + ' elevation'} is given twice with "
                    f"different values (also on line {found[label][1]})",
                    line=number,
                )
            found[label] = (parsed, number)
    if "elevation" not in values and datums:
        values |= _datum_elevation(path, datums, values.get("depth_reference"))
    try:
        return WellMetadata(**{f: v for f, (v, _) in values.items()}), north
    except ValidationError as exc:  # each field was read alone: the survey dates' order
        (error,) = exc.errors()
        last = values["survey_date_last"][1]
        raise InputFileError(path, str(error["ctx"]["error"]), line=last) from None


STATEMENT_KEYS = {"confidence": "confidence", "errormodel": "error_model", "tieon": "tie_on"}
"""Title keys of what a file states of its uncertainty columns (gyropipe's ``# confidence=``,
``# error_model=``, ``# tie_on=``), by their words."""


def title_statements(path: Path, lines: list[str], delimiter: str) -> dict[str, tuple[str, int]]:
    """The :data:`STATEMENT_KEYS` lines above the header: each value and line number; one
    given again with another value is an :class:`InputFileError` at its second line (which
    of two error models, or tie-ons, would the columns have?)."""
    found: dict[str, tuple[str, int]] = {}
    for number, line in enumerate(lines, start=1):
        entry = _key_value(line, delimiter)
        if entry is None or not (name := STATEMENT_KEYS.get("".join(_words(entry[0])))):
            continue
        first = found.setdefault(name, (entry[1], number))
        if first[0] != entry[1]:
            raise InputFileError(
                path,
                f"{name} is given twice with different values (also on line {first[1]}: "
                f"{first[0]!r}); expected one statement of the uncertainty columns' {name}",
                line=number,
            )
    return found


def _datum(words: list[str]) -> str | None:
    """The datum whose elevation a title key names (``KB Elevation``, ``RKB``), if any."""
    return DATUM_WORDS.get("".join(w for w in words if w not in ELEVATION_WORDS))


def _key_unit(path: Path, key: str, field: str, line: int) -> str | None:
    """The unit in brackets after a title key (``Elevation (ft)``): None without brackets;
    ``""``, with a warning, for brackets holding no unit of the field (``Latitude (WGS84)``)."""
    stated = _BRACKETS.search(key)
    if stated is None:
        return None
    unit, quantity = stated[1].strip(), UNIT_FIELDS.get(field)
    if quantity is not None and is_unit_of(unit, quantity):
        return unit
    warn_input(path, f"{key!r} not read: {unit!r} is no unit of {field}", line)
    return ""


def _datum_elevation(
    path: Path, datums: dict[str, tuple[Any, int]], reference: tuple[Any, int] | None
) -> dict[str, tuple[Any, int]]:
    """The elevation among the datums' (and the depth reference the one given implies): the
    depth reference's, else the only one; none, with a warning, when neither says which."""
    if reference is None and len(datums) == 1:
        ((datum, entry),) = datums.items()
        return {"elevation": entry, "depth_reference": (datum, entry[1])}
    wanted = None if reference is None else DATUM_WORDS.get("".join(_words(reference[0])))
    if wanted in datums:
        return {"elevation": datums[wanted]}
    given = ", ".join(f"{d} (line {line})" for d, (_, line) in datums.items())
    warn_input(
        path,
        f"elevation left out: the elevations of {given} are not of the depth reference "
        + (
            "(none is given: add e.g. 'Depth reference: RKB')"
            if reference is None
            else f"{reference[0]!r} (line {reference[1]})"
        ),
        max(line for _, line in datums.values()),
    )
    return {}


def _key_value(line: str, delimiter: str) -> tuple[str, str] | None:
    """``(key, value)`` of a ``key: value`` / ``# key=value`` line with a non-empty value (its
    separator within the first :data:`KEY_ROOM` characters)."""
    comment = line.lstrip().startswith("#")
    junk = " \t" if comment else ' \t"' + delimiter
    text = line.strip().lstrip("#").strip(junk)
    separator = _TITLE_SEPARATOR.search(text, 0, KEY_ROOM)
    if separator is None:
        return None
    key, value = text[: separator.start()].strip(), text[separator.end() :].strip(junk)
    return (key, value) if value and _TITLE_KEY.fullmatch(key) else None


def _north_word(path: Path, value: str, line: int) -> NorthReference:
    words = [w for w in _words(value) if w != "north"]
    if len(words) == 1 and words[0] in NORTH_WORDS:
        return NORTH_WORDS[words[0]]
    raise InputFileError(
        path, f"north reference {value!r} is not one of true, grid, magnetic", line=line
    )


def _well_value(
    path: Path,
    field: str,
    value: str,
    line: int,
    lengths: dict[str, str] | None,
    unit: str | None = None,
) -> Any:
    """The validated value of one well field; a number may carry a unit for UNIT_FIELDS,
    after it or ``unit`` (the key's, in brackets), which must agree (without one:
    :data:`UNIT_FIELDS`; ``lengths`` None: a ``well.<field>`` key, in m), None for a null
    marker (:mod:`pipeline.io.nulls`, in its unit); the survey dates are read as a LAS DATE
    is (:func:`pipeline.io.dates.header_date`)."""
    parsed: Any = value
    quantity = UNIT_FIELDS.get(field)
    try:
        plain, sign = _hemisphere(field, value)
        number = re.match(r"^([+-]?[0-9.]+(?:[eE][+-]?[0-9]+)?)\s*(\S.*)?$", plain)
        if quantity and number and is_null_marker(float(number[1]), angle=quantity == "angle"):
            return None
        if quantity and number:
            scale = _scale(field, plain, quantity, [u for u in (unit, number[2]) if u], lengths)
            parsed = sign * float(number[1]) * scale
        elif field in ("survey_date", "survey_date_last"):
            parsed = header_date(value)
        return getattr(WellMetadata.model_validate({field: parsed}), field)
    except (ValueError, UnitError) as exc:  # pydantic's ValidationError is a ValueError
        reason = exc.errors()[0]["msg"] if isinstance(exc, ValidationError) else str(exc)
        raise InputFileError(path, f"invalid {field} {value!r}: {reason}", line=line) from None


def _hemisphere(field: str, value: str) -> tuple[str, float]:
    """``value`` less a hemisphere letter it ends in (:data:`HEMISPHERES`), and the sign
    the letter gives (1 without one)."""
    letters = HEMISPHERES.get(field)
    found = re.fullmatch(rf"(.*[0-9.°\s])([{letters}])", value.strip(), re.I) if letters else None
    if letters is None or found is None:
        return value, 1.0
    if found[1].lstrip().startswith(("-", "+")):
        raise ValueError("both a sign and a hemisphere letter")
    return found[1].strip(), -1.0 if found[2].upper() == letters[1] else 1.0


def _scale(
    field: str, value: str, quantity: str, stated: list[str], lengths: dict[str, str] | None
) -> float:
    """Factor to the field's unit from the ``stated`` units of its value (the key's and the
    value's, which must agree), else from the file's (:func:`_file_length`)."""
    factors = {conversion_factor(unit, quantity) for unit in stated}
    if len(factors) > 1:
        raise UnitError(f"the key says {stated[0]!r}, the value {stated[1]!r}")
    if factors:
        return factors.pop()
    unit = _file_length(field, value, lengths) if quantity == "length" else None
    return conversion_factor(unit, quantity) if unit else 1.0


def _file_length(field: str, value: str, lengths: dict[str, str] | None) -> str | None:
    """The unit of a length title value given without one: the file's one length unit,
    for a map coordinate only metres (:data:`MAP_FIELDS`); None for a ``well.<field>`` key
    (m). Raises :class:`UnitError` when it has none or several, or feet for a map
    coordinate."""
    if lengths is None:
        return None
    factors = {conversion_factor(unit, "length") for unit in lengths.values()}
    unit = next(iter(lengths.values()), None)
    if len(factors) == 1 and (factors == {1.0} or field not in MAP_FIELDS):
        return unit
    if len(factors) == 1:
        raise UnitError(
            f"no unit, and a map coordinate is in its CRS's unit, which lengths in {unit} do "
            f"not tell (US survey or international feet): write it (e.g. '{value} usft' or "
            f"'{value} ft')"
        )
    found = ", ".join(f"{text!r} in {unit}" for text, unit in lengths.items())
    raise UnitError(
        f"no unit, and the file's length columns ({found or 'none with a unit'}) do not "
        f"say one: write it (e.g. '{value} m' or '{value} ft')"
    )


def is_footer(cells: list[str], width: int, required: list[int]) -> bool:
    """A line after the data that is text: non-numeric first cell, and fewer cells than the
    header or no numeric cell in a required column."""
    first = next((c.strip() for c in cells if c.strip()), "")
    if _NUMBERISH.match(first):
        return False
    numeric = any(i < len(cells) and _NUMBERISH.match(cells[i].strip()) for i in required)
    return len(cells) < width or not numeric

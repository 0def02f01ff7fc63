"""Built-in CSV plugin: a reader of survey stations and raw sensor samples from delimited
text files, and a CSV writer of any table.

Kinds read (``read(path, kind, options)``):

* ``stations`` → :class:`~pipeline.tables.Stations`: md (m), inc and azi (deg), optional
  survey id, plus any of tvd, north (+N/−S), east (+E/−W) in m and dls in deg/30m found in
  the file (a wellpath report; empty cells of these are null), a trajectory's uncertainty
  columns by gyropipe's names (``cov_nn`` m², ``ellipse_major`` m…, stating the title's
  ``confidence``, ``error_model`` and ``tie_on``: :mod:`pipeline.io.uncertainty_columns`), what each
  row is as the file says it (``station_type``: a ``Station Type``, ``Survey Type``,
  ``Type`` or ``Comment`` column), and ``source_line``. A row whose ``station_type`` names
  a projection or an interpolation (:data:`NOT_MEASURED`: ``Projection to TD``, ``PTB``,
  ``Interpolated``…) is no survey station: left out with a warning at its line naming its
  md (the option ``stations: all`` reads it; every row left out: refused at the column); a
  tie-in row (``Tie-In``, ``Tie On``) is the survey's first station and read. A file
  without such a column says nothing of its rows: each is read;
* ``samples`` → :class:`~pipeline.tables.RawSamples`: time (s) and the gyro (deg/h),
  accelerometer (m/s²) and optional magnetometer (nT) triads, optional md (m),
  frame_angle (deg), station and position (integers), and ``source_line``; empty cells of
  the columns the contract lets be null are null (the writer writes a null so); converted
  to the canonical conventions with :func:`~pipeline.io.conventions.to_canonical` and the
  option ``conventions``.

``source_line`` is each row's 1-based file line, so later contract errors can cite it.
Null markers (:mod:`pipeline.io.nulls`: ``-999.25``…, in the file's unit) are empty cells:
null where a cell may be empty (an azimuth then is undefined, allowed only at vertical), an
error at their line elsewhere. Values are not range-checked here (the engine checks the
contract and the angles' plausibility, :mod:`pipeline.plausibility`).

File layout, in order:

* **title block** (optional): lines before the header — free text, ``key: value`` or
  ``key=value`` lines (optionally behind ``#``); keys naming well metadata fields (or as
  :data:`~pipeline.io.csv.header.WELL_ALIASES`: ``Magnetic Declination``, ``Convergence``)
  fill the returned :class:`WellMetadata`, ``north_reference`` declares the azimuth reference; a
  number may carry its unit, after it or in brackets after the key (``Elevation: 82 ft``,
  ``Easting (usft): 2300000``; brackets holding no unit leave the line unread, warned), else
  an angle is in degrees and a length in the file's length unit, the one unit of its length
  columns (``Elevation: 82`` above ``MD [ft]``: 82 ft; none or several: an error), a map
  coordinate (``Easting``, ``Northing``, in its CRS's unit) only where that is m (beside
  feet: an error, US survey or international), a ``well.<field>`` key in the field's (m);
  a datum's elevation (``KB Elevation``, ``RKB``, ``Ground Level``) is the elevation where
  no ``Elevation`` is given: the depth reference's, else the only one (implying the depth
  reference; several and none named: left out, warned);
  a latitude, longitude, declination or convergence may end in its hemisphere letter
  (``33.5 S``, ``2.5° W``: negative);
  a date as a LAS DATE (:mod:`pipeline.io.dates`: ISO, ``21-Nov-2026``, ``21/11/2026``);
  a null marker (``Elevation: -999.25``) is no value; a value longer than
  :data:`~pipeline.io.limits.TEXT_MAX` characters (or a line than
  :data:`~pipeline.io.limits.HEADER_LINE_MAX`) is refused at its line;
* **header row**: line ``header_line`` if that option is set, else the first line (within
  :data:`~pipeline.io.csv.header.HEADER_SEARCH_LINES`, never a ``#`` line) whose cells,
  split by one of ``, ; tab |``, name every required column of the kind. Names are looked up
  in the ``aliases`` option, then in the one mnemonics table
  (:mod:`pipeline.io.mnemonics`), compared case- and punctuation-insensitively; the option
  ``columns`` names a column's header text outright. Units sit in brackets: ``MD [ft]``,
  ``Rate X ( deg/h )``; an azimuth name may add its north reference: ``Azimuth True``,
  ``AZI (GN)``, ``Grid Azimuth``. Each column may use its own unit (MD in ft, TVD in m);
* **data rows**: every later line; blank lines and ``#`` lines are skipped;
* **footer** (optional): a trailing run of lines after the last data row, each with a
  non-numeric first cell and either fewer cells than the header or no numeric cell in a
  required column (``End of survey``, ``Total,,,1234``). Any other bad cell is an error
  naming its file line — a truncated or corrupt last row is never dropped as a footer; a
  footer left out is told in a warning at its first line.

Delimiters are detected (runs of spaces are not supported: names like ``Measured Depth``
make them ambiguous); line ends may be LF, CRLF or CR; text is UTF-8 with or without a BOM.
Decimal commas are read with ``decimal=","`` or when the delimiter is not ``,`` and no
required column's value contains a dot. Units come from the header or the options
``units``/``md_unit``/``angle_unit`` (which win), never assumed: a read column with no or
an unknown unit is an :class:`~pipeline.errors.InputFileError` naming it. The azimuth north
reference comes from the header, a ``north_reference`` title line or the option, which must
agree; the one the file names (header or title line, not the option) is also the returned
well metadata's ``north_reference``, as LAS's NREF is (a ``well.north_reference`` line
saying another is overruled, warned: the azimuths' own is what they are). Options may
come from a vendor profile (``profile: vendor.yaml``, see :mod:`pipeline.io.csv.options`),
whose units fill in the ones headers lack: a header stating another is refused.

Every problem of the file (or profile) is an InputFileError naming the file, the line and,
for a cell, its column: wrong cell counts, non-numeric or empty cells, unknown units,
invalid UTF-8, NUL bytes, a quote left open.

Writing puts ``# gyropipe <well>``, ``# north_reference=<ref>``, ``# well.<field>=<value>``
and, for a trajectory, ``# survey_method=…`` and ``# vs_azimuth=… deg`` lines above a
``name[unit]`` header (a title line the reader would refuse for its length is refused,
:func:`~pipeline.io.csv.header.title_problem`), floats at their unit's decimals
(:mod:`pipeline.io.precision`); the reader reads stations and samples back to within half a
step of those decimals (of several columns that look like one, the one whose unit fits:
``dogleg[deg]`` is no DLS).
"""

from __future__ import annotations

import csv as stdcsv
import io
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv

from pipeline.contracts import NORTH_KEY, SOURCE_LINE, UNIT_KEY, TableContract
from pipeline.errors import InputFileError, WrongKindError, warn_rows
from pipeline.hookspecs import hookimpl
from pipeline.io.conventions import to_canonical
from pipeline.io.csv.header import (
    HEADER_SEARCH_LINES,
    Cell,
    Header,
    check_title,
    choose,
    factor,
    find_header,
    length_units,
    north_reference,
    read_title,
    title_problem,
    title_statements,
    with_units_row,
)
from pipeline.io.csv.options import CsvOptions, profile_units
from pipeline.io.csv.rows import (
    Rows,
    data_rows,
    load,
    newlines,
    parse_blocks,
    split_head,
)
from pipeline.io.mnemonics import CURVES
from pipeline.io.north import stated_north
from pipeline.io.nulls import null_markers, refuse_null_markers, value_range
from pipeline.io.numbers import scaled
from pipeline.io.precision import for_export
from pipeline.io.uncertainty_columns import UNCERTAINTY_COLUMNS, Stated, readable, stating
from pipeline.registry import Claim, ReaderDef, WriterDef
from pipeline.streams import TableStream
from pipeline.survey.calculation import calculation_of
from pipeline.tables import PositionReadings, RawSamples, Stations
from pipeline.uncertainty.stated import file_statements
from pipeline.uncertainty.tieon import tie_on_of
from pipeline.units import canonical_unit
from pipeline.well import NorthReference, WellMetadata

__all__ = ["LAYOUTS", "CsvOptions", "Layout", "read", "sniff", "stream", "write_csv"]

SNIFF_BYTES = 64 * 1024
SNIFF_SUFFIXES = (".csv", ".txt", ".tsv")


@dataclass(frozen=True)
class Layout:
    """What one kind reads: the columns of its contract, plus ``extras`` kept with the
    canonical unit of their mnemonic; empty cells of the ``blanks`` columns are null (of
    other number columns, errors)."""

    contract: type[TableContract]
    extras: tuple[str, ...] = ()
    blanks: frozenset[str] = frozenset()

    @property
    def columns(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.contract.compiled().columns) + self.extras

    @property
    def required(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.contract.compiled().columns if c.required)

    def types(self) -> dict[str, pa.DataType]:
        """Arrow type of each column."""
        return {c.name: c.type for c in self.contract.compiled().columns} | dict.fromkeys(
            self.extras, pa.float64()
        )

    def table(self, data: dict[str, Any], north: str | None) -> pa.Table:
        """The contract's table of ``data`` (canonical units), extras with unit metadata."""
        table = self.contract.compiled().make_table(data, north_reference=north)
        fields = [
            f.with_metadata({UNIT_KEY: _unit_of(f.name).encode()}) if f.name in self.extras else f
            for f in table.schema
        ]
        return pa.Table.from_arrays(table.columns, schema=pa.schema(fields))


def _unit_of(name: str) -> str:
    quantity = CURVES[name].quantity
    assert quantity is not None, name
    return canonical_unit(quantity)


STATION_EXTRAS = ("tvd", "north", "east", "dls", *UNCERTAINTY_COLUMNS)
NOT_MEASURED = r"\b(proj\w*|ptb|ptd|interp\w*|extrap\w*)\b"
"""Words of a ``station_type`` cell (compared ignoring case) naming a projection (``Projection
to TD``, ``Proj. to Bit``, ``PTB``, ``PTD``) or an inter- or extrapolation: not a survey
station."""
LAYOUTS = {
    # an empty azimuth is undefined (NaN), allowed by the contract only at vertical
    "stations": Layout(Stations, extras=STATION_EXTRAS, blanks=frozenset({*STATION_EXTRAS, "azi"})),
    "samples": Layout(
        RawSamples, blanks=frozenset(c.name for c in RawSamples.compiled().columns if c.nullable)
    ),
    "readings": Layout(
        PositionReadings,
        blanks=frozenset(c.name for c in PositionReadings.compiled().columns if not c.required),
    ),
}


# ---------------------------------------------------------------------------- reader


def read(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read ``path`` as ``kind`` (``stations`` or ``samples``) in canonical units and
    conventions, with a ``source_line`` column; also the title block's well metadata."""
    rows, well = _open(path, kind, options)
    return pa.concat_tables(list(rows.tables()), promote_options="none"), well


def stream(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
    """:func:`read` as a stream of record batches: a block of about
    :data:`~pipeline.io.csv.rows.ROWS_BLOCK` bytes of data lines at a time, parsed and
    checked as it passes (each pass reads the file again)."""
    rows, well = _open(path, kind, options)
    return TableStream.of_batches(rows.schema, rows.batches), well


@dataclass(frozen=True)
class _Rows:
    """A file's data rows and how to read them: their tables a block at a time."""

    path: Path
    layout: Layout
    header: Header
    chosen: dict[str, Cell]
    factors: dict[str, float]
    rows: Rows
    decimal: str | None
    """the decimal mark; None: found (:func:`~pipeline.io.csv.rows.parse_blocks`)"""
    north: str | None
    opts: CsvOptions
    stated: Stated
    """what the title block states of the uncertainty columns"""

    @property
    def schema(self) -> pa.Schema:
        """The tables' schema (that of a table without rows)."""
        types = self._types()
        empty = {name: pa.array([], types[name]) for name in self.chosen}
        return self._table(empty, np.empty(0, np.int64)).schema

    def tables(self) -> Iterator[pa.Table]:
        """The table of each block of rows; rows all left out (:meth:`_measured`) are no
        survey: refused at the station_type column once every block is read."""
        blocks = parse_blocks(
            self.path,
            self.rows,
            self.header,
            self.chosen,
            self._types(),
            self._blanks(),
            self.decimal,
        )
        read = kept = 0
        for values, rows in blocks:
            lines = rows.source_lines(len(values[self.layout.required[0]]))
            table = self._table(self._without_markers(values, lines), lines)
            measured = self._measured(table)
            read, kept = read + table.num_rows, kept + measured.num_rows
            yield measured
        if read and not kept:
            column = self.chosen["station_type"].text
            raise InputFileError(
                self.path,
                f"no survey station: each of the {read} rows is left out, its {column!r} "
                "naming a projection or an interpolation; the reader option stations: all "
                "reads them",
                self.header.index + 1,
                column,
            )

    def batches(self) -> Iterator[pa.RecordBatch]:
        for table in self.tables():
            yield from table.to_batches()

    def _without_markers(self, values: dict[str, Any], lines: Any) -> dict[str, Any]:
        """Null markers (-999.25…, :mod:`pipeline.io.nulls`) as nulls where a cell may be
        empty (azi, tvd…); elsewhere (md, inc, time…) an error at the cell's line."""
        for name, array in values.items():
            if not pa.types.is_floating(array.type):
                continue
            quantity = CURVES[name].quantity if name in CURVES else None
            found = null_markers(array, angle=quantity in ("angle", "dogleg_severity"))
            if found is None:
                continue
            if name not in self._blanks():
                first = int(np.flatnonzero(found)[0])
                raise InputFileError(
                    self.path,
                    f"{array[first].as_py()!r} is a null marker: expected a value of {name}"
                    + (" (or the option null_stations: drop)" if name == "inc" else ""),
                    line=int(lines[first]),
                    column=self.chosen[name].text,
                )
            values[name] = pc.if_else(pa.array(found), pa.scalar(None, array.type), array)
        return values

    def _measured(self, table: pa.Table) -> pa.Table:
        """``table`` without the stations its ``station_type`` column names a projection or
        an interpolation (:data:`NOT_MEASURED`; option ``stations: survey``), each left out
        with a warning at its line naming its md."""
        if "station_type" not in table.column_names or self.opts.stations == "all":
            return table
        kinds = table.column("station_type")
        named = pc.fill_null(pc.match_substring_regex(kinds, NOT_MEASURED, ignore_case=True), False)
        if not pc.any(named).as_py():
            return table
        left = table.filter(named)
        column = self.chosen["station_type"].text
        rows = [
            (
                f"station at md {md!r} m left out: {kind!r} in column {column!r} names a "
                "projection or an interpolation, not a measurement; the reader option "
                "stations: all reads it",
                line,
            )
            for md, kind, line in zip(
                *(left.column(c).to_pylist() for c in ("md", "station_type", SOURCE_LINE)),
                strict=True,
            )
        ]
        warn_rows(self.path, rows, "stations left out")
        return table.filter(pc.invert(named))

    def _blanks(self) -> frozenset[str]:
        """Columns whose cells may be empty: the layout's, and a station's inclination under
        the option ``null_stations: drop`` (the engine leaves such stations out)."""
        drop = self.layout.contract is Stations and self.opts.null_stations == "drop"
        return self.layout.blanks | {"inc"} if drop else self.layout.blanks

    def _types(self) -> dict[str, pa.DataType]:
        return {n: t for n, t in self.layout.types().items() if n in self.chosen}

    def _table(self, values: dict[str, Any], lines: Any) -> pa.Table:
        """The contract's table of parsed columns, in canonical units and conventions."""
        data = {name: _scaled(values[name], self.factors.get(name, 1.0)) for name in self.chosen}
        data[SOURCE_LINE] = pa.array(lines, pa.int64())
        table = stating(self.layout.table(data, self.north), self.stated)
        try:
            return to_canonical(table, self.opts.conventions)
        except ValueError as exc:
            line = self.header.index + 1
            raise InputFileError(self.path, f"option conventions: {exc}", line=line) from None


def _scaled(values: Any, factor: float) -> Any:
    """``values`` × ``factor``. Floats just parsed (in buffers of their own: a header cell
    is one column, each chunk its own buffer) are scaled in place, which spares a copy of
    the column; any other values into a new array."""
    if factor == 1.0:
        return values
    chunks = values.chunks if isinstance(values, pa.ChunkedArray) else [values]
    buffers = [chunk.buffers()[1] for chunk in chunks]
    own = all(b is not None and b.is_mutable for b in buffers)
    if not (
        pa.types.is_float64(values.type)
        and own
        and len({b.address for b in buffers}) == len(buffers)
    ):
        return pc.multiply(values, factor)
    for chunk, buffer in zip(chunks, buffers, strict=True):
        data = np.frombuffer(buffer, np.float64, len(chunk), chunk.offset * 8)
        scaled(data, factor, out=data)
    return values


def _open(path: Path, kind: str, options: CsvOptions | None) -> tuple[_Rows, WellMetadata]:
    """The header found, the columns chosen with their units, the data rows delimited and
    the decimal mark resolved; and the title block's well metadata."""
    layout = LAYOUTS.get(kind)
    if layout is None:
        raise ValueError(f"the csv reader reads kinds {', '.join(LAYOUTS)}, not {kind!r}")
    given = options or CsvOptions()
    opts = given.resolved()
    text = load(path, max(HEADER_SEARCH_LINES, opts.header_line or 0))
    try:
        header = find_header(path, text.head, opts, layout.required)
    except InputFileError as exc:
        _other_kind(path, text.head, opts, kind, exc)
        raise
    header = with_units_row(path, text.head, header)
    lengths = length_units(header, opts, layout.columns)
    title = text.head[: header.index]
    check_title(path, title, header.delimiter)
    well, in_file = read_title(path, title, header.delimiter, lengths)
    option = [("option north_reference", opts.north_reference)] if opts.north_reference else []
    declared = in_file + option
    statements = title_statements(path, title, header.delimiter)
    uncertainty = Stated.of(
        path, statements.get("confidence"), statements.get("error_model"), statements.get("tie_on")
    )
    chosen = readable(
        path,
        {
            name: choose(path, header, name, declared)
            for name in layout.columns
            if name in header.found
        },
        uncertainty,
        dict.fromkeys(header.found, header.index + 1),
    )
    _one_name_per_cell(path, header, chosen)
    north = None
    if "azi" in chosen:
        north = _azimuth_reference(path, header, chosen["azi"], declared, opts)
        stated = north_reference(path, header, chosen["azi"], in_file)
        well = stated_north(path, well, stated, header.index + 1)
    profiled = profile_units(given)
    factors = {
        name: factor(path, header, cell, name, opts, profiled)
        for name, cell in chosen.items()
        if CURVES[name].quantity is not None
    }
    rows = data_rows(path, text, header, [chosen[n].index for n in layout.required])
    found = _Rows(
        path, layout, header, chosen, factors, rows, opts.decimal, north, opts, uncertainty
    )
    found.schema  # noqa: B018  (a conventions option that cannot apply fails before the rows)
    return found, well


def _one_name_per_cell(path: Path, header: Header, chosen: dict[str, Cell]) -> None:
    """Refuse two columns read from one header cell (the option ``columns`` naming it
    twice): a cell is one column."""
    names: dict[int, str] = {}
    for name, cell in chosen.items():
        first = names.setdefault(cell.index, name)
        if first != name:
            raise InputFileError(
                path,
                f"option columns: {first} and {name} both name the header cell {cell.text!r}; "
                "a cell is one column",
                line=header.index + 1,
                column=cell.text,
            )


def _azimuth_reference(
    path: Path,
    header: Header,
    azi: Cell,
    declared: list[tuple[str, NorthReference]],
    opts: CsvOptions,
) -> NorthReference:
    """The azimuths' north reference: declared by the file or the options, else the
    default; an error if none."""
    north = north_reference(path, header, azi, declared) or opts.default_north_reference
    if north is None:
        raise InputFileError(
            path,
            "no north reference for the azimuths: name it in the header ('Azimuth True', "
            "'AZI (GN)'), add a line 'north_reference: grid' above the header, or set the "
            "option north_reference (or the well's north_reference)",
            line=header.index + 1,
            column=azi.text,
        )
    return north


KIND_WORDS = {
    "stations": "survey stations",
    "samples": "raw sensor samples",
    "readings": "position readings",
}
"""The kinds in words."""


def _other_kind(
    path: Path, head: list[str], opts: CsvOptions, kind: str, problem: InputFileError
) -> None:
    """Raise a :class:`WrongKindError` if the file has another kind's header instead."""
    for other, layout in LAYOUTS.items():
        if other == kind:
            continue
        try:
            find_header(path, head, opts, layout.required)
        except InputFileError:
            continue
        needs = ", ".join(LAYOUTS[kind].required)
        raise WrongKindError(
            path,
            f"a table of {KIND_WORDS.get(other, other)}; not {KIND_WORDS.get(kind, kind)} "
            f"(needs {needs})",
            problem.line,
            found=other,
        ) from None


def sniff(path: Path) -> Claim:
    """By content, a stations, samples or readings header in the first 64 KiB; by name, a
    .csv/.txt/.tsv file. A NUL byte in those 64 KiB (Parquet, MCAP and other binary files)
    is no CSV's: then the name alone counts (parsing binary bytes as lines costs ~0.1 s)."""
    by_name = Claim.NAME if path.suffix.lower() in SNIFF_SUFFIXES else Claim.NO
    try:
        with path.open("rb") as fh:
            head = fh.read(SNIFF_BYTES)
        if b"\0" in head:
            return by_name
        lines, _ = split_head(newlines(head), HEADER_SEARCH_LINES)
        for layout in LAYOUTS.values():
            try:
                find_header(path, lines, CsvOptions(), layout.required)
                return Claim.CONTENT
            except InputFileError:
                continue
        return by_name
    except Exception:  # sniffing never raises: a failure leaves only the name to go by
        return by_name


# ---------------------------------------------------------------------------- writer


def write_csv(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` as CSV: comment lines (well, north reference, survey calculation, the
    confidence and error model the columns state, the uncertainty's tie-on record as JSON),
    ``name[unit]`` header,
    then the values (floats at their unit's precision, :mod:`pipeline.io.precision`; NaN and
    ±inf as an empty cell; a value that is a null marker, -999.25…, is refused, as in LAS:
    every reader would read it back as no value); ``source_line`` is not written, as in LAS
    (:func:`~pipeline.io.precision.for_export`)."""
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
    if (calculation := calculation_of(table)) is not None:
        comments += [
            f"# survey_method={calculation.method}",
            f"# vs_azimuth={calculation.vs_azimuth!r} deg",
        ]
    comments += [f"# {key}={value}" for key, value in file_statements(table.schema).items()]
    if (tie_on := tie_on_of(table)) is not None:
        comments.append(f"# tie_on={tie_on.model_dump_json()}")
    for comment in comments:  # none the reader would refuse
        if (reason := title_problem(comment, ",")) is not None:
            raise ValueError(f"title line {comment[:40]!r}…: {reason}")
    rounded = for_export(table)
    head = io.StringIO()
    stdcsv.writer(head, lineterminator="\n").writerow([_header_cell(f) for f in rounded.schema])
    refuse_null_markers(
        {f.name: rounded.column(i).combine_chunks() for i, f in enumerate(rounded.schema)}
    )
    with path.open("wb") as fh:
        fh.write(("\n".join(comments) + "\n" + head.getvalue()).encode())
        pacsv.write_csv(_nan_as_null(rounded), fh, pacsv.WriteOptions(include_header=False))


def _nan_as_null(table: pa.Table) -> pa.Table:
    """NaN (an undefined value) and ±inf written as CSV's null, the empty cell: a writer
    never writes a number that is not finite."""
    columns = [
        pc.if_else(pc.is_finite(column), column, None)
        if pa.types.is_floating(column.type) and not _all_finite(column)
        else column
        for column in table.columns
    ]
    return pa.Table.from_arrays(columns, schema=table.schema)


def _all_finite(column: pa.ChunkedArray) -> bool:
    """Whether a float column holds finite numbers only (no null), told by its extremes
    (:func:`~pipeline.io.nulls.value_range`; False where they cannot tell)."""
    extremes = value_range(column)
    return extremes is not None and math.isfinite(extremes[0]) and math.isfinite(extremes[1])


def _header_cell(field: pa.Field) -> str:
    unit = (field.metadata or {}).get(UNIT_KEY)
    return f"{field.name}[{unit.decode()}]" if unit else str(field.name)


# ---------------------------------------------------------------------------- hooks


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="csv",
            description="survey stations (MD, inclination, azimuth; TVD, N/E, DLS) or raw "
            "sensor samples (time, gyro/accelerometer/magnetometer triads) from a delimited "
            "text file; vendor profiles in YAML",
            kinds={name: layout.contract for name, layout in LAYOUTS.items()},
            read=read,
            sniff=sniff,
            options=CsvOptions,
            stream=stream,
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

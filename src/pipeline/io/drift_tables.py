"""Built-in plugin: the reader of the drift tables.

The ``drift_tables`` reader reads three kinds — ``calibration``
(:class:`~pipeline.drift.tables.CalibrationReadings`), ``calibration_result``
(:class:`~pipeline.drift.tables.CalibrationResult`) and ``free_gyro``
(:class:`~pipeline.tables.FreeGyroReadings`) — from Parquet (as gyropipe writes it, units in
the schema) or from CSV in the layout gyropipe's CSV writer produces: optional ``#`` lines
above the header (``# well.<field>=<value>`` fill the well metadata, ``# north_reference=``
names the azimuths' north, the well's north reference too), a header of column names with
units in brackets or parentheses (``time[min]``, ``set_azimuth (deg)``; any unit
:mod:`pipeline.units` converts), then the rows. Columns the contract does not know are
ignored; numeric columns need a unit; an empty cell or a null marker
(:mod:`pipeline.io.nulls`: ``-999.25``…) is a null. The stages ``read_calibration``,
``read_calibration_result`` and ``read_free_gyro`` (:mod:`pipeline.stages.drift`) read a
pipeline input through it (one stage per kind, because a stage's output contract is fixed).
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from pipeline.contracts import SOURCE_LINE, ColumnSpec, TableContract
from pipeline.drift.tables import CalibrationReadings, CalibrationResult
from pipeline.errors import InputFileError, UnitError
from pipeline.hookspecs import hookimpl
from pipeline.io import parquet
from pipeline.io.north import stated_north
from pipeline.io.nulls import is_null_marker
from pipeline.io.numbers import file_integer, file_number
from pipeline.registry import Claim, ReaderDef
from pipeline.tables import FreeGyroReadings
from pipeline.units import QUANTITIES, conversion_factor
from pipeline.well import NORTH_WORDS, NorthReference, WellMetadata

KINDS: dict[str, type[TableContract]] = {
    "calibration": CalibrationReadings,
    "calibration_result": CalibrationResult,
    "free_gyro": FreeGyroReadings,
}
CSV_SUFFIXES = (".csv", ".txt", ".tsv")
HEADER_CELL = re.compile(r"^\s*([A-Za-z_]\w*)\s*(?:[\[(]\s*([^\])]*?)\s*[\])])?\s*$")
QUANTITY_OF = {q.canonical: name for name, q in QUANTITIES.items()}
TRUE_WORDS = {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}


class DriftReaderOptions(BaseModel):
    """Options of the drift_tables reader."""

    model_config = ConfigDict(extra="forbid")
    default_north_reference: NorthReference | None = Field(
        None, description="north reference of CSV azimuths the file does not declare"
    )


def read_drift_table(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read ``path`` (Parquet or CSV) as a table of ``kind`` (module docstring)."""
    contract = KINDS.get(kind)
    if contract is None:
        raise ValueError(f"the drift_tables reader reads kinds {', '.join(KINDS)}, not {kind!r}")
    if parquet.sniff(path):
        return parquet.read(path, kind, options)
    default = options.default_north_reference if options is not None else None
    table, well, stated = _read_csv(path, contract, default)
    return table, stated_north(path, well, stated)


def sniff(path: Path) -> Claim:
    """By content, a Parquet file; by name, a .csv/.txt/.tsv file."""
    if parquet.sniff(path):
        return Claim.CONTENT
    return Claim.NAME if path.suffix.lower() in CSV_SUFFIXES else Claim.NO


def _read_csv(
    path: Path, contract: type[TableContract], north: NorthReference | None
) -> tuple[pa.Table, WellMetadata, NorthReference | None]:
    """The table, the well metadata of its ``# well.`` lines and the north its
    ``# north_reference=`` line names (``north``, the option's, where it names none)."""
    stated = None
    try:
        lines = path.read_text(encoding="utf-8-sig").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"cannot read the file as UTF-8 text: {exc}") from None
    well: dict[str, str] = {}
    header: list[str] | None = None
    header_line = 0
    rows: list[tuple[int, list[str]]] = []
    for number, line in enumerate(lines, 1):
        text = line.strip()
        if not text:
            continue
        if text.startswith("#"):
            key, sep, value = text.lstrip("#").partition("=")
            key, value = key.strip(), value.strip()
            if header is None and sep and key.startswith("well."):
                well[key.removeprefix("well.")] = value
            elif header is None and sep and key == "north_reference":
                north = stated = _north(path, value, number)
            continue
        cells = next(csv.reader([line]))
        if header is None:
            header, header_line = cells, number
        elif len(cells) != len(header):
            raise InputFileError(path, f"{len(cells)} cells, the header has {len(header)}", number)
        else:
            rows.append((number, cells))
    if header is None:
        raise InputFileError(path, "no header line")
    columns = _columns(path, header, header_line, contract)
    data: dict[str, Any] = {}
    for spec, index, factor in columns:
        data[spec.name] = [_value(path, spec, cells[index], factor, line) for line, cells in rows]
    data[SOURCE_LINE] = [line for line, _ in rows]
    needs_north = any(spec.north_reference for spec, _, _ in columns)
    if needs_north and north is None:
        raise InputFileError(
            path,
            "no north reference for the azimuths: add a line '# north_reference=true' above "
            "the header, or set the well's north_reference",
            header_line,
        )
    try:
        metadata = WellMetadata.model_validate(well)
    except ValidationError as exc:
        raise InputFileError(path, f"well metadata lines: {exc}") from None
    return contract.compiled().make_table(data, north_reference=north), metadata, stated


def _north(path: Path, value: str, line: int) -> NorthReference:
    found = NORTH_WORDS.get(value.strip().lower())
    if found is None:
        raise InputFileError(path, f"unknown north reference {value!r}", line)
    return found


def _columns(
    path: Path, header: list[str], line: int, contract: type[TableContract]
) -> list[tuple[ColumnSpec, int, float]]:
    """(column rule, cell index, factor to the canonical unit) of each contract column."""
    specs = {c.name: c for c in contract.compiled().columns}
    found: list[tuple[ColumnSpec, int, float]] = []
    for index, cell in enumerate(header):
        match = HEADER_CELL.match(cell)
        spec = specs.get(match.group(1)) if match else None
        if match is None or spec is None:
            continue
        if any(known is spec for known, _, _ in found):
            raise InputFileError(path, f"column {spec.name!r} appears twice", line, cell)
        unit = match.group(2)
        factor = 1.0
        if spec.unit is not None:
            if not unit:
                raise InputFileError(
                    path, f"give the unit of {spec.name}: '{spec.name}[{spec.unit}]'", line, cell
                )
            if unit != spec.unit:
                quantity = QUANTITY_OF.get(spec.unit)
                if quantity is None:
                    raise InputFileError(path, f"unit must be {spec.unit!r}", line, cell)
                try:
                    factor = conversion_factor(unit, quantity)
                except UnitError as exc:
                    raise InputFileError(path, str(exc), line, cell) from None
        found.append((spec, index, factor))
    missing = [
        c.name for c in specs.values() if c.required and c.name not in {s.name for s, _, _ in found}
    ]
    if missing:
        raise InputFileError(
            path, f"no column {', '.join(map(repr, missing))} for {contract.__name__}", line
        )
    return found


def _value(path: Path, spec: ColumnSpec, cell: str, factor: float, line: int) -> Any:
    text = cell.strip()
    if not text:
        return None
    try:
        if pa.types.is_floating(spec.type):
            number = file_number(text)
            angle = QUANTITY_OF.get(spec.unit or "") in ("angle", "dogleg_severity")
            if is_null_marker(number, angle=angle):  # in the file's unit: no value
                return None
            value = number * factor
            if spec.finite and not math.isfinite(value):
                raise InputFileError(path, f"not a finite number: {text!r}", line, spec.name)
            return value
        if pa.types.is_integer(spec.type):
            return file_integer(text)
        if pa.types.is_boolean(spec.type):
            return TRUE_WORDS[text.lower()]
    except (ValueError, KeyError):
        kind = "number" if not pa.types.is_boolean(spec.type) else "true/false value"
        raise InputFileError(path, f"not a {kind}: {text!r}", line, spec.name) from None
    return text


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="drift_tables",
            description="calibration readings, calibration results and free-gyro readings "
            "from Parquet or CSV (name[unit] header, '# well.<field>=' lines)",
            kinds=KINDS,
            read=read_drift_table,
            sniff=sniff,
            options=DriftReaderOptions,
        )
    )

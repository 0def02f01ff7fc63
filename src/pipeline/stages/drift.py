"""Built-in plugin: free-gyro drift — calibration (seed 000), drift correction of free-gyro
surveys with in/out-run QC, Allan analysis of static records; and the reader of the drift
tables.

The ``drift_tables`` reader reads three kinds — ``calibration``
(:class:`~pipeline.drift.tables.CalibrationReadings`), ``calibration_result``
(:class:`~pipeline.drift.tables.CalibrationResult`) and ``free_gyro``
(:class:`~pipeline.tables.FreeGyroReadings`) — from Parquet (as gyropipe writes it, units in
the schema) or from CSV in the layout gyropipe's CSV writer produces: optional ``#`` lines
above the header (``# well.<field>=<value>`` fill the well metadata, ``# north_reference=``
names the azimuths' north), a header of column names with units in brackets or parentheses
(``time[min]``, ``set_azimuth (deg)``; any unit :mod:`pipeline.units` converts), then the
rows. Columns the contract does not know are ignored; numeric columns need a unit. The
stages ``read_calibration``, ``read_calibration_result`` and ``read_free_gyro`` read a
pipeline input through it (one stage per kind, because a stage's output contract is fixed).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from pipeline.contracts import SOURCE_LINE, ColumnSpec, TableContract
from pipeline.drift.allan import AllanOptions, analyse_static
from pipeline.drift.calibration import CalibrationOptions, calibrate
from pipeline.drift.correction import (
    CorrectionOptions,
    DriftRate,
    calibration_rate,
    correct_survey,
)
from pipeline.drift.tables import (
    AllanResult,
    CalibrationReadings,
    CalibrationResult,
    CalibrationSeries,
    CorrectedFreeGyroReadings,
    DriftStations,
    DwellRecommendation,
    InOutQc,
    NoiseParameters,
)
from pipeline.earth.site import resolve_site
from pipeline.errors import InputFileError, UnitError
from pipeline.hookspecs import hookimpl
from pipeline.io import parquet
from pipeline.registry import ReaderDef, StageContext, StageDef
from pipeline.stages.files import read_stage_def
from pipeline.tables import FreeGyroReadings, RawSamples
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
    return _read_csv(path, contract, default)


def sniff(path: Path) -> bool:
    """Parquet files and .csv/.txt/.tsv files."""
    return parquet.sniff(path) or path.suffix.lower() in CSV_SUFFIXES


def _read_csv(
    path: Path, contract: type[TableContract], north: NorthReference | None
) -> tuple[pa.Table, WellMetadata]:
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
                north = _north(path, value, number)
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
    return contract.compiled().make_table(data, north_reference=north), metadata


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
            return float(text) * factor
        if pa.types.is_integer(spec.type):
            return int(text)
        if pa.types.is_boolean(spec.type):
            return TRUE_WORDS[text.lower()]
    except (ValueError, KeyError):
        kind = "number" if not pa.types.is_boolean(spec.type) else "true/false value"
        raise InputFileError(path, f"not a {kind}: {text!r}", line, spec.name) from None
    return text


def calibrate_stage(
    inputs: Mapping[str, pa.Table], params: CalibrationOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Calibration readings → drift estimates and series means per instrument."""
    result, series = calibrate(inputs["readings"], params, ctx.well.tool_serial)
    return {"result": result, "series": series}


def correct_stage(
    inputs: Mapping[str, pa.Table], params: CorrectionOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Free-gyro readings → drift-corrected readings, stations and in/out QC."""
    source = params.source
    if source == "auto":
        source = (
            "calibration"
            if "calibration" in inputs
            else "given"
            if params.drift_rate is not None
            else "tie_in"
        )
    rate: DriftRate | None = None
    if source == "calibration":
        if "calibration" not in inputs:
            raise ValueError("source calibration: wire a calibration result to `calibration`")
        serial = params.instrument or ctx.well.tool_serial
        rate = calibration_rate(
            inputs["calibration"], serial, params.estimate, params.allow_nonlinear
        )
    elif source == "given":
        if params.drift_rate is None:
            raise ValueError("source given: set drift_rate (°/h)")
        rate = DriftRate(params.drift_rate, params.drift_sigma, "given")
    survey = correct_survey(inputs["readings"], params, rate)
    return {"readings": survey.readings, "stations": survey.stations, "qc": survey.qc}


def allan_stage(
    inputs: Mapping[str, pa.Table], params: AllanOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Static raw samples → Allan deviations, noise terms and the recommended dwell."""
    site = resolve_site(ctx.well, stage="allan", latitude=params.latitude)
    allan, noise, dwell = analyse_static(inputs["samples"], params, site.latitude)
    return {"allan": allan, "noise": noise, "dwell": dwell}


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


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    for name, kind, contract, description, default_input in (
        (
            "read_calibration",
            "calibration",
            CalibrationReadings,
            "Read free-gyro calibration readings (series × set azimuths).",
            "calibration",
        ),
        (
            "read_calibration_result",
            "calibration_result",
            CalibrationResult,
            "Read a drift calibration result written by calibrate_drift.",
            "calibration",
        ),
        (
            "read_free_gyro",
            "free_gyro",
            FreeGyroReadings,
            "Read free-gyro in-run/out-run station readings.",
            "readings",
        ),
    ):
        register(read_stage_def(name, kind, contract, description, default_input))
    register(
        StageDef(
            name="calibrate_drift",
            func=calibrate_stage,
            description="Drift rate of free gyros from calibration series (seed 000): pairwise, "
            "mean, grouped, fitted and traditional estimates with σ, and a linearity verdict.",
            inputs={"readings": CalibrationReadings},
            outputs={"result": CalibrationResult, "series": CalibrationSeries},
            params=CalibrationOptions,
        )
    )
    register(
        StageDef(
            name="correct_drift",
            func=correct_stage,
            description="Remove the drift from free-gyro readings (calibrated, given or tie-in "
            "rate) with predicted σ; combined stations; in-run/out-run QC.",
            inputs={"readings": FreeGyroReadings, "calibration": CalibrationResult},
            outputs={
                "readings": CorrectedFreeGyroReadings,
                "stations": DriftStations,
                "qc": InOutQc,
            },
            params=CorrectionOptions,
            optional_inputs=frozenset({"calibration"}),
        )
    )
    register(
        StageDef(
            name="allan",
            func=allan_stage,
            description="Allan deviations of a static record, IEEE 952 noise terms per axis and "
            "the compassing dwell per frame position for a target azimuth σ.",
            inputs={"samples": RawSamples},
            outputs={"allan": AllanResult, "noise": NoiseParameters, "dwell": DwellRecommendation},
            params=AllanOptions,
        )
    )

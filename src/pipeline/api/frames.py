"""Tables in and out of the Python API.

A table is given as a pandas DataFrame or an Arrow table and returned as the same kind.

- **Arrow tables** carry each column's unit (and an azimuth's north reference) in the field
  metadata (``unit``, ``north_reference``) and the well metadata in the schema metadata, as
  every table of a pipeline does.
- **DataFrames** carry them in ``attrs``: ``attrs["units"]`` maps a column to its unit,
  ``attrs["north_reference"]`` names the azimuths' north (``true``, ``grid`` or
  ``magnetic``; ``attrs["north_references"]`` maps azimuth columns to theirs, as returned),
  ``attrs["well"]`` holds the well metadata (a mapping), ``attrs["uncertainty"]`` what a
  trajectory's uncertainty columns state (error model, confidence, σ convention of each
  column family, largest horizontal semi-major axis and TD's: the JSON summary's
  ``uncertainty`` object; its error model and confidence go back to the columns when the
  frame is written or passed on). A column without a declared unit
  is taken to be in its canonical unit (m, deg, deg/h, m/s², nT, s, deg/30 m). Integer
  columns come back as pandas' nullable ``Int64``; float columns as NumPy floats (NaN: an
  undefined value), or as nullable ``Float64`` when they have missing values (null).

A declared unit that is not the canonical one is converted (``ft`` → m, ``rad/s`` → deg/h…)
or, if it is not a unit of the column's quantity, refused with a :class:`UnitError` naming
the column — never silently used.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any, TypeAlias, TypeGuard

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from pydantic import ValidationError

from pipeline.contracts import NORTH_KEY, NORTH_REFERENCES, UNIT_KEY, TableContract
from pipeline.errors import ParameterError, UnitError
from pipeline.io.mnemonics import CURVES
from pipeline.uncertainty.stated import statement_of, with_statements
from pipeline.uncertainty.tieon import TieOnRecord
from pipeline.units import QUANTITIES, canonical_unit, conversion_factor
from pipeline.well import WELL_KEY, WellMetadata, attach, well_of

if TYPE_CHECKING:
    import pandas as pd

PANDAS_KEY = b"pandas"
"""Schema metadata pandas writes (and pyarrow reads back) to restore an index and dtypes."""

TableLike: TypeAlias = "pd.DataFrame | pa.Table"
"""A table the API takes: a pandas DataFrame or an Arrow table."""
WellLike: TypeAlias = "WellMetadata | Mapping[str, Any] | None"
"""Well metadata the API takes: a :class:`WellMetadata`, a mapping of its fields, or None."""

QUANTITY_OF_UNIT = {q.canonical: name for name, q in QUANTITIES.items()}


def well_metadata(*wells: WellLike) -> WellMetadata:
    """The well metadata of ``wells`` merged in order (later fields win)."""
    merged = WellMetadata()
    for well in wells:
        if well is None:
            continue
        if isinstance(well, WellMetadata):
            merged = merged.merged(well)
            continue
        if not isinstance(well, Mapping):
            raise ParameterError(f"well: expected a mapping of well metadata fields, got {well!r}")
        try:
            merged = merged.merged(WellMetadata.model_validate(dict(well)))
        except ValidationError as exc:
            raise ParameterError(f"well: {describe(exc)}") from None
    return merged


def is_frame(data: object) -> TypeGuard[pd.DataFrame]:
    """True if ``data`` is a pandas DataFrame (pandas is imported only by who makes one)."""
    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(data, pandas.DataFrame)


def well_of_data(data: TableLike) -> WellMetadata:
    """The well metadata a table carries (none: empty)."""
    if is_frame(data):
        return well_metadata(data.attrs.get("well"))
    if not isinstance(data, pa.Table):
        raise ParameterError(f"expected a pandas DataFrame or a pyarrow Table, got {data!r}")
    return _stored_well(data) or WellMetadata()


def _stored_well(table: pa.Table) -> WellMetadata | None:
    """The well metadata stored in ``table``'s schema, if any; a :class:`ParameterError` if
    it is not JSON of valid fields (a table made or edited by hand)."""
    try:
        return well_of(table)
    except ValueError as exc:  # not JSON (or too deep), or not WellMetadata's fields
        detail = describe(exc) if isinstance(exc, ValidationError) else str(exc)
        raise ParameterError(
            f"the table's well metadata (schema metadata {WELL_KEY.decode()!r}) cannot be "
            f"used: {detail}"
        ) from None


def to_table(
    data: TableLike,
    contract: type[TableContract] | None = None,
    *,
    what: str = "table",
    well: WellMetadata | None = None,
) -> pa.Table:
    """``data`` as an Arrow table in canonical units: the columns of ``contract`` converted
    from their declared units; azimuths without a north reference take the well's. ``what``
    names the table in errors (e.g. ``compass input 'readings'``)."""
    if is_frame(data):
        table = _from_frame(data)
        north = data.attrs.get("north_reference")
    elif isinstance(data, pa.Table):
        table = data
        north = None
    else:
        raise ParameterError(
            f"{what}: expected a pandas DataFrame or a pyarrow Table, got {data!r}"
        )
    if contract is None:
        return table
    units = {f.name: f.metadata[UNIT_KEY].decode() for f in table.schema if _has(f, UNIT_KEY)}
    default_north = north or (well.north_reference if well is not None else None)
    columns = {c.name: c for c in contract.compiled().columns}
    fields, arrays = [], []
    for field, array in zip(table.schema, table.columns, strict=True):
        spec = columns.get(field.name)
        if spec is None:
            fields.append(field)
            arrays.append(array)
            continue
        declared = units.get(field.name)
        if spec.unit is not None and declared is not None and declared != spec.unit:
            array = pc.multiply(array.cast(pa.float64()), _factor(declared, spec.unit, field, what))
        ref = field.metadata[NORTH_KEY].decode() if _has(field, NORTH_KEY) else default_north
        if spec.north_reference and ref is None:
            raise ParameterError(
                f"{what}: the north reference of column {field.name!r} is unknown: set "
                "attrs['north_reference'] to 'true', 'grid' or 'magnetic', or give "
                "well={'north_reference': …}"
            )
        fields.append(spec.field(ref if spec.north_reference else None))
        try:
            arrays.append(array.cast(spec.type) if array.type != spec.type else array)
        except (pa.ArrowInvalid, pa.ArrowNotImplementedError) as exc:  # text in a number column
            raise ParameterError(
                f"{what}: column {field.name!r} ({array.type}) is not {spec.type}: {exc}"
            ) from None
    out = pa.Table.from_arrays(arrays, schema=pa.schema(fields, metadata=table.schema.metadata))
    return out


def to_frame(table: pa.Table) -> pd.DataFrame:
    """``table`` as a DataFrame whose ``attrs`` hold the units, the north reference (when the
    table has one) and the well metadata. A ``pandas`` schema metadata item that pyarrow
    cannot use (not JSON, not pandas' form) is a :class:`ParameterError`."""
    import pandas as pd

    if not isinstance(table, pa.Table):
        raise ParameterError(f"to_frame: expected a pyarrow Table, got {table!r}")
    nullable = {pa.int64(): pd.Int64Dtype(), pa.int32(): pd.Int32Dtype()}
    nullable_float = {pa.float64(): pd.Float64Dtype(), pa.float32(): pd.Float32Dtype()}
    try:
        frame: pd.DataFrame = table.to_pandas(types_mapper=nullable.get)
    except Exception as exc:  # pyarrow's own parsing of a file's "pandas" metadata
        if not _pandas_metadata_at_fault(table):
            raise
        raise ParameterError(
            "the table's pandas metadata (schema metadata 'pandas') cannot be used: "
            f"{type(exc).__name__}: {exc}"
        ) from None
    for name, column in zip(table.column_names, table.columns, strict=True):
        if pa.types.is_floating(column.type) and column.null_count:  # null is not NaN
            frame[name] = column.to_pandas(types_mapper=nullable_float.get)
    frame.attrs["units"] = {
        f.name: f.metadata[UNIT_KEY].decode() for f in table.schema if _has(f, UNIT_KEY)
    }
    norths = {f.name: f.metadata[NORTH_KEY].decode() for f in table.schema if _has(f, NORTH_KEY)}
    if norths:
        frame.attrs["north_references"] = norths
    if len(set(norths.values())) == 1:
        frame.attrs["north_reference"] = next(iter(norths.values()))
    well = _stored_well(table)
    if well is not None:
        frame.attrs["well"] = well.model_dump(mode="json", exclude_none=True)
    try:
        stated = statement_of(table)
    except ValueError as exc:  # columns stating different models or confidences
        raise ParameterError(f"the table's uncertainty columns: {exc}") from None
    if stated is not None:
        frame.attrs["uncertainty"] = stated.as_dict()
    return frame


def _pandas_metadata_at_fault(table: pa.Table) -> bool:
    """Whether ``table`` converts to a DataFrame once its ``pandas`` metadata is left out
    (called after a conversion failed: the metadata was the fault, not the data)."""
    meta = table.schema.metadata or {}
    if PANDAS_KEY not in meta:
        return False
    rest = {k: v for k, v in meta.items() if k != PANDAS_KEY}
    try:
        table.replace_schema_metadata(rest).to_pandas()
    except Exception:
        return False
    return True


def _from_frame(data: pd.DataFrame) -> pa.Table:
    """A DataFrame as an Arrow table with its declared units (and azimuths' north references)
    in the field metadata and its well metadata in the schema metadata."""
    arrays = [
        pa.array(column.to_numpy())  # NaN stays NaN (an undefined value), not null
        if isinstance(column.dtype, np.dtype) and column.dtype.kind == "f"
        else pa.array(column, from_pandas=True)  # nullable dtypes: NA is null
        for _, column in data.items()
    ]
    table = pa.Table.from_arrays(arrays, names=[str(name) for name in data.columns])
    units = _attr_mapping(data, "units")
    norths = _attr_mapping(data, "north_references")
    fields = []
    for f in table.schema:
        meta = {**(f.metadata or {})}
        if f.name in units:
            meta[UNIT_KEY] = str(units[f.name]).encode()
        if f.name in norths:
            meta[NORTH_KEY] = str(norths[f.name]).encode()
        fields.append(f.with_metadata(meta) if meta else f)
    well = well_of_data(data)
    north = data.attrs.get("north_reference")
    if north is not None and north not in NORTH_REFERENCES:
        raise ParameterError(
            f"attrs['north_reference'] is {north!r}: expected one of {', '.join(NORTH_REFERENCES)}"
        )
    if north is not None and not norths and well.north_reference is None:
        well = well.merged(WellMetadata(north_reference=north))  # the azimuths' default
    table = pa.Table.from_arrays(table.columns, schema=pa.schema(fields))
    return attach(_stated(table, data.attrs.get("uncertainty")), well)


def _stated(table: pa.Table, uncertainty: object) -> pa.Table:
    """``table`` whose uncertainty columns state the error model and confidence of a frame's
    ``attrs["uncertainty"]`` (as :func:`to_frame` put it there; either may be None)."""
    if uncertainty is None:
        return table
    if not isinstance(uncertainty, Mapping):
        raise ParameterError(f"attrs['uncertainty']: expected a mapping, got {uncertainty!r}")
    model, confidence = uncertainty.get("error_model"), uncertainty.get("confidence")
    if model is not None and not isinstance(model, str):
        raise ParameterError(f"attrs['uncertainty']: error_model {model!r} is no text")
    if confidence is not None and not (isinstance(confidence, float) and 0 < confidence < 1):
        raise ParameterError(
            f"attrs['uncertainty']: confidence {confidence!r} is no probability in (0, 1)"
        )
    try:
        tie_on = TieOnRecord(surveys=uncertainty.get("tie_on", ()))
    except ValidationError as exc:
        raise ParameterError(f"attrs['uncertainty']: tie_on: {exc.errors()[0]['msg']}") from None
    return with_statements(table, confidence, model, tie_on if tie_on.surveys else None)


def as_stated(table: pa.Table) -> pa.Table:
    """``table`` stating what the API takes it to mean, for a writer: a canonical column
    declaring no unit (``inc``, ``md``…) in its canonical unit (deg, m…), an ``azi`` naming
    no north reference in the well's (a DataFrame's ``attrs['north_reference']``)."""
    well = well_of(table)
    north = well.north_reference if well is not None else None
    fields = []
    for f in table.schema:
        meta = dict(f.metadata or {})
        quantity = CURVES[f.name].quantity if f.name in CURVES else None
        if quantity is not None and UNIT_KEY not in meta:
            meta[UNIT_KEY] = canonical_unit(quantity).encode()
        if f.name == "azi" and north is not None and NORTH_KEY not in meta:
            meta[NORTH_KEY] = north.encode()
        fields.append(f.with_metadata(meta) if meta else f)
    return pa.Table.from_arrays(table.columns, schema=pa.schema(fields, table.schema.metadata))


def _attr_mapping(data: pd.DataFrame, key: str) -> dict[str, Any]:
    """``data.attrs[key]`` (none: empty), which must map column names to text."""
    value = data.attrs.get(key) or {}
    if not isinstance(value, Mapping):
        raise ParameterError(f"attrs[{key!r}]: expected a mapping of column names, got {value!r}")
    return dict(value)


def like(template: TableLike, table: pa.Table) -> TableLike:
    """``table`` as the kind of table ``template`` is (DataFrame or Arrow)."""
    return to_frame(table) if is_frame(template) else table


def _factor(declared: str, canonical: str, field: pa.Field, what: str) -> float:
    quantity = QUANTITY_OF_UNIT.get(canonical)
    if quantity is None:
        raise UnitError(
            f"{what}: column {field.name!r} is declared in {declared!r}; it must be in "
            f"{canonical!r}"
        )
    try:
        return conversion_factor(declared, quantity)
    except UnitError as exc:
        raise UnitError(f"{what}: column {field.name!r}: {exc}") from None


def _has(field: pa.Field, key: bytes) -> bool:
    return field.metadata is not None and key in field.metadata


def describe(exc: ValidationError) -> str:
    """A pydantic error as ``field: problem (got value)`` items, one per problem."""
    return "; ".join(_items(exc))


def _items(exc: ValidationError) -> Iterator[str]:
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "value"
        if err["type"] == "extra_forbidden":
            yield f"unknown parameter {where!r}"
            continue
        got = err.get("input")
        shown = (
            "" if err["type"] == "missing" or isinstance(got, dict | list) else f" (got {got!r})"
        )
        yield f"{where}: {err['msg']}{shown}"

"""What a read table must be before a stage sees it: the columns of its kind, plausible
angles and the kind's contract (each failure an :class:`~pipeline.errors.InputFileError`
naming the file), and a reader's options parsed with every problem named."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, Protocol

import pyarrow as pa
from pydantic import BaseModel, ValidationError

from pipeline.contracts import TableContract
from pipeline.errors import ContractViolation, InputFileError, ReaderOptionsError, WrongKindError
from pipeline.plausibility import check_angles
from pipeline.tables import Stations
from pipeline.well import WellMetadata

__all__ = ["Reader", "check_columns", "check_read", "read_violation", "reader_options"]


class Reader(Protocol):
    """What the checks need of a reader (:class:`pipeline.registry.ReaderDef`)."""

    @property
    def name(self) -> str: ...

    @property
    def kinds(self) -> Mapping[str, type[TableContract]]: ...

    def parse_options(self, options: Mapping[str, Any], well: WellMetadata | None) -> BaseModel: ...


def check_read(
    path: Path, kind: str, reader: Reader, table: pa.Table, *, confirmed: bool = False
) -> None:
    """Raise an :class:`InputFileError` unless the table ``reader`` read from ``path`` meets
    the contract of ``kind`` (a :class:`WrongKindError` if it lacks a column the kind
    requires: a file of another kind): what a reader lets through (MD or time out of order, an
    inclination past 180°, a Parquet or MCAP column in another unit) is the file's fault,
    named with the line of its first bad row (when the table records lines) and every
    rule broken, on one line. Stations' angles are checked for plausibility first
    (:func:`pipeline.plausibility.check_angles`; ``confirmed``: the reader option
    ``angle_unit_confirmed``)."""
    check_columns(path, kind, reader, table.column_names)
    if issubclass(reader.kinds[kind], Stations):
        check_angles(path, table, confirmed=confirmed)
    try:
        reader.kinds[kind].validate_table(table)
    except ContractViolation as exc:
        raise read_violation(path, kind, reader, exc) from None


def check_columns(path: Path, kind: str, reader: Reader, names: list[str]) -> None:
    """A :class:`WrongKindError` unless the columns ``names`` read from ``path`` include
    every column the kind requires (else it is a file of another kind)."""
    columns = reader.kinds[kind].compiled().columns
    missing = [c.name for c in columns if c.required and c.name not in names]
    if missing:  # a reader of any kind of table (Parquet) found another kind's
        raise WrongKindError(
            path, f"not {kind}: no column {', '.join(map(repr, missing))} (reader {reader.name!r})"
        )


def read_violation(path: Path, kind: str, reader: Reader, exc: ContractViolation) -> InputFileError:
    """What a table read from ``path`` breaking the kind's contract is: the file's fault,
    at the line of its first bad row (when the table records lines), every rule on one line."""
    lines = [n for failure in exc.failures for n in failure.lines]
    rules = "; ".join(map(str, exc.failures))
    return InputFileError(
        path, f"not valid as {kind} (reader {reader.name!r}): {rules}", min(lines, default=0)
    )


def reader_options(
    reader: Reader, options: Mapping[str, Any], well: WellMetadata | None
) -> BaseModel:
    """The reader's options parsed (``ReaderDef.parse_options``), a problem a
    :class:`ReaderOptionsError` naming the reader and every option at fault."""
    try:
        return reader.parse_options(options, well)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(str(p) for p in e['loc']) or 'options'}: {e['msg']}" for e in exc.errors()
        )
        raise ReaderOptionsError(f"options of reader {reader.name!r}: {problems}") from None

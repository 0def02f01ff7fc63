"""Built-in plugin: Parquet reader (tables gyropipe wrote) and writer.

Parquet keeps the Arrow schema, so units, north references and well metadata round-trip.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
from pydantic import ValidationError

from pipeline.contracts import TableContract
from pipeline.errors import InputFileError, WrongKindError
from pipeline.hookspecs import hookimpl
from pipeline.registry import ReaderDef, WriterDef
from pipeline.tables import LogTable, PositionReadings, RawSamples, Stations
from pipeline.well import WELL_KEY, WellMetadata, well_of

MAGIC = b"PAR1"
KINDS: dict[str, type[TableContract]] = {
    "stations": Stations,
    "samples": RawSamples,
    "readings": PositionReadings,
    "log": LogTable,
}


def sniff(path: Path) -> bool:
    """By content: the file starts with the Parquet magic bytes."""
    try:
        with open(path, "rb") as fh:
            return fh.read(4) == MAGIC
    except OSError:
        return False


KIND_WORDS = {
    "stations": "survey stations",
    "samples": "raw sensor samples",
    "readings": "position readings",
}
"""The survey kinds in words."""


def read(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read a Parquet table; its units must already be canonical (checked by the contract).
    A table of another kind than ``kind`` (its required columns missing, another kind's all
    there) is a :class:`WrongKindError` saying which kind it is."""
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:  # Arrow's messages may span lines
        reason = " ".join(str(exc).split())
        raise InputFileError(path, f"not a readable Parquet file: {reason}") from exc
    _check_names(path, table.schema)
    contract = KINDS.get(kind)  # the drift-table reader reads its own kinds through here
    missing = _missing(contract, table) if contract is not None else []
    if missing:
        others = [k for k in KIND_WORDS if k != kind and not _missing(KINDS[k], table)]
        if others:
            raise WrongKindError(
                path,
                f"a table of {KIND_WORDS[others[0]]}; not {KIND_WORDS.get(kind, kind)} "
                f"(needs {', '.join(missing)})",
                found=others[0],
            )
    return table, _well(path, table)


def _check_names(path: Path, schema: pa.Schema) -> None:
    """Every column name is text (pyarrow decodes a name only when it is asked for it)."""
    for i in range(len(schema)):
        try:
            schema.field(i).name  # noqa: B018  (decoding is the check)
        except UnicodeDecodeError as exc:
            raise InputFileError(
                path, f"column {i + 1}: its name is not UTF-8 text ({exc.reason})"
            ) from None


def _well(path: Path, table: pa.Table) -> WellMetadata:
    """The well metadata stored in the table's schema (none: empty); metadata that is not
    a JSON object of well fields is the file's fault."""
    try:
        return well_of(table) or WellMetadata()
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(map(str, e['loc'])) or 'value'}: {e['msg']}" for e in exc.errors()
        )
    except ValueError as exc:  # not UTF-8, not JSON
        problems = f"not JSON text: {exc}"
    raise InputFileError(
        path, f"well metadata ({WELL_KEY.decode()!r} in the schema metadata): {problems}"
    )


def _missing(contract: type[TableContract], table: pa.Table) -> list[str]:
    """Required columns of ``contract`` that ``table`` lacks."""
    columns = contract.compiled().columns
    return [c.name for c in columns if c.required and c.name not in table.column_names]


def write(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` (schema and field metadata included) as Parquet."""
    pq.write_table(table, path)


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="parquet",
            description="Parquet tables with gyropipe unit metadata",
            kinds=KINDS,
            read=read,
            sniff=sniff,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="parquet",
            description="Apache Parquet (keeps units and well metadata)",
            extension="parquet",
            write=write,
        )
    )

"""Built-in plugin: Parquet reader (tables gyropipe wrote) and writer.

Parquet keeps the Arrow schema, so units, north references and well metadata round-trip.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from pipeline.errors import InputFileError
from pipeline.hookspecs import hookimpl
from pipeline.registry import ReaderDef, WriterDef
from pipeline.tables import LogTable, PositionReadings, RawSamples, Stations
from pipeline.well import WellMetadata, well_of

MAGIC = b"PAR1"


def sniff(path: Path) -> bool:
    """By content: the file starts with the Parquet magic bytes."""
    try:
        with open(path, "rb") as fh:
            return fh.read(4) == MAGIC
    except OSError:
        return False


def read(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Read a Parquet table; its units must already be canonical (checked by the contract)."""
    try:
        table = pq.read_table(path)
    except (OSError, pa.ArrowException) as exc:
        raise InputFileError(path, f"not a readable Parquet file: {exc}") from exc
    return table, well_of(table) or WellMetadata()


def write(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` (schema and field metadata included) as Parquet."""
    pq.write_table(table, path)


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="parquet",
            description="Parquet tables with gyropipe unit metadata",
            kinds={
                "stations": Stations,
                "samples": RawSamples,
                "readings": PositionReadings,
                "log": LogTable,
            },
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

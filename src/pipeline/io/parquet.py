"""Built-in plugin: Parquet reader (tables gyropipe wrote) and writer.

Parquet keeps the Arrow schema, so units, north references and well metadata round-trip;
the north the ``azi`` column names is the well's north reference the reader returns.
Both stream: the reader reads a row group at a time (:func:`stream`), the writer writes a
row group per batch (:func:`write_stream`).

Bounds, checked on the footer before anything is decoded (:func:`_check_bounds`): at most
:data:`MAX_COLUMNS` columns, and the decoded table (rows × columns × 8 bytes, or the row
groups' declared sizes when larger) at most :data:`MAX_INFLATION` times the file's size or
:data:`MIN_DECODED` bytes — run-length encoding packs millions of equal values into a few
bytes, so a small file can claim gigabytes. Columns are decoded on pyarrow's
threads when the readers have more than one (:func:`~pipeline.io.threads.reader_threads`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.dataset as ds
import pyarrow.parquet as pq
from pydantic import ValidationError

from pipeline import jsontext
from pipeline.contracts import NORTH_KEY, UNIT_KEY, TableContract
from pipeline.errors import InputFileError, WrongKindError
from pipeline.hookspecs import hookimpl
from pipeline.io.limits import MAX_COLUMNS
from pipeline.io.north import stated_north
from pipeline.io.threads import reader_threads
from pipeline.io.uncertainty_columns import UNCERTAINTY_COLUMNS, tie_on_record
from pipeline.registry import ReaderDef, WriterDef
from pipeline.streams import BATCH_ROWS, TableStream
from pipeline.tables import LogTable, PositionReadings, RawSamples, Stations
from pipeline.uncertainty.stated import unit_of
from pipeline.uncertainty.tieon import TIE_ON_KEY, TieOnRecord
from pipeline.units import quantity_of
from pipeline.well import NORTH_WORDS, WELL_KEY, WellMetadata, well_of

MAGIC = b"PAR1"
READ_BUFFER = 1 << 20
"""Bytes read from the file at a time when streaming."""
WRITE_BUFFER = 1 << 20
"""Bytes gathered before a write to the file (:func:`_sink`)."""
MAX_INFLATION = 100
"""Most times its own size a Parquet input may decode to (float sensor data: ~1.5)."""
MIN_DECODED = 64 << 20
"""The decoded size a small Parquet input may reach whatever its own size (bytes)."""
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
        _check_bounds(path)
        table = pq.read_table(path, use_threads=reader_threads() > 1)
    except (OSError, pa.ArrowException) as exc:  # Arrow's messages may span lines
        raise _unreadable(path, exc) from exc
    _check_kind(path, kind, table.schema)
    _check_uncertainty(path, table.schema)
    return table, _well(path, table.schema)


READ_WHOLE = 16 << 20
"""The most bytes a row group may hold in the file (compressed) for :func:`stream` to read
its column chunks whole, not through a buffer of :data:`READ_BUFFER` bytes (gyropipe's row
groups of :data:`~pipeline.streams.BATCH_ROWS` rows hold ~0.5 MB a float column): a
buffered read copies every page out of the buffer, ~5 % of the CPU of decoding such a file
(paired timing of the j-well samples)."""


def stream(path: Path, kind: str, options: Any) -> tuple[TableStream, WellMetadata]:
    """:func:`read` as a stream: the schema and well metadata from the file's footer (read
    once), the rows in batches of at most :data:`BATCH_ROWS` rows, row group after row
    group, the column chunks of a row group read whole when it holds at most
    :data:`READ_WHOLE` bytes of the file, else through a buffer of :data:`READ_BUFFER`
    bytes (a foreign file's row groups may hold millions of rows); its ``nbytes`` the
    decoded size the footer gives (:func:`_check_bounds`)."""
    try:
        meta, decoded = _check_bounds(path)
        schema = meta.schema.to_arrow_schema()
    except (OSError, pa.ArrowException) as exc:
        raise _unreadable(path, exc) from exc
    _check_kind(path, kind, schema)
    _check_uncertainty(path, schema)
    buffer = 0 if _largest_group(meta) <= READ_WHOLE else READ_BUFFER

    def batches() -> Iterator[pa.RecordBatch]:
        try:
            with pq.ParquetFile(path, metadata=meta, pre_buffer=False, buffer_size=buffer) as file:
                yield from file.iter_batches(
                    batch_size=BATCH_ROWS, use_threads=reader_threads() > 1
                )
        except (OSError, pa.ArrowException) as exc:
            raise _unreadable(path, exc) from exc

    stream = TableStream.of_batches(schema, batches)
    return dataclasses.replace(stream, nbytes=decoded), _well(path, schema)


def _largest_group(meta: pq.FileMetaData) -> int:
    """The most bytes (compressed, in the file) that one row group's column chunks hold."""
    return max(
        (
            sum(group.column(j).total_compressed_size for j in range(group.num_columns))
            for group in map(meta.row_group, range(meta.num_row_groups))
        ),
        default=0,
    )


def _check_bounds(path: Path) -> tuple[pq.FileMetaData, int]:
    """Refuse a file of more than :data:`MAX_COLUMNS` columns, or one that would decode to
    more than its budget (module docstring), before anything is decoded; the footer and
    the bytes the file decodes to. (The footer is read through a dataset fragment:
    ``pq.read_metadata`` decodes the column names.)"""
    meta = next(ds.dataset(str(path), format="parquet").get_fragments()).metadata
    if meta.num_columns > MAX_COLUMNS:
        raise InputFileError(
            path, f"footer: {meta.num_columns:,} columns, more than {MAX_COLUMNS:,}: refused"
        )
    size = path.stat().st_size
    budget = max(MIN_DECODED, MAX_INFLATION * size)
    decoded = 0
    for i in range(meta.num_row_groups):
        group = meta.row_group(i)
        decoded += max(group.total_byte_size, group.num_rows * meta.num_columns * 8)
    if decoded > budget:
        raise InputFileError(
            path,
            f"footer: {meta.num_rows:,} rows × {meta.num_columns} columns would decode to about "
            f"{decoded:,} bytes, more than {budget:,} ({MAX_INFLATION} times the file's "
            f"{size:,} bytes, at least {MIN_DECODED:,}): refused",
        )
    return meta, decoded


def _check_uncertainty(path: Path, schema: pa.Schema) -> None:
    """The file's uncertainty columns: each unit it states a unit of the column's quantity
    (a variance in 'ft' is no variance; one in ft², not carried, the stages say), the tie-on
    record (:data:`TIE_ON_KEY`), where it has one, the record gyropipe writes; else an
    :class:`InputFileError` saying what is wrong."""
    for name in UNCERTAINTY_COLUMNS:
        if name not in schema.names:
            continue
        unit = (schema.field(name).metadata or {}).get(UNIT_KEY, b"").decode(errors="replace")
        wanted = unit_of(name)
        if unit and quantity_of(unit) != quantity_of(wanted):
            raise InputFileError(path, f"unit {unit!r}: expected a unit of {wanted!r}", column=name)
    raw = (schema.metadata or {}).get(TIE_ON_KEY)
    if raw is not None:
        tie_on_record(path, raw.decode(errors="replace"), 0, TieOnRecord)


def _unreadable(path: Path, exc: Exception) -> InputFileError:
    reason = " ".join(str(exc).split())  # Arrow's messages may span lines
    return InputFileError(path, f"not a readable Parquet file: {reason}")


def _check_kind(path: Path, kind: str, schema: pa.Schema) -> None:
    """Column names are text; a table of another survey kind than ``kind`` (its required
    columns missing, another kind's all there) is a :class:`WrongKindError` naming it."""
    _check_names(path, schema)
    contract = KINDS.get(kind)  # the drift-table reader reads its own kinds through here
    missing = _missing(contract, schema) if contract is not None else []
    if missing:
        others = [k for k in KIND_WORDS if k != kind and not _missing(KINDS[k], schema)]
        if others:
            raise WrongKindError(
                path,
                f"a table of {KIND_WORDS[others[0]]}; not {KIND_WORDS.get(kind, kind)} "
                f"(needs {', '.join(missing)})",
                found=others[0],
            )


def _check_names(path: Path, schema: pa.Schema) -> None:
    """Every column name is text (pyarrow decodes a name only when it is asked for it)."""
    for i in range(len(schema)):
        try:
            schema.field(i).name  # noqa: B018  (decoding is the check)
        except UnicodeDecodeError as exc:
            raise InputFileError(
                path, f"column {i + 1}: its name is not UTF-8 text ({exc.reason})"
            ) from None


def _well(path: Path, schema: pa.Schema) -> WellMetadata:
    """The well metadata stored in the table's schema (none: empty), with the north its
    ``azi`` column names as its north reference (:func:`~pipeline.io.north.stated_north`);
    metadata that is not a JSON object of well fields is the file's fault."""
    try:
        well = well_of(schema) or WellMetadata()
        azi = (schema.field("azi").metadata or {}) if "azi" in schema.names else {}
        stated = NORTH_WORDS.get(azi.get(NORTH_KEY, b"").decode(errors="replace"))
        return stated_north(path, well, stated)
    except ValidationError as exc:
        problems = "; ".join(
            f"{'.'.join(map(str, e['loc'])) or 'value'}: {e['msg']}" for e in exc.errors()
        )
    except jsontext.TooDeep as exc:
        problems = str(exc)
    except ValueError as exc:  # not UTF-8, not JSON
        problems = f"not JSON text: {exc}"
    raise InputFileError(
        path, f"well metadata ({WELL_KEY.decode()!r} in the schema metadata): {problems}"
    )


def _missing(contract: type[TableContract], schema: pa.Schema) -> list[str]:
    """Required columns of ``contract`` that ``schema`` lacks."""
    columns = contract.compiled().columns
    return [c.name for c in columns if c.required and c.name not in schema.names]


def write(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` (schema and field metadata included) as Parquet, in row groups of
    :data:`~pipeline.streams.BATCH_ROWS` rows: a streamed read decodes a row group at a
    time, so its memory is bounded by the row group, not by the survey. Float columns are
    stored plain (:func:`dictionary_columns`)."""
    with _sink(path) as sink:
        pq.write_table(
            table, sink, row_group_size=BATCH_ROWS, use_dictionary=dictionary_columns(table.schema)
        )


def write_stream(stream: TableStream, path: Path, well: WellMetadata) -> None:
    """Write one pass of ``stream`` as Parquet, a row group per batch (the schema, with its
    field and schema metadata, as :func:`write` keeps it)."""
    with (
        _sink(path) as sink,
        pq.ParquetWriter(
            sink, stream.schema, use_dictionary=dictionary_columns(stream.schema)
        ) as writer,
    ):
        for batch in stream:
            writer.write_batch(batch)


def _sink(path: Path) -> pa.BufferedOutputStream:
    """``path`` opened for writing through a buffer of :data:`WRITE_BUFFER` bytes: the
    Parquet writer writes each page header, page and footer part on its own (a 24-column
    table of 122 rows: ~80 writes), each a system call when it writes to the file itself
    (a continuous well's 7 persisted tables took 9.9 ms, now 9.1; the bytes are the same)."""
    return pa.BufferedOutputStream(pa.OSFile(str(path), "wb"), WRITE_BUFFER)


def dictionary_columns(schema: pa.Schema) -> list[str]:
    """The columns worth dictionary encoding: all but the floating-point ones. Sensor
    samples and computed values are nearly all distinct, so a float column's dictionary
    only fills up and is dropped, and building it cost 6× the rest of writing a full-rate
    series (benchmarks/bench_well_floor.py); plain, the file is smaller and decodes faster."""
    return [f.name for f in schema if not pa.types.is_floating(f.type)]


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="parquet",
            description="Parquet tables with gyropipe unit metadata",
            kinds=KINDS,
            read=read,
            sniff=sniff,
            stream=stream,
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
            write_stream=write_stream,
        )
    )

"""gyropipe's own MCAP layout: batched, columnar raw samples (writer and reader).

* Topic ``/gyropipe/samples``, message encoding ``arrow.ipc.record_batch``: each message is
  one Arrow IPC encapsulated record-batch message of up to :data:`BATCH_ROWS` samples (no
  schema inside); its log time is the first sample's time in ns (display only — the exact
  float64 times are in the batch). The channel's schema record (encoding
  ``arrow.ipc.schema``) holds the table's whole Arrow IPC schema: every field with its unit
  metadata, the schema metadata, and under ``gyropipe.markers`` the JSON list of the
  columns carried by the markers channel instead of the batches.
* Topic ``/gyropipe/markers``, message encoding ``json`` (JSON schema ``gyropipe.Marker``):
  one event at the first sample and at each change of ``station``/``position``:
  ``{"row": 0-based sample index, "time": sample time in s, "station": int|null,
  "position": int|null}``; the reader forward-fills them back into the columns.
* Metadata records ``gyropipe.well`` (the set WellMetadata fields, tool type and serial
  included, as strings: numbers in shortest round-trip form, dates ISO) and
  ``gyropipe.units`` (column → unit, ``""`` when unitless) for tools without Arrow.
* Chunks uncompressed, with CRCs, plus the data-section CRC. Integrity comes from these
  CRCs alone — a flipped bit inside a float of an Arrow batch is otherwise undetectable —
  and the reader checks them (:mod:`pipeline.io.mcap.records`). Uncompressed for speed:
  zstd saves about a third on simulated mems-vrg samples (time, depth and frame angle are
  smooth; sensor noise is not) but decompresses at ~0.6 GB/s on a 2-core VM, slower than
  the reader needs, and it rules out handing out the batches as views of the file's bytes
  (the columns the reader returns are chunked per message, zero-copy views of the bytes
  read; the writer replaces a file by a new one rather than truncating it in place).

Any table with a finite, strictly increasing float64 ``time`` column (s) is written, extra
columns included (not the engine's own: ``source_line``, the lines of a file read, and the
``gyropipe.source`` path it was read from, :func:`for_client`); other tables (Stations,
trajectories) are refused with a ``ValueError`` naming the writers that take them, and so
are dictionary-encoded columns.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import IO, Any, cast

import numpy as np
import pyarrow as pa
from mcap.records import Channel
from mcap.writer import CompressionType, Writer
from pydantic import ValidationError

from pipeline import jsontext
from pipeline.contracts import SOURCE_KEY, SOURCE_LINE, UNIT_KEY
from pipeline.errors import ParameterError
from pipeline.io.mcap.crc import DataSection
from pipeline.io.mcap.records import (
    McapFile,
    Messages,
    describe,
    iter_messages,
    iter_payloads,
    messages_of,
)
from pipeline.version import __version__
from pipeline.well import WellMetadata

SAMPLES_TOPIC = "/gyropipe/samples"
MARKERS_TOPIC = "/gyropipe/markers"
ARROW_SCHEMA_ENCODING = "arrow.ipc.schema"
ARROW_MESSAGE_ENCODING = "arrow.ipc.record_batch"
SAMPLES_SCHEMA = "gyropipe.samples"
MARKER_SCHEMA = "gyropipe.Marker"
WELL_RECORD = "gyropipe.well"
UNITS_RECORD = "gyropipe.units"
MARKERS_KEY = b"gyropipe.markers"
PROFILE = "gyropipe"
MARKER_COLUMNS = ("station", "position")
BATCH_ROWS = 10_000
"""Samples per message (~0.5–1 MB: per-message costs vanish, batches stay small)."""
CHUNK_BYTES = 4 << 20
"""Bytes of messages after which a chunk of a samples file is closed: such a file is read as
a run's input, and fewer, larger chunks read faster (a 47 MB file in chunks of one message
read in 55 ms, in 4 MiB chunks 52 ms). A run's processed tables, written by every run, go
in smaller chunks (:data:`pipeline.io.mcap.tables.CHUNK_BYTES`)."""
_MAX_NS = 2**64 - 1


# ---------------------------------------------------------------------------- writer


def write_samples(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write a time-series table (raw samples) in gyropipe's batched MCAP layout."""
    times = _checked_times(table)
    check_encodable(table)
    markers = [
        m for m in MARKER_COLUMNS if m in table.column_names and pa.types.is_integer(table[m].type)
    ]
    meta = {**(table.schema.metadata or {}), MARKERS_KEY: json.dumps(markers).encode()}
    data = table.drop_columns(markers)
    schema = for_client(table.schema.with_metadata(meta))
    path.unlink(missing_ok=True)  # a new inode: tables still mapping an old file stay valid
    with path.open("wb") as fh:
        section = DataSection(fh)
        writer = start_writer(section)
        add_arrow_channel(writer, SAMPLES_TOPIC, SAMPLES_SCHEMA, data, schema, times)
        if markers and table.num_rows:
            marker_schema = writer.register_schema(
                MARKER_SCHEMA, "jsonschema", json.dumps(_marker_json_schema(markers)).encode()
            )
            marker_channel = writer.register_channel(MARKERS_TOPIC, "json", marker_schema)
            for sequence, event in enumerate(_events(table, markers, times)):
                stamp = _ns(event["time"])
                writer.add_message(
                    marker_channel, stamp, json.dumps(event).encode(), stamp, sequence
                )
        writer.add_metadata(WELL_RECORD, well_strings(well))
        writer.add_metadata(UNITS_RECORD, units_of(schema))
        writer.finish()  # type: ignore[no-untyped-call]
        section.seal()


def start_writer(section: DataSection, chunk_bytes: int | None = None) -> Writer:
    """An MCAP writer of gyropipe's profile into ``section`` (its file; after the writer's
    ``finish``, :meth:`~pipeline.io.mcap.crc.DataSection.seal` writes the data section's
    CRC): uncompressed chunks (closed past ``chunk_bytes`` of messages, by default
    :data:`CHUNK_BYTES`) with CRCs, started."""
    writer = Writer(
        cast(IO[bytes], section),  # what the writer calls: write, tell, flush
        chunk_size=CHUNK_BYTES if chunk_bytes is None else chunk_bytes,
        compression=CompressionType.NONE,
        enable_crcs=True,
        enable_data_crcs=False,  # the section's own (each chunk's messages read once)
    )
    writer.start(profile=PROFILE, library=f"gyropipe {__version__}")
    return writer


def add_arrow_channel(
    writer: Writer,
    topic: str,
    schema_name: str,
    data: pa.Table | Iterable[pa.RecordBatch],
    schema: pa.Schema,
    times: np.ndarray | bool | None,
) -> None:
    """A channel ``topic`` whose schema record is ``schema`` (the whole Arrow IPC schema),
    with ``data`` (a table, or record batches as they come) as record batches of up to
    :data:`BATCH_ROWS` rows; each message's log time is ``times`` (s) at its first row —
    ``True``: the batch's own ``time`` column, which must be complete and finite
    (:class:`UnstampedBatch` at the first batch whose column is not) — or 0. The engine's
    own column and metadata are left out (:func:`for_client`)."""
    schema = for_client(schema)
    schema_id = writer.register_schema(schema_name, ARROW_SCHEMA_ENCODING, schema.serialize())
    channel = writer.register_channel(topic, ARROW_MESSAGE_ENCODING, schema_id)
    batches = data.to_batches() if isinstance(data, pa.Table) else data
    row = sequence = 0
    for whole in batches:
        if times is True and not _stamps(whole):
            raise UnstampedBatch(topic)
        if SOURCE_LINE in whole.schema.names:
            whole = whole.drop_columns([SOURCE_LINE])
        for batch in pa.Table.from_batches([whole]).to_batches(max_chunksize=BATCH_ROWS):
            if not batch.num_rows:
                continue
            if times is True:
                stamp = _ns(float(batch.column("time")[0].as_py()))
            else:
                stamp = _ns(times[row]) if isinstance(times, np.ndarray) else 0
            data = batch.serialize()  # the IPC buffer itself, not copied to bytes
            writer.add_message(channel, stamp, data, stamp, sequence)
            row += batch.num_rows
            sequence += 1


def for_client(schema: pa.Schema) -> pa.Schema:
    """``schema`` as a file for others holds it: without ``source_line`` (the lines of the
    file a table was read from mean nothing in another) and the ``gyropipe.source`` path of
    that file (a path on the machine that ran, named in the engine's errors)."""
    if SOURCE_LINE in schema.names:
        schema = schema.remove(schema.get_field_index(SOURCE_LINE))
    meta = {k: v for k, v in (schema.metadata or {}).items() if k != SOURCE_KEY}
    return schema.with_metadata(meta) if meta else schema.remove_metadata()


class UnstampedBatch(Exception):
    """A batch of the channel ``topic`` whose ``time`` column cannot stamp its messages (a
    null, a value not finite)."""

    def __init__(self, topic: str) -> None:
        super().__init__(f"{topic}: a batch's 'time' column has nulls or values not finite")
        self.topic = topic


def _stamps(batch: pa.RecordBatch) -> bool:
    """The batch's ``time`` column is complete and finite (it can stamp messages)."""
    column = batch.column(batch.schema.get_field_index("time"))
    return not column.null_count and bool(np.isfinite(column.to_numpy()).all())


def check_encodable(table: pa.Table | pa.Schema) -> None:
    """Refuse columns the batched layout does not hold (dictionary-encoded ones)."""
    for f in table if isinstance(table, pa.Schema) else table.schema:
        if pa.types.is_dictionary(f.type):
            raise ValueError(f"column {f.name!r} is dictionary-encoded: decode it first")


def units_of(table: pa.Table | pa.Schema) -> dict[str, str]:
    """Column → unit (``""`` when unitless), for tools without Arrow."""
    schema = table if isinstance(table, pa.Schema) else table.schema
    return {f.name: (f.metadata or {}).get(UNIT_KEY, b"").decode() for f in schema}


def _checked_times(table: pa.Table) -> np.ndarray:
    if "time" not in table.column_names or table.schema.field("time").type != pa.float64():
        raise ValueError(
            "the mcap writer writes time series: the table needs a float64 'time' column "
            "(s); write other tables with the parquet or csv writer, or several processed "
            "tables with the export stage"
        )
    column = table.column("time")
    if column.null_count:
        raise ValueError("column 'time' has missing values")
    times: np.ndarray = column.to_numpy()
    if len(times) and not (np.isfinite(times).all() and (np.diff(times) > 0).all()):
        raise ValueError("column 'time' must be finite and strictly increasing")
    return times


def _ns(seconds: float) -> int:
    """A log time in ns (clamped to MCAP's unsigned range; the batch keeps the exact time)."""
    seconds = float(seconds)  # a Python float: no overflow warning from NumPy
    if seconds >= _MAX_NS / 1e9:
        return _MAX_NS
    return max(round(seconds * 1e9), 0)


def _events(table: pa.Table, markers: list[str], times: np.ndarray) -> list[dict[str, Any]]:
    """One event per row where any marker column changes value (nulls included)."""
    change = np.zeros(table.num_rows, dtype=bool)
    change[0] = True
    columns = []
    for name in markers:
        column = table.column(name)
        valid = column.is_valid().to_numpy(zero_copy_only=False)
        values = column.fill_null(0).to_numpy().astype(np.int64)
        change[1:] |= (valid[1:] != valid[:-1]) | (valid[1:] & (values[1:] != values[:-1]))
        columns.append((name, values, valid))
    return [
        {"row": row, "time": float(times[row])}
        | {name: int(values[row]) if valid[row] else None for name, values, valid in columns}
        for row in np.flatnonzero(change).tolist()
    ]


def _marker_json_schema(markers: list[str]) -> dict[str, Any]:
    integer = {"type": ["integer", "null"]}
    return {
        "title": MARKER_SCHEMA,
        "description": "station/position from this sample on (forward-filled)",
        "type": "object",
        "properties": {
            "row": {"type": "integer", "description": "0-based sample index"},
            "time": {"type": "number", "unit": "s", "description": "sample time"},
        }
        | dict.fromkeys(markers, integer),
        "required": ["row", "time", *markers],
    }


def well_strings(well: WellMetadata) -> dict[str, str]:
    """The set well metadata fields as the strings of the ``gyropipe.well`` record."""
    return {k: str(v) for k, v in well.model_dump(mode="json", exclude_none=True).items()}


def read_well(file: McapFile) -> WellMetadata:
    """The well metadata of the file's ``gyropipe.well`` records (later ones override)."""
    well = WellMetadata()
    for name, entries, offset in file.metadata:
        if name != WELL_RECORD:
            continue
        try:
            well = well.merged(WellMetadata.model_validate(entries))
        except ValidationError as exc:
            problem = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors())
            raise file.fail(f"metadata record {WELL_RECORD} at byte {offset}: {problem}") from None
        except ParameterError as exc:  # its survey dates and an earlier record's out of order
            raise file.fail(f"metadata record {WELL_RECORD} at byte {offset}: {exc}") from None
    return well


# ---------------------------------------------------------------------------- reader


def read_batches(file: McapFile, channel: Channel) -> pa.Table:
    """gyropipe's batched samples channel, markers forward-filled back into their columns."""
    where = f"topic {SAMPLES_TOPIC}"
    full = arrow_schema(file, channel)
    meta = dict(full.metadata or {})
    try:
        markers = jsontext.loads(meta.pop(MARKERS_KEY, b"[]"))
    except ValueError as exc:
        raise file.fail(f"{where}: unreadable Arrow schema: {exc}") from None
    if "time" not in full.names or full.field("time").type != pa.float64():
        raise file.fail(f"{where}: the Arrow schema has no float64 'time' column")
    if not (
        isinstance(markers, list)
        and all(isinstance(m, str) for m in markers)
        and set(markers) <= set(full.names) - {"time"}
    ):
        raise file.fail(f"{where}: schema metadata names unknown marker columns {markers!r}")
    markers.sort(key=full.get_field_index)  # inserted back in schema order
    table = arrow_batches(file, channel, pa.schema([f for f in full if f.name not in markers]))
    for name, column in _marker_columns(file, table, markers).items():
        field = full.field(name)
        try:
            column = column.cast(field.type)
        except pa.ArrowInvalid as exc:
            problem = f"{MARKERS_TOPIC}: {name} values do not fit {field.type}: {exc}"
            raise file.fail(problem) from None
        table = table.add_column(full.get_field_index(name), field, column)
    return table.replace_schema_metadata(meta or None)


def arrow_schema(file: McapFile, channel: Channel) -> pa.Schema:
    """The whole Arrow schema of one of gyropipe's batched channels."""
    where = f"topic {channel.topic}"
    schema = file.schemas.get(channel.schema_id)
    if channel.message_encoding != ARROW_MESSAGE_ENCODING or schema is None:
        raise file.fail(f"{where}: expected {ARROW_MESSAGE_ENCODING} messages with a schema")
    if schema.encoding != ARROW_SCHEMA_ENCODING:
        raise file.fail(
            f"{where}: schema encoding {schema.encoding!r}, not {ARROW_SCHEMA_ENCODING}"
        )
    where += f", schema record {schema.id} ({schema.name!r})"
    try:
        found: pa.Schema = pa.ipc.read_schema(pa.py_buffer(schema.data))
    except (pa.ArrowException, ValueError, OSError) as exc:  # OSError: a corrupt flatbuffer
        reason = " ".join(str(exc).split())
        raise file.fail(f"{where}: unreadable Arrow schema: {reason}") from None
    for i in range(len(found)):
        try:
            found.field(i).name  # noqa: B018  (pyarrow decodes a name when asked: the check)
        except UnicodeDecodeError as exc:
            raise file.fail(
                f"{where}: column {i + 1} of the Arrow schema: its name is not UTF-8 text "
                f"({exc.reason})"
            ) from None
    return found


def arrow_batches(file: McapFile, channel: Channel, schema: pa.Schema) -> pa.Table:
    """The record batches of a batched channel as one table of ``schema`` (zero-copy)."""
    batches = []
    for index, block, row in iter_messages(messages_of(file, channel.id)):
        try:
            batch = pa.ipc.read_record_batch(pa.py_buffer(block.payload(row)), schema)
            batch.validate()  # buffer sizes agree with the lengths (cheap, not the values)
        except (pa.ArrowException, ValueError, OSError, EOFError) as exc:
            # OSError: a payload cut short; EOFError: an empty one
            raise file.fail(f"{block.describe(row, index)}: bad Arrow batch: {exc}") from None
        batches.append(batch)
    return pa.Table.from_batches(batches, schema=schema)


def _marker_columns(
    file: McapFile, table: pa.Table, markers: list[str]
) -> dict[str, pa.ChunkedArray]:
    """The marker columns forward-filled from their events (int64)."""
    n = table.num_rows
    if n == 0 or not markers:
        return {name: pa.chunked_array([], pa.int64()) for name in markers}
    events, messages = _marker_events(file, markers)
    rows = np.array([e["row"] for e in events], dtype=np.int64)
    if not (rows[0] == 0 and (np.diff(rows) > 0).all() and rows[-1] < n):
        wrong = np.flatnonzero(np.diff(rows) <= 0) + 1
        first = 0 if rows[0] != 0 else int(wrong[0]) if len(wrong) else len(rows) - 1
        raise file.fail(
            f"{describe(messages, first)}: event rows must increase from 0 within {n} "
            f"samples, got row {int(rows[first])}"
        )
    times = _values_at(table.column("time"), rows)
    stated = np.array([e["time"] for e in events], dtype=np.float64)
    if not np.array_equal(times, stated):
        bad = int(np.flatnonzero(times != stated)[0])
        raise file.fail(
            f"{describe(messages, bad)}: event says time {stated[bad]!r} at row {rows[bad]}, "
            f"the sample's time is {times[bad]!r}"
        )
    lengths = np.diff(np.append(rows, n)).tolist()
    return {name: _runs([e[name] for e in events], lengths) for name in markers}


def _values_at(column: pa.ChunkedArray, rows: np.ndarray) -> np.ndarray:
    """``column[rows]`` (sorted rows) without concatenating the chunks."""
    starts = np.cumsum([0] + [len(chunk) for chunk in column.chunks])
    found = []
    for chunk, start, end in zip(column.chunks, starts[:-1], starts[1:], strict=True):
        inside = rows[(rows >= start) & (rows < end)]
        if len(inside):
            found.append(chunk.to_numpy()[inside - start])
    values: np.ndarray = np.concatenate(found)
    return values


def _runs(values: list[int | None], lengths: list[int]) -> pa.ChunkedArray:
    """Runs of ``values[i]`` repeated ``lengths[i]`` times. Runs of one value are slices of
    one array, so a column of few values (positions, nulls) allocates almost nothing."""
    longest: dict[int | None, int] = {}
    for value, length in zip(values, lengths, strict=True):
        longest[value] = max(longest.get(value, 0), length)
    template = {
        v: pa.nulls(size, pa.int64()) if v is None else pa.array(np.full(size, v, np.int64))
        for v, size in longest.items()
    }
    chunks = [template[v].slice(0, size) for v, size in zip(values, lengths, strict=True)]
    return pa.chunked_array(chunks, pa.int64())


def _marker_events(file: McapFile, markers: list[str]) -> tuple[list[dict[str, Any]], Messages]:
    """The marker events, checked: {"row": int, "time": number, marker: int | null}; and
    their messages."""
    channels = [c for c in file.channels.values() if c.topic == MARKERS_TOPIC]
    if len(channels) != 1:
        raise file.fail(f"expected one {MARKERS_TOPIC} channel, found {len(channels)}")
    messages = messages_of(file, channels[0].id)
    payloads = list(iter_payloads(messages))
    try:  # one parse of all events; message by message only to name a bad one
        events = jsontext.loads(b"[" + b",".join(data for data, _, _ in payloads) + b"]")
    except ValueError:
        events = None
    expected = {"row", "time", *markers}
    for index, (data, _, located) in enumerate(payloads):
        try:
            event = events[index] if events is not None else jsontext.loads(data)
        except (ValueError, IndexError) as exc:
            raise file.fail(f"{located}: not one JSON event: {exc}") from None
        if not isinstance(event, dict) or event.keys() != expected:
            raise file.fail(f"{located}: expected an event {sorted(expected)}")
        problem = _event_problem(event, markers)
        if problem:
            raise file.fail(f"{located}: {problem}")
    if events is None or len(events) != len(payloads) or not events:
        raise file.fail(f"{MARKERS_TOPIC}: expected one JSON event per message, from row 0")
    return list(events), messages


_INT64 = range(-(2**63), 2**63)


def _event_problem(event: dict[str, Any], markers: list[str]) -> str | None:
    """Why a marker event's values are unusable (None if they are usable): the row a
    non-negative int64, the time a finite number (s), each marker an int64 or null."""
    row, time = event["row"], event["time"]
    if type(row) is not int or not 0 <= row < 2**63:
        return f"event row {row!r} is not a sample index (an integer from 0)"
    finite = type(time) is float and math.isfinite(time)
    if not (finite or (type(time) is int and abs(time) <= sys.float_info.max)):
        return f"event time {time!r} is not a finite number of seconds"
    for name in markers:
        value = event[name]
        if value is not None and (type(value) is not int or value not in _INT64):
            return f"event {name} {value!r} is not an int64 or null"
    return None

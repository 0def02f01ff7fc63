"""Processed tables of a run in one MCAP file (writer ``mcap`` through the ``export`` stage).

Each table goes on its own topic ``/gyropipe/<role>`` (``trajectory``, ``stations``,
``readings``, ``series``, ``qc``, ``rejects``: the export stage's port names) in gyropipe's
batched Arrow IPC encoding (:mod:`pipeline.io.mcap.arrow`): the channel's schema record is
the table's whole Arrow schema — every unit, north reference and the schema metadata — and
each message a record batch of up to 10,000 rows, logged at its first row's ``time`` (s) when
the table has a complete float64 ``time`` column, else at 0. Metadata records:
``gyropipe.well`` (the header), ``gyropipe.units/<role>`` (column → unit, for tools without
Arrow) and ``gyropipe.run`` (pipeline, its SHA-256, start, gyropipe version).

:func:`read_tables` gives the tables back exactly as written (less the engine's own
``source_line`` column and ``gyropipe.source`` path, never written:
:func:`~pipeline.io.mcap.arrow.for_client`); :func:`read_stations` one of them as survey
stations: ``/gyropipe/trajectory``, else ``/gyropipe/stations`` (the option ``topics``
names another), every column and what it states (units, north reference, the error model
and confidence of uncertainty columns) kept.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pyarrow as pa
from mcap.records import Channel

from pipeline.errors import WrongKindError
from pipeline.io.mcap.arrow import (
    ARROW_MESSAGE_ENCODING,
    SAMPLES_TOPIC,
    UNITS_RECORD,
    WELL_RECORD,
    UnstampedBatch,
    add_arrow_channel,
    arrow_batches,
    arrow_schema,
    check_encodable,
    for_client,
    read_well,
    start_writer,
    units_of,
    well_strings,
)
from pipeline.io.mcap.crc import DataSection
from pipeline.io.mcap.records import McapFile, scan
from pipeline.registry import Provenance
from pipeline.streams import Port
from pipeline.well import WellMetadata

TOPIC_PREFIX = "/gyropipe/"
RUN_RECORD = "gyropipe.run"
STATION_TOPICS = ("/gyropipe/trajectory", "/gyropipe/stations")
"""Topics read as survey stations, the first the file has."""
STATION_COLUMNS = ("md", "inc", "azi")
CHUNK_BYTES = 512 << 10
"""Bytes of messages after which a chunk is closed: a chunk holds one or two messages, so
the library's chunk buffer and chunk record (a message more than this) stay below the
allocator's mmap threshold (:data:`~pipeline.streams.MMAP_THRESHOLD`, 1 MiB) and reuse
glibc's heap; in 4 MiB chunks every chunk's buffers were mapped and faulted in afresh, and
a continuous well's full-rate series (5.8 MB) took 12 ms to write, now 6 (its floor, the
batches serialized, CRC'd twice and written: 5 ms; the messages are now CRC'd once,
:mod:`~pipeline.io.mcap.crc`). Read back, one-message chunks cost a
few per cent more than large ones (:data:`pipeline.io.mcap.arrow.CHUNK_BYTES`)."""


def write_tables(
    tables: Mapping[str, Port], path: Path, well: WellMetadata, provenance: Provenance
) -> None:
    """Write each table on the topic ``/gyropipe/<role>`` of one MCAP file; a stream (the
    full-rate series) is written batch by batch as it is read, in one pass (a second, the
    file written again with the stream's messages logged at 0, only when a batch's
    ``time`` column turns out to have a null or a value not finite)."""
    for table in tables.values():
        check_encodable(table.schema)
    times = {role: _times(table) for role, table in tables.items()}
    while True:
        try:
            return _write(tables, times, path, well, provenance)
        except UnstampedBatch as exc:
            times[exc.topic.removeprefix(TOPIC_PREFIX)] = None


def _write(
    tables: Mapping[str, Port],
    times: Mapping[str, np.ndarray | bool | None],
    path: Path,
    well: WellMetadata,
    provenance: Provenance,
) -> None:
    """:func:`write_tables` with each table's message ``times`` (:func:`_times`)."""
    path.unlink(missing_ok=True)  # a new inode: tables still mapping an old file stay valid
    with path.open("wb") as fh:
        section = DataSection(fh)
        writer = start_writer(section, CHUNK_BYTES)
        for role, table in tables.items():
            add_arrow_channel(
                writer,
                TOPIC_PREFIX + role,
                f"gyropipe.{role}",
                table if isinstance(table, pa.Table) else iter(table),
                table.schema,
                times[role],
            )
        writer.add_metadata(WELL_RECORD, well_strings(well))
        for role, table in tables.items():
            writer.add_metadata(f"{UNITS_RECORD}/{role}", units_of(for_client(table.schema)))
        writer.add_metadata(
            RUN_RECORD,
            {
                "pipeline": provenance.pipeline,
                "pipeline_sha256": provenance.pipeline_sha256,
                "started": provenance.started.isoformat(),
                "gyropipe": provenance.gyropipe,
            },
        )
        writer.finish()  # type: ignore[no-untyped-call]
        section.seal()


def _times(table: Port) -> np.ndarray | bool | None:
    """The ``time`` column (s) when it can stamp messages: float64, complete, finite (for a
    stream ``True``: each batch stamps its messages, checked as it is written)."""
    if "time" not in table.column_names or table.schema.field("time").type != pa.float64():
        return None
    if isinstance(table, pa.Table):
        column = table.column("time")
        times: np.ndarray = column.to_numpy(zero_copy_only=False)
        return times if column.null_count == 0 and np.isfinite(times).all() else None
    return True


def read_tables(path: Path) -> tuple[dict[str, pa.Table], WellMetadata]:
    """The processed tables of a file :func:`write_tables` wrote, by role, and its well
    metadata; problems are :class:`~pipeline.errors.InputFileError` naming the record."""
    file = scan(path)
    tables = {
        channel.topic[len(TOPIC_PREFIX) :]: arrow_batches(
            file, channel, arrow_schema(file, channel)
        )
        for channel in processed_channels(file)
    }
    if not tables:
        raise file.fail("no processed-table channel (/gyropipe/<role>) in the file")
    return tables, read_well(file)


def processed_channels(file: McapFile) -> list[Channel]:
    """The file's processed-table channels (``/gyropipe/<role>``, Arrow record batches)."""
    return [
        channel
        for channel in file.channels.values()
        if channel.topic.startswith(TOPIC_PREFIX)
        and channel.topic != SAMPLES_TOPIC
        and channel.message_encoding == ARROW_MESSAGE_ENCODING
    ]


def read_stations(path: Path, topics: list[str] | None) -> tuple[pa.Table, WellMetadata]:
    """The survey stations of a processed-tables file: the table of the one topic of
    ``topics``, else of the first of :data:`STATION_TOPICS` the file has, as written.
    A file without such a topic is a :class:`~pipeline.errors.WrongKindError` (raw
    samples say so); a topic without md, inc and azi an InputFileError naming it."""
    file = scan(path)
    channels = {c.topic: c for c in processed_channels(file)}
    if topics is not None:
        if len(topics) != 1 or topics[0] not in channels:
            raise file.fail(
                f"option topics: name one processed-table topic to read as stations, not "
                f"{topics} (topics: {sorted(channels)})"
            )
        wanted = topics
    else:
        wanted = [t for t in STATION_TOPICS if t in channels]
    if not wanted:
        samples = any(c.topic == SAMPLES_TOPIC for c in file.channels.values())
        raise WrongKindError(
            path,
            f"no survey stations topic ({' or '.join(STATION_TOPICS)}); topics: "
            f"{sorted(c.topic for c in file.channels.values())}",
            found="samples" if samples else None,
        )
    channel = channels[wanted[0]]
    table = arrow_batches(file, channel, arrow_schema(file, channel))
    missing = [c for c in STATION_COLUMNS if c not in table.column_names]
    if missing:
        raise file.fail(f"topic {channel.topic!r} is no survey: it has no column {missing}")
    return table, read_well(file)

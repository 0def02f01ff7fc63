"""Built-in MCAP plugin: raw sensor streams (kind ``samples``) in and out of MCAP files,
and a run's processed tables read back as survey stations (kind ``stations``).

**Writer** ``mcap``: gyropipe's own batched, columnar layout — Arrow IPC record batches on
``/gyropipe/samples``, station/position events on ``/gyropipe/markers``, well metadata and
column units in metadata records, uncompressed chunks with CRCs
(:mod:`pipeline.io.mcap.arrow`; the data section's CRC carried over each chunk's messages
from the chunk's own: :mod:`pipeline.io.mcap.crc`). Time series only: other tables are
refused. Through the ``export`` stage it writes several processed tables, each on its own
topic (:mod:`pipeline.io.mcap.tables`).

**Reader** ``mcap`` (kind ``samples``; files starting with the MCAP magic
``\\x89MCAP0\\r\\n``; options: :mod:`pipeline.io.mcap.options`):

* gyropipe's channel → the table exactly as written (bit-for-bit values, nulls, units,
  schema metadata, markers), fast: columns are views of the file's bytes read once;
* otherwise the readable channels — per-sample JSON, ROS 2 ``sensor_msgs`` Imu and
  MagneticField, protobuf with its schema — decoded (:mod:`pipeline.io.mcap.keyed`,
  :mod:`pipeline.io.mcap.sources`), converted to canonical units and conventions and
  joined on the base channel's times.

**Stream** (:func:`stream_samples`): the same table as record batches, one per message of
gyropipe's channel — zero-copy views of the file's bytes (read once into memory, not
mapped: a file cut short while it is read is an error, not a SIGBUS); the other channels
are decoded whole first.

Kind ``stations``: the trajectory (else the stations) a run's ``export`` wrote, as written
(:func:`pipeline.io.mcap.tables.read_stations`; the option ``topics`` names another topic,
the other options are for samples).

Well metadata comes from the ``gyropipe.well`` metadata record. Every CRC the file carries
is checked first (:mod:`pipeline.io.mcap.records`); every problem raises
:class:`~pipeline.errors.InputFileError` naming the file and the record or message.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pyarrow as pa
from mcap.records import Channel

from pipeline.errors import InputFileError, WrongKindError
from pipeline.hookspecs import hookimpl
from pipeline.io.mcap import sources
from pipeline.io.mcap.arrow import (
    ARROW_MESSAGE_ENCODING,
    ARROW_SCHEMA_ENCODING,
    MARKERS_TOPIC,
    SAMPLES_TOPIC,
    read_batches,
    read_well,
    write_samples,
)
from pipeline.io.mcap.options import SAMPLE_COLUMNS, McapOptions
from pipeline.io.mcap.records import MAGIC, McapFile, scan
from pipeline.io.mcap.tables import processed_channels, read_stations, write_tables
from pipeline.registry import ReaderDef, WriterDef
from pipeline.streams import TableStream
from pipeline.tables import RawSamples, Stations
from pipeline.well import WellMetadata

# ---------------------------------------------------------------------------- reader


def sniff(path: Path) -> bool:
    """By content: the file starts with the MCAP magic bytes."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(MAGIC)) == MAGIC
    except OSError:
        return False


def read_mcap(path: Path, kind: str, options: McapOptions) -> tuple[pa.Table, WellMetadata]:
    """The ``samples`` or ``stations`` of an MCAP file (module docstring), its well metadata."""
    if kind != "stations":
        return read_samples(path, kind, options)
    given = options.model_dump(exclude_defaults=True, exclude={"topics"})
    if given:
        raise InputFileError(path, f"options {sorted(given)} are for samples, not stations")
    return read_stations(path, options.topics)


def read_samples(path: Path, kind: str, options: McapOptions) -> tuple[pa.Table, WellMetadata]:
    """Raw samples of an MCAP file (see the module docstring) and its well metadata."""
    file = scan(path)
    well = read_well(file)
    selected = _selected(file, options)
    if any(c.topic == SAMPLES_TOPIC for c in selected):
        if len(selected) > 1:
            others = [c.topic for c in selected if c.topic != SAMPLES_TOPIC]
            raise file.fail(f"read {SAMPLES_TOPIC} alone, not with {others}")
        table = read_batches(file, selected[0])
    else:
        table = _read_sources(file, selected, options)
    return table, well


def stream_samples(path: Path, kind: str, options: McapOptions) -> tuple[TableStream, WellMetadata]:
    """:func:`read_mcap` as a stream of its record batches (module docstring)."""
    table, well = read_mcap(path, kind, options)
    return TableStream(table.schema, lambda: iter(table.to_batches())), well


def _selected(file: McapFile, options: McapOptions) -> list[Channel]:
    channels = list(file.channels.values())
    if not channels:
        raise file.fail("the file has no channels (no messages)")
    if options.topics is None:
        own = [c for c in channels if c.topic == SAMPLES_TOPIC]
        chosen = own or [
            c
            for c in channels
            if c.topic != MARKERS_TOPIC
            and sources.readable(c, file.schemas.get(c.schema_id)) is None
        ]
        if not chosen:
            found = ", ".join(f"{c.topic} ({c.message_encoding})" for c in channels)
            message = f"no channel readable as samples; channels: {found}"
            if processed_channels(file):  # a run's processed tables
                raise WrongKindError(file.path, message, found="stations")
            raise file.fail(message)
        return chosen
    by_topic = {c.topic: c for c in channels}
    missing = [t for t in options.topics if t not in by_topic]
    if missing:
        raise file.fail(f"no topics {missing} in the file (topics: {sorted(by_topic)})")
    chosen = [by_topic[t] for t in options.topics]
    for channel in chosen:
        reason = sources.readable(channel, file.schemas.get(channel.schema_id))
        if channel.topic != SAMPLES_TOPIC and reason is not None:
            raise file.fail(f"topic {channel.topic!r}: {reason}")
    return chosen


def _read_sources(file: McapFile, channels: list[Channel], options: McapOptions) -> pa.Table:
    decoded = []
    for channel in channels:
        try:
            decoded.append(
                sources.decode(file, channel, file.schemas.get(channel.schema_id), options)
            )
        except ValueError as exc:  # conventions that need a whole triad
            raise file.fail(f"topic {channel.topic!r}: {exc}") from None
    columns, origin = sources.join(file.path, decoded, options.join)
    ordered = {name: columns[name] for name in SAMPLE_COLUMNS if name in columns}
    table = RawSamples.compiled().make_table(ordered)
    if origin is None:
        return table
    return table.replace_schema_metadata({sources.TIME_ORIGIN_KEY: str(origin).encode()})


# ---------------------------------------------------------------------------- hooks


@hookimpl
def gyropipe_register_readers(register: Callable[[ReaderDef], None]) -> None:
    register(
        ReaderDef(
            name="mcap",
            description="raw sensor samples from MCAP: gyropipe's Arrow channel, per-sample "
            "JSON, ROS 2 Imu/MagneticField or protobuf; a run's processed trajectory or "
            "stations as survey stations",
            kinds={"samples": RawSamples, "stations": Stations},
            read=read_mcap,
            sniff=sniff,
            options=McapOptions,
            stream=stream_samples,
        )
    )


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="mcap",
            description="time series (raw samples) as MCAP: Arrow record batches, station and "
            "position markers, well metadata records; with the export stage, processed tables "
            "(trajectory, stations, series, QC…) each on its own topic",
            extension="mcap",
            write=write_samples,
            write_tables=write_tables,
            tables_streamed=True,
        )
    )


__all__ = [
    "ARROW_MESSAGE_ENCODING",
    "ARROW_SCHEMA_ENCODING",
    "MARKERS_TOPIC",
    "SAMPLES_TOPIC",
    "McapOptions",
    "read_mcap",
    "read_samples",
    "sniff",
    "write_samples",
]

"""MCAP reader hardening (fuzz findings): a message whose payload is cut short (container
and CRCs intact) is a located error, not a traceback; every message-level error names the
message's index, log time and topic. Test files are made with the mcap writer."""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from test_mcap import (
    UNITS,
    WRITER,
    flat_messages,
    gyropipe_file,
    imu_values,
    read,
    write_json,
    write_ros,
)

from pipeline.errors import InputFileError
from pipeline.io.mcap.arrow import (
    ARROW_MESSAGE_ENCODING,
    ARROW_SCHEMA_ENCODING,
    MARKERS_KEY,
    SAMPLES_SCHEMA,
    SAMPLES_TOPIC,
    start_writer,
)
from pipeline.plugins import load_registry
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli

Mutate = Callable[[int, str, bytes], bytes]


def samples_file(
    path: Path,
    cut: Callable[[bytes], bytes],
    rows: int = 30_000,
    schema_bytes: Callable[[bytes], bytes] = bytes,
) -> None:
    """gyropipe's own layout, 10,000-row batches logged at 0, 100, 200 s…, the payload of
    message 1 passed through ``cut`` and the serialized Arrow schema of the schema record
    through ``schema_bytes`` (the writer computes the CRCs of what it is given)."""
    rng = np.random.default_rng(1)
    columns = {"time": np.arange(rows) * 0.01}
    columns |= {c: rng.normal(size=rows) for c in ("gyro_x", "acc_x", "acc_y", "acc_z")}
    table = RawSamples.compiled().make_table(columns)
    with path.open("wb") as fh:
        writer = start_writer(fh)
        schema = table.schema.with_metadata({MARKERS_KEY: b"[]"})
        schema_id = writer.register_schema(
            SAMPLES_SCHEMA, ARROW_SCHEMA_ENCODING, schema_bytes(schema.serialize().to_pybytes())
        )
        channel = writer.register_channel(SAMPLES_TOPIC, ARROW_MESSAGE_ENCODING, schema_id)
        for i, batch in enumerate(table.to_batches(max_chunksize=10_000)):
            data = batch.serialize().to_pybytes()
            stamp = i * 100 * 10**9
            writer.add_message(channel, stamp, cut(data) if i == 1 else data, stamp, i)
        writer.finish()


def rewritten(source: Path, target: Path, mutate: Mutate) -> None:
    """``source`` copied message by message (uncompressed, fresh CRCs), each payload
    passed through ``mutate(index in its topic, topic, data)``."""
    with source.open("rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert summary is not None
        messages = list(reader.iter_messages())
        metadata = list(reader.iter_metadata())
    with target.open("wb") as out:
        writer = Writer(out, compression=CompressionType.NONE)
        writer.start()
        schemas = {
            sid: writer.register_schema(s.name, s.encoding, s.data)
            for sid, s in summary.schemas.items()
        }
        channels = {
            cid: writer.register_channel(
                c.topic, c.message_encoding, schemas.get(c.schema_id, 0), c.metadata
            )
            for cid, c in summary.channels.items()
        }
        seen: dict[str, int] = {}
        for _, channel, message in messages:
            index = seen.get(channel.topic, 0)
            seen[channel.topic] = index + 1
            data = mutate(index, channel.topic, message.data)
            writer.add_message(
                channels[channel.id], message.log_time, data, message.publish_time, message.sequence
            )
        for record in metadata:
            writer.add_metadata(record.name, record.metadata)
        writer.finish()


def test_a_payload_cut_short_is_a_located_error_through_convert(tmp_path: Path):
    """Was ``OSError: Expected to be able to read 560000 bytes for message body, got
    186378``, without saying where."""
    path = tmp_path / "cut.mcap"
    samples_file(path, lambda data: data[: len(data) // 3])
    out = tmp_path / "out.parquet"
    result = gyropipe_cli("convert", str(path), str(out), "--kind", "samples")
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    assert (
        f"{path}: message 1 (log time 100 s, topic /gyropipe/samples; chunk at byte"
    ) in result.stderr
    assert "bad Arrow batch: Expected to be able to read" in result.stderr
    assert not out.exists()


@pytest.mark.parametrize(
    "cut",
    [lambda d: b"", lambda d: d[:7], lambda d: d[: len(d) - 1]],
    ids=["empty", "7-bytes", "one-short"],
)
def test_any_cut_of_an_arrow_payload_is_located(tmp_path: Path, cut: Callable[[bytes], bytes]):
    path = tmp_path / "cut.mcap"
    samples_file(path, cut)
    with pytest.raises(InputFileError, match="bad Arrow batch") as info:
        read(path)
    assert "message 1 (log time 100 s, topic /gyropipe/samples;" in str(info.value)


def test_json_ros_and_marker_errors_name_index_log_time_and_topic(tmp_path: Path):
    json_path = tmp_path / "json.mcap"
    write_json(json_path, flat_messages(imu_values(50)))
    bad = tmp_path / "bad.mcap"
    rewritten(json_path, bad, lambda i, topic, data: data[:5] if i == 12 else data)
    with pytest.raises(InputFileError) as info:
        read(bad, **UNITS)
    assert "message 12 (log time 1700000000.12 s, topic /imu; chunk at byte" in str(info.value)
    assert "not valid JSON" in str(info.value)

    ros_path = tmp_path / "ros.mcap"
    write_ros(ros_path, 20)
    rewritten(
        ros_path, bad, lambda i, topic, data: data[:10] if (i, topic) == (3, "/mag") else data
    )
    with pytest.raises(InputFileError) as info:
        read(bad)
    assert "message 3 (log time 1763700000.060000777 s, topic /mag;" in str(info.value)
    assert "bad CDR" in str(info.value)

    own, _ = gyropipe_file(tmp_path, rows=4000)
    marked = tmp_path / "marked.mcap"
    rewritten(
        own,
        marked,
        lambda i, topic, data: b"{}" if (i, topic) == (1, "/gyropipe/markers") else data,
    )
    with pytest.raises(InputFileError) as info:
        read(marked)
    assert "message 1 (log time " in str(info.value) and "topic /gyropipe/markers;" in str(
        info.value
    )


def test_every_payload_cut_of_every_channel_kind_is_a_located_error(tmp_path: Path):
    """A small sweep: each message of each kind of channel cut to a third (CRCs intact)."""
    own, _ = gyropipe_file(tmp_path, rows=25_000)
    json_path = tmp_path / "json.mcap"
    write_json(json_path, flat_messages(imu_values(8)))
    ros_path = tmp_path / "ros.mcap"
    write_ros(ros_path, 6)
    bad = tmp_path / "bad.mcap"
    failures = []
    for source, options, count in ((own, {}, 3), (json_path, UNITS, 8), (ros_path, {}, 6)):
        for target in range(count):
            rewritten(
                source,
                bad,
                lambda i, topic, data, target=target: (
                    data[: len(data) // 3] if i == target else data
                ),
            )
            with pytest.raises(InputFileError) as info:
                read(bad, **options)
            if f"message {target} (log time " not in str(info.value):
                failures.append(str(info.value))
    assert failures == []


def test_an_arrow_table_with_a_cut_payload_is_refused_by_the_arrow_reader():
    """The exception pyarrow raises for a cut payload is an OSError (the reader maps it)."""
    batch = pa.record_batch({"x": np.arange(100.0)})
    data = batch.serialize().to_pybytes()
    with pytest.raises(OSError, match="Expected to be able to read"):
        pa.ipc.read_record_batch(pa.py_buffer(data[: len(data) // 2]), batch.schema)


SCHEMA_RECORD = "topic /gyropipe/samples, schema record 1 ('gyropipe.samples')"


@pytest.mark.parametrize(
    ("schema_bytes", "problem"),
    [
        (  # was OSError out of pyarrow, a traceback
            lambda d: d[:4] + b"\0" + d[5:],
            "unreadable Arrow schema: Invalid flatbuffers message.",
        ),
        (  # was a UnicodeDecodeError when the names were asked for (a ReaderError, no place)
            lambda d: d.replace(b"gyro_x", b"gyro\xffx"),
            "column 2 of the Arrow schema: its name is not UTF-8 text (invalid start byte)",
        ),
    ],
    ids=["flatbuffer", "column-name"],
)
def test_a_corrupt_arrow_schema_record_is_located(
    tmp_path: Path, schema_bytes: Callable[[bytes], bytes], problem: str
):
    """Fuzz findings: the schema record changed, the file's CRCs intact."""
    path = tmp_path / "schema.mcap"
    samples_file(path, bytes, rows=100, schema_bytes=schema_bytes)
    with pytest.raises(InputFileError) as info:
        load_registry().read(path, "samples")
    assert str(info.value) == f"{path}: {SCHEMA_RECORD}: {problem}"


def test_unit_metadata_that_is_not_text_is_a_contract_violation_through_convert(
    tmp_path: Path,
):
    """Fuzz finding: the contract check decoded the unit of the embedded Arrow schema and
    ended in a UnicodeDecodeError (a traceback out of ``gyropipe convert``)."""
    path = tmp_path / "unit.mcap"
    samples_file(path, bytes, rows=100, schema_bytes=lambda d: d.replace(b"m/s2", b"m/s\xb2", 1))
    out = tmp_path / "out.csv"
    result = gyropipe_cli("convert", str(path), str(out), "--kind", "samples")
    assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
    assert result.stderr.splitlines() == [
        f"error: {path}: not valid as samples (reader 'mcap'): column 'acc_z': unit: expected "
        "unit 'm/s2' in field metadata, got 'm/s\ufffd'"
    ]
    assert not out.exists()


@pytest.mark.parametrize(
    ("key", "value", "problem"),
    [
        ("row", 2**64, f"event row {2**64} is not a sample index (an integer from 0)"),
        ("time", 10**400, "event time 1000"),
        ("time", float("inf"), "event time inf is not a finite number of seconds"),
        ("station", 2**70, f"event station {2**70} is not an int64 or null"),
    ],
    ids=["row", "time-int", "time-inf", "station"],
)
def test_a_marker_event_number_past_int64_or_float64_is_located(
    tmp_path: Path, key: str, value: float, problem: str
):
    """Fuzz finding: a marker event's row, time or station past int64/float64 (CRCs intact)
    was an OverflowError building the marker columns."""
    own, _ = gyropipe_file(tmp_path, rows=4000)
    marked = tmp_path / "marked.mcap"

    def change(i: int, topic: str, data: bytes) -> bytes:
        if (i, topic) != (1, "/gyropipe/markers"):
            return data
        return json.dumps(json.loads(data) | {key: value}).encode()

    rewritten(own, marked, change)
    with pytest.raises(InputFileError) as info:
        load_registry().read(marked, "samples")
    text = str(info.value)
    assert text.startswith(f"{marked}: message 1 (log time "), text
    assert "topic /gyropipe/markers;" in text and problem in text, text


def test_a_time_past_the_log_time_range_is_written_without_a_warning(tmp_path: Path):
    """Fuzz finding: a sample time of 1e300 s made NumPy warn of an overflow (and failed
    converting it to a log time); the log time is clamped, the exact time is in the batch."""
    table = RawSamples.compiled().make_table(
        {c: [0.0, 1.0] for c in ("gyro_x", "acc_x", "acc_y", "acc_z")} | {"time": [1e300, 2e300]}
    )
    path = tmp_path / "far.mcap"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        WRITER.write(table, path, WellMetadata())
        back, _ = read(path)
    assert back.column("time").to_pylist() == [1e300, 2e300]
    with path.open("rb") as fh:
        stamps = [m.log_time for _, _, m in make_reader(fh).iter_messages()]
    assert stamps == [2**64 - 1]  # one batch, logged at its first sample: clamped


def test_a_json_value_scaled_past_the_largest_double_is_refused_without_a_warning(
    tmp_path: Path,
):
    """Fuzz finding (seed 1212, as in LAS): a per-sample JSON acceleration of -1e308 g made
    NumPy warn of an overflow scaling it to m/s²; it is refused as not finite, naming it."""
    messages = flat_messages(imu_values(6) / [1, 1, 1, 9.80665, 9.80665, 9.80665])
    messages[3]["gz"] = -1e308
    path = tmp_path / "json.mcap"
    write_json(path, messages)
    units = {"columns": {"time": "t"}, "units": {"gyro": "deg/h", "acc": "g", "time": "s"}}
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (NumPy's "overflow encountered in multiply")
        with pytest.raises(InputFileError, match=r"json.mcap.*acc_z.*finite"):
            load_registry().read(path, "samples", reader="mcap", options=units)

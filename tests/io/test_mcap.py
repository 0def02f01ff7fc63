"""MCAP plugin: gyropipe's batched channel round trip, per-sample JSON, ROS 2 Imu and
MagneticField, protobuf, bad input and fuzzing. Every test file is made with a writer."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from pydantic import ValidationError

from pipeline.errors import InputFileError, UnitError
from pipeline.io import mcap as plugin
from pipeline.io.conventions import Conventions
from pipeline.io.mcap import arrow as mcap_arrow
from pipeline.io.mcap import keyed as mcap_keyed
from pipeline.io.mcap.options import McapOptions
from pipeline.registry import ReaderDef, WriterDef
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.tables import RawSamples, Stations
from pipeline.well import WellMetadata

SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "elevation": 120.0,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
WELL = WellMetadata(
    well="W-7",
    uwi="300-12",
    latitude=61.25,
    longitude=73.4,
    elevation=82.125,
    survey_date="2026-11-21",
    tool_type="mems-vrg",
    tool_serial="SN 0042",
    north_reference="true",
)
RAD_S = 180 / np.pi * 3600  # rad/s → deg/h
MAGNETOMETER = {"magnetometer": {"noise_density": 5.0}}


def readers() -> dict[str, ReaderDef]:
    found: list[ReaderDef] = []
    plugin.gyropipe_register_readers(register=found.append)
    return {r.name: r for r in found}


def writers() -> dict[str, WriterDef]:
    found: list[WriterDef] = []
    plugin.gyropipe_register_writers(register=found.append)
    return {w.name: w for w in found}


READER = readers()["mcap"]
WRITER = writers()["mcap"]


def read(path: Path, **options: Any) -> tuple[pa.Table, WellMetadata]:
    return READER.read(path, "samples", READER.options.model_validate(options))


def simulated(preset: str, overrides: dict[str, Any] | None = None) -> pa.Table:
    spec = SimulationSpec.model_validate(
        {
            "name": "mcap",
            "seed": 11,
            "site": SITE,
            "well": {
                "sections": [
                    {"kind": "vertical", "length": 20},
                    {"kind": "curve", "dls": 30.0, "inc": 35, "azi": 40},
                ]
            },
            "tool": {"preset": preset, "overrides": overrides or {}},
            "survey": {"mode": "point", "every": 25, "dwell": 2.0, "move_time": 1.0, "speed": 5},
        }
    )
    return simulate(spec).samples


@pytest.fixture(scope="module", params=["ideal", "mems-vrg", "mems-vrg+mag"])
def samples(request: pytest.FixtureRequest) -> pa.Table:
    preset, _, mag = request.param.partition("+")
    return simulated(preset, MAGNETOMETER if mag else None)


def same_bits(a: pa.Table, b: pa.Table) -> None:
    assert a.equals(b, check_metadata=True)
    for name in a.column_names:
        x, y = a.column(name), b.column(name)
        assert x.null_count == y.null_count
        assert np.array_equal(x.is_null().to_numpy(), y.is_null().to_numpy())
        if pa.types.is_floating(x.type):
            bits = [c.fill_null(0).to_numpy().view(np.uint64) for c in (x, y)]
            assert np.array_equal(*bits), name


# ----------------------------------------------------------------------- round trip


def test_registered_through_hooks() -> None:
    assert READER.kinds == {"samples": RawSamples, "stations": Stations}
    assert WRITER.extension == "mcap"


def test_simulated_samples_round_trip_exactly(samples: pa.Table, tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    WRITER.write(samples, path, WELL)
    assert READER.sniff(path)
    table, well = read(path)
    same_bits(table, samples)
    assert well == WELL
    RawSamples.validate_table(table)
    assert ("mag_x" in table.column_names) == ("mag_x" in samples.column_names)


def test_file_layout_is_valid_mcap(samples: pa.Table, tmp_path: Path) -> None:
    """The library reader (CRCs checked) sees the documented channels and records."""
    path = tmp_path / "run.mcap"
    WRITER.write(samples, path, WELL)
    with path.open("rb") as fh:
        reader = make_reader(fh, validate_crcs=True)
        messages = list(reader.iter_messages())
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        summary = reader.get_summary()
    assert summary is not None
    assert {c.topic for c in summary.channels.values()} == {
        plugin.SAMPLES_TOPIC,
        "/gyropipe/markers",
    }
    batches = [(c, m) for _, c, m in messages if c.topic == plugin.SAMPLES_TOPIC]
    schema = pa.ipc.read_schema(pa.py_buffer(summary.schemas[batches[0][0].schema_id].data))
    first = pa.ipc.read_record_batch(
        pa.py_buffer(batches[0][1].data),
        schema.remove(schema.get_field_index("position")).remove(schema.get_field_index("station")),
    )
    assert "station" not in first.schema.names  # markers are not duplicated in the batches
    assert batches[0][1].log_time == round(samples["time"][0].as_py() * 1e9)
    events = [json.loads(m.data) for _, c, m in messages if c.topic == plugin.MARKERS_TOPIC]
    assert events[0] == {
        "row": 0,
        "time": samples["time"][0].as_py(),
        "station": samples["station"][0].as_py(),
        "position": samples["position"][0].as_py(),
    }
    assert 1 < len(events) < samples.num_rows / 10
    assert metadata["gyropipe.well"]["survey_date"] == "2026-11-21"
    assert metadata["gyropipe.well"]["elevation"] == "82.125"
    assert metadata["gyropipe.units"]["gyro_x"] == "deg/h"
    assert metadata["gyropipe.units"]["station"] == ""


def test_many_batches_and_empty_tables(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    samples = simulated("ideal")
    monkeypatch.setattr(mcap_arrow, "BATCH_ROWS", 700)
    monkeypatch.setattr(mcap_arrow, "CHUNK_BYTES", 50_000)
    path = tmp_path / "many.mcap"
    WRITER.write(samples, path, WellMetadata())
    table, well = read(path)
    same_bits(table, samples)
    assert well == WellMetadata()
    assert table.column("time").num_chunks == -(-samples.num_rows // 700)
    empty = samples.slice(0, 0)
    WRITER.write(empty, path, WELL)
    table, _ = read(path)
    assert table.num_rows == 0
    assert table.schema.equals(empty.schema, check_metadata=True)


def test_any_time_series_round_trips(tmp_path: Path) -> None:
    """Extra columns, marker columns in another order and type, no well metadata."""
    table = pa.table(
        {
            "position": pa.array([None, 1, 1, 2], pa.int32()),
            "time": [0.5, 1.5, 2.5, 3.5],
            "note": ["a", None, "c", "d"],
            "station": pa.array([7, 7, None, None], pa.int64()),
        }
    )
    path = tmp_path / "any.mcap"
    WRITER.write(table, path, WellMetadata())
    got, well = read(path)
    same_bits(got, table.replace_schema_metadata({}))
    assert well == WellMetadata()


def test_writer_refuses_tables_that_are_not_time_series(tmp_path: Path) -> None:
    stations = Stations.compiled().make_table(
        {"md": [0.0, 30.0], "inc": [0.0, 1.0], "azi": [0, 2.0]}
    )
    with pytest.raises(ValueError, match="time series"):
        WRITER.write(stations, tmp_path / "s.mcap", WELL)
    backwards = pa.table({"time": [0.0, 2.0, 1.0], "gyro_x": [1.0, 2.0, 3.0]})
    with pytest.raises(ValueError, match="strictly increasing"):
        WRITER.write(backwards, tmp_path / "b.mcap", WELL)
    coded = pa.table({"time": [0.0, 1.0], "tag": pa.array(["a", "b"]).dictionary_encode()})
    with pytest.raises(ValueError, match="dictionary"):
        WRITER.write(coded, tmp_path / "d.mcap", WELL)


# -------------------------------------------------------------------- per-sample JSON


def write_json(
    path: Path,
    messages: list[Any],
    *,
    topic: str = "/imu",
    metadata: dict[str, str] | None = None,
    schema: dict[str, Any] | None = None,
    rate: float = 100.0,
    extra: tuple[str, list[Any]] | None = None,
) -> None:
    with path.open("wb") as fh:
        writer = Writer(fh, chunk_size=64 * 1024)
        writer.start()
        schema_id = (
            writer.register_schema("Sample", "jsonschema", json.dumps(schema).encode())
            if schema
            else 0
        )
        channel = writer.register_channel(topic, "json", schema_id, metadata or {})
        other = writer.register_channel(extra[0], "json", 0) if extra else 0
        for i, message in enumerate(messages):
            stamp = 1_700_000_000_000_000_000 + round(i * 1e9 / rate)
            data = message if isinstance(message, bytes) else json.dumps(message).encode()
            writer.add_message(channel, stamp, data, stamp, i)
            if extra and i < len(extra[1]):
                writer.add_message(other, stamp, json.dumps(extra[1][i]).encode(), stamp, i)
        writer.finish()


def imu_values(n: int, seed: int = 5) -> np.ndarray:
    return np.random.default_rng(seed).normal(size=(n, 6)) * [10, 10, 10, 0.5, 0.5, 9.8]


def flat_messages(values: np.ndarray) -> list[dict[str, float]]:
    keys = ("wx", "wy", "wz", "gx", "gy", "gz")
    return [
        {"t": i * 0.01, **dict(zip(keys, row.tolist(), strict=True))}
        for i, row in enumerate(values)
    ]


def test_json_samples_with_units_declared_in_the_options(tmp_path: Path) -> None:
    values = imu_values(5000)
    path = tmp_path / "json.mcap"
    write_json(path, flat_messages(values))
    assert READER.sniff(path)
    table, well = read(
        path, columns={"time": "t"}, units={"gyro": "deg/s", "acc": "g", "time": "s"}
    )
    assert well == WellMetadata()
    assert table.num_rows == 5000
    np.testing.assert_array_equal(table["time"].to_numpy(), np.arange(5000) * 0.01)
    np.testing.assert_allclose(table["gyro_y"].to_numpy(), values[:, 1] * 3600, rtol=1e-15)
    np.testing.assert_allclose(table["acc_z"].to_numpy(), values[:, 5] * 9.80665, rtol=1e-15)
    RawSamples.validate_table(table)


def test_json_bulk_and_message_by_message_paths_agree(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    values = imu_values(300)
    path = tmp_path / "json.mcap"
    write_json(path, flat_messages(values))
    options = {"columns": {"time": "t"}, "units": {"gyro": "deg/h", "acc": "m/s2", "time": "s"}}
    bulk, _ = read(path, **options)
    monkeypatch.setattr(mcap_keyed, "_parse_bulk", lambda messages, schema: None)
    slow, _ = read(path, **options)
    same_bits(bulk, slow)
    np.testing.assert_array_equal(bulk["gyro_x"].to_numpy(), values[:, 0])


def test_json_nested_triads_units_from_channel_metadata_and_log_time(tmp_path: Path) -> None:
    values = imu_values(400)
    messages = [
        {"gyro": row[:3].tolist(), "acc": {"x": row[3], "y": row[4], "z": row[5]}, "seq": i}
        for i, row in enumerate(values)
    ]
    units = json.dumps({"gyro": "rad/s", "acc": "m/s2"})
    path = tmp_path / "nested.mcap"
    write_json(path, messages, metadata={"units": units}, rate=200.0)
    table, _ = read(path, ignore=["seq"])
    np.testing.assert_allclose(table["gyro_z"].to_numpy(), values[:, 2] * RAD_S, rtol=1e-15)
    np.testing.assert_array_equal(table["acc_x"].to_numpy(), values[:, 3])
    np.testing.assert_allclose(table["time"].to_numpy(), np.arange(400) / 200.0, atol=1e-9)
    assert table.schema.metadata[b"gyropipe.time_origin_ns"] == b"1700000000000000000"


def test_json_units_from_the_json_schema_and_conventions(tmp_path: Path) -> None:
    values = imu_values(50)
    schema = {
        "type": "object",
        "properties": {
            k: {"type": "number", "unit": u}
            for k, u in [
                ("wx", "deg/h"),
                ("wy", "deg/h"),
                ("wz", "deg/h"),
                ("gx", "m/s2"),
                ("gy", "m/s2"),
                ("gz", "m/s2"),
            ]
        }
        | {"t": {"type": "number", "unit": "s"}},
    }
    path = tmp_path / "schema.mcap"
    write_json(path, flat_messages(values), schema=schema)
    conventions = {"axes": ["y", "-x", "z"], "accelerometer": "specific_force"}
    table, _ = read(path, columns={"time": "t"}, conventions=conventions)
    np.testing.assert_array_equal(table["gyro_x"].to_numpy(), values[:, 1])
    np.testing.assert_array_equal(table["gyro_y"].to_numpy(), -values[:, 0])
    np.testing.assert_array_equal(table["acc_y"].to_numpy(), values[:, 3])
    np.testing.assert_array_equal(table["acc_z"].to_numpy(), -values[:, 5])


UNITS = {"columns": {"time": "t"}, "units": {"gyro": "deg/h", "acc": "m/s2", "time": "s"}}


@pytest.mark.parametrize(
    ("change", "options", "expected"),
    [
        (lambda m: m.pop("gy"), UNITS, r"message 1234 .*missing \['gy'\]"),
        (lambda m: m.update(temp=40.0), UNITS, r"message 1234 .*extra \['temp'\]"),
        (lambda m: m.update(gy="9.8"), UNITS, r"message 1234 .*'gy' is '9.8', not a number"),
        (lambda m: m.update(gy=[1, 2]), UNITS, r"message 1234 .*keys differ"),
        (lambda m: m.update(gy=None), UNITS, r"message 1234 .*'gy' is None"),
        (lambda m: m.update(gy=10**400), UNITS, r"'gy' has a number too large"),
        (
            lambda m: None,
            {"columns": {"time": "t"}, "units": {"time": "s"}},
            r"no unit for key 'wx' \(gyro_x\).*option units",
        ),
        (
            lambda m: None,
            {"units": UNITS["units"]},
            r"key 't' names no raw-samples column.*columns",
        ),
        (lambda m: None, {**UNITS, "units": {"gyro": "deg/h", "acc": "m/s2", "time": "h"}}, None),
    ],
)
def test_bad_json_messages_are_named(tmp_path: Path, change, options, expected) -> None:
    messages: list[Any] = flat_messages(imu_values(2000))
    change(messages[1234])
    path = tmp_path / "bad.mcap"
    write_json(path, messages)
    if expected is None:  # a legal unit: times in hours
        table, _ = read(path, **options)
        assert table["time"][1].as_py() == pytest.approx(36.0)
        return
    with pytest.raises(InputFileError, match=expected) as info:
        read(path, **options)
    assert str(path) in str(info.value)


def test_invalid_json_payloads_and_extra_topics(tmp_path: Path) -> None:
    messages: list[Any] = flat_messages(imu_values(100))
    messages[7] = b'{"t": 0.07, "wx": 1.0,'
    path = tmp_path / "broken.mcap"
    write_json(path, messages)
    with pytest.raises(InputFileError, match=r"message 7 .*not valid JSON"):
        read(path, **UNITS)
    messages[7] = b"[1, 2, 3]"
    write_json(path, messages)
    with pytest.raises(InputFileError, match=r"message 0 .*expected an object|message 7"):
        read(path, **UNITS)


def test_nested_json_errors_are_found_by_the_message_by_message_pass(tmp_path: Path) -> None:
    messages = [{"gyro": [1.0, 2.0, 3.0], "acc": {"x": 0.0, "y": 0.0, "z": 9.8}}] * 30
    messages = [dict(m) for m in messages]
    messages[17] = {"gyro": [1.0, None, 3.0], "acc": {"x": 0.0, "y": 0.0, "z": 9.8}}
    messages[25] = {"gyro": [1.0, 2.0, 3.0], "acc": {"x": 0.0, "y": 0.0}}
    path = tmp_path / "nested.mcap"
    write_json(path, messages)
    with pytest.raises(InputFileError, match=r"message 17 .*'gyro\[1\]' is None"):
        read(path, units={"gyro": "deg/h", "acc": "m/s2"})
    messages[17] = messages[0]
    write_json(path, messages)
    with pytest.raises(InputFileError, match=r"message 25 .*missing \['acc.z'\]"):
        read(path, units={"gyro": "deg/h", "acc": "m/s2"})


def test_station_keys_are_integers(tmp_path: Path) -> None:
    messages = [m | {"station": 3} for m in flat_messages(imu_values(20))]
    messages[4]["station"] = 3.5
    path = tmp_path / "station.mcap"
    write_json(path, messages)
    with pytest.raises(
        InputFileError,
        match=r"message 4 \(log time 1700000000.04 s, topic /imu; .*\): key 'station' is 3.5",
    ):
        read(path, **UNITS)


# ------------------------------------------------------------------------------- ROS 2

VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
HEADER = (
    "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
    + "=" * 80
    + "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
)
SEP = "=" * 80 + "\n"
IMU_MSGDEF = (
    "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n"
    "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n"
    + SEP
    + HEADER
    + SEP
    + "MSG: geometry_msgs/Quaternion\nfloat64 x\nfloat64 y\nfloat64 z\nfloat64 w\n"
    + SEP
    + VECTOR3
)
MAG_MSGDEF = (
    "std_msgs/Header header\ngeometry_msgs/Vector3 magnetic_field\n"
    "float64[9] magnetic_field_covariance\n" + SEP + HEADER + SEP + VECTOR3
)
T0 = 1_763_700_000_000_000_000


def write_ros(
    path: Path, n: int, *, mag_every: int = 2, mag_shift: int = 0, stamps: bool = True
) -> np.ndarray:
    from mcap_ros2.writer import Writer as RosWriter

    rng = np.random.default_rng(9)
    values = rng.normal(size=(n, 9)) * [1e-4] * 3 + [0, 0, 0, 0.1, 0.2, 9.8, 1e-5, 2e-5, 5e-5]
    with path.open("wb") as fh:
        writer = RosWriter(fh)
        imu = writer.register_msgdef("sensor_msgs/msg/Imu", IMU_MSGDEF)
        mag = writer.register_msgdef("sensor_msgs/msg/MagneticField", MAG_MSGDEF)
        for i, row in enumerate(values):
            t = T0 + i * 10_000_000
            stamp = (
                {"sec": t // 10**9, "nanosec": t % 10**9} if stamps else {"sec": 0, "nanosec": 0}
            )
            header = {"stamp": stamp, "frame_id": "imu_link"}
            vec = [dict(zip("xyz", row[k : k + 3].tolist(), strict=True)) for k in (0, 3, 6)]
            writer.write_message(
                "/imu",
                imu,
                {
                    "header": header,
                    "orientation": {"x": 0, "y": 0, "z": 0, "w": 1},
                    "orientation_covariance": [0.0] * 9,
                    "angular_velocity": vec[0],
                    "angular_velocity_covariance": [0.0] * 9,
                    "linear_acceleration": vec[1],
                    "linear_acceleration_covariance": [0.0] * 9,
                },
                log_time=t + 777,
            )
            if i % mag_every == 0:
                mt = t + mag_shift
                header = {
                    "stamp": {"sec": mt // 10**9, "nanosec": mt % 10**9},
                    "frame_id": "imu_link",
                }
                writer.write_message(
                    "/mag",
                    mag,
                    {
                        "header": header,
                        "magnetic_field": vec[2],
                        "magnetic_field_covariance": [0.0] * 9,
                    },
                    log_time=mt + 777,
                )
        writer.finish()
    return values


def test_ros2_imu_and_magnetic_field_are_converted_and_joined(tmp_path: Path) -> None:
    path = tmp_path / "ros.mcap"
    values = write_ros(path, 300)
    table, _ = read(path)
    np.testing.assert_array_equal(table["time"].to_numpy(), np.arange(300) * 10_000_000 / 1e9)
    np.testing.assert_allclose(table["gyro_x"].to_numpy(), values[:, 0] * RAD_S, rtol=1e-15)
    np.testing.assert_array_equal(table["acc_z"].to_numpy(), -values[:, 5])  # specific force
    mag = table["mag_y"]
    assert mag.null_count == 150
    np.testing.assert_allclose(
        mag.to_numpy(zero_copy_only=False)[::2], values[::2, 7] * 1e9, rtol=1e-15
    )
    assert table.schema.metadata[b"gyropipe.time_origin_ns"] == str(T0).encode()
    RawSamples.validate_table(table)
    imu_only, _ = read(path, topics=["/imu"], conventions={"accelerometer": "gravity"})
    np.testing.assert_array_equal(imu_only["acc_z"].to_numpy(), values[:, 5])
    assert "mag_x" not in imu_only.column_names


def test_ros2_mismatched_clocks_need_interpolation(tmp_path: Path) -> None:
    path = tmp_path / "ros.mcap"
    values = write_ros(path, 100, mag_every=4, mag_shift=3_000_000)
    with pytest.raises(
        InputFileError, match=r"25 of 25 samples of topic '/mag'.*join: interpolate"
    ):
        read(path)
    table, _ = read(path, join="interpolate")
    mag = table["mag_x"].to_numpy(zero_copy_only=False)
    assert np.isnan(mag[0]) and np.isnan(mag[-1])  # outside the magnetometer's span: null
    expected = np.interp(
        np.arange(100) * 0.01, np.arange(0, 100, 4) * 0.01 + 0.003, values[::4, 6] * 1e9
    )
    np.testing.assert_allclose(mag[1:-3], expected[1:-3], rtol=1e-12)


def test_ros2_without_stamps_uses_log_time(tmp_path: Path) -> None:
    path = tmp_path / "ros.mcap"
    write_ros(path, 10, stamps=False)
    table, _ = read(path, topics=["/imu"])
    np.testing.assert_array_equal(table["time"].to_numpy(), np.arange(10) * 10_000_000 / 1e9)


# ---------------------------------------------------------------------------- protobuf


def sample_class() -> Any:
    """A protobuf message type built at run time: Sample {Timestamp stamp; Vector3 gyro; Vector3 acc}."""
    from google.protobuf import descriptor_pb2, descriptor_pool, timestamp_pb2
    from google.protobuf.message_factory import GetMessageClass

    pool = descriptor_pool.DescriptorPool()
    pool.AddSerializedFile(timestamp_pb2.DESCRIPTOR.serialized_pb)
    proto = descriptor_pb2.FileDescriptorProto(
        name="gyropipe_test/sample.proto",
        package="gyropipe_test",
        syntax="proto3",
        dependency=["google/protobuf/timestamp.proto"],
    )
    vector = proto.message_type.add(name="Vector3")
    for number, axis in enumerate("xyz", start=1):
        vector.field.add(
            name=axis, number=number, type=descriptor_pb2.FieldDescriptorProto.TYPE_DOUBLE
        )
    sample = proto.message_type.add(name="Sample")
    message = descriptor_pb2.FieldDescriptorProto.TYPE_MESSAGE
    sample.field.add(name="stamp", number=1, type=message, type_name=".google.protobuf.Timestamp")
    sample.field.add(name="gyro", number=2, type=message, type_name=".gyropipe_test.Vector3")
    sample.field.add(name="acc", number=3, type=message, type_name=".gyropipe_test.Vector3")
    pool.Add(proto)
    return GetMessageClass(pool.FindMessageTypeByName("gyropipe_test.Sample"))


def test_protobuf_messages_with_their_schema(tmp_path: Path) -> None:
    from mcap_protobuf.writer import Writer as ProtoWriter

    sample = sample_class()
    values = imu_values(200)
    path = tmp_path / "proto.mcap"
    with path.open("wb") as fh:
        writer = ProtoWriter(fh)
        for i, row in enumerate(values):
            message = sample()
            message.stamp.FromNanoseconds(T0 + i * 5_000_000)
            message.gyro.x, message.gyro.y, message.gyro.z = row[:3]
            message.acc.x, message.acc.y, message.acc.z = row[3:]
            writer.write_message("/sample", message, log_time=i, publish_time=i)
        writer.finish()
    table, _ = read(path, units={"gyro": "deg/s", "acc": "m/s2"})
    np.testing.assert_array_equal(table["time"].to_numpy(), np.arange(200) * 5_000_000 / 1e9)
    np.testing.assert_allclose(table["gyro_y"].to_numpy(), values[:, 1] * 3600, rtol=1e-15)
    np.testing.assert_array_equal(table["acc_x"].to_numpy(), values[:, 3])


# --------------------------------------------------------------------------- bad input


def gyropipe_file(tmp_path: Path, rows: int = 400) -> tuple[Path, pa.Table]:
    table = simulated("mems-vrg").slice(600, rows)
    path = tmp_path / "small.mcap"
    WRITER.write(table, path, WELL)
    return path, read(path)[0]


def write_raw(path: Path, encoding: str, schema: tuple[str, str] | None = None) -> None:
    with path.open("wb") as fh:
        writer = Writer(fh, compression=CompressionType.NONE)
        writer.start()
        schema_id = writer.register_schema("S", schema[0], schema[1].encode()) if schema else 0
        channel = writer.register_channel("/x", encoding, schema_id)
        writer.add_message(channel, 1, b"\x01\x02", 1)
        writer.finish()


def test_bad_files_raise_input_file_errors(tmp_path: Path) -> None:
    path, _ = gyropipe_file(tmp_path)
    data = path.read_bytes()
    bad = tmp_path / "bad.mcap"
    cases: list[tuple[bytes, str]] = [
        (b"", "too short"),
        (b"PAR1" + data[4:], "no MCAP magic"),
        (data[: len(data) // 2], "truncated"),
        (data[:-3], "truncated|closing MCAP magic"),
        (data[:-8], "closing MCAP magic"),
    ]
    middle = len(data) // 2  # inside the samples chunk
    cases.append(
        (data[:middle] + bytes([data[middle] ^ 0x10]) + data[middle + 1 :], "CRC mismatch")
    )
    metadata_at = data.index(b"gyropipe.well")  # the well metadata record
    cases.append((data[: metadata_at + 20] + b"X" + data[metadata_at + 21 :], "CRC mismatch"))
    for content, message in cases:
        bad.write_bytes(content)
        with pytest.raises(InputFileError, match=message) as info:
            read(bad)
        assert str(bad) in str(info.value)
    assert not READER.sniff(tmp_path / "missing.mcap")
    with pytest.raises(InputFileError, match="cannot read"):
        read(tmp_path / "missing.mcap")


def test_chunk_crc_checked_without_a_data_section_crc(tmp_path: Path) -> None:
    path = tmp_path / "json.mcap"
    write_json(path, flat_messages(imu_values(50)))  # zstd chunks, no data-section CRC
    data = bytearray(path.read_bytes())
    at = data.index(b"zstd") + 60
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(InputFileError, match=r"chunk at byte \d+: (cannot decompress|chunk CRC)"):
        read(path, **UNITS)


@pytest.mark.parametrize(
    ("encoding", "schema", "topics", "expected"),
    [
        ("cbor", None, None, r"no channel readable as samples; channels: /x \(cbor\)"),
        ("cbor", None, ["/x"], r"topic '/x': unknown message encoding 'cbor'"),
        ("protobuf", None, ["/x"], "schema-less protobuf"),
        ("protobuf", None, None, "no channel readable"),
        ("cdr", ("ros2msg", "float64 x"), ["/x"], "ROS 2 messages of type S"),
        ("protobuf", ("protobuf", "not a descriptor"), None, "protobuf schema 'S'"),
        ("json", None, ["/y"], r"no topics \['/y'\]"),
    ],
)
def test_unreadable_channels(tmp_path: Path, encoding, schema, topics, expected) -> None:
    path = tmp_path / "x.mcap"
    write_raw(path, encoding, schema)
    with pytest.raises(InputFileError, match=expected):
        read(path, topics=topics)


def test_file_without_channels(tmp_path: Path) -> None:
    path = tmp_path / "empty.mcap"
    with path.open("wb") as fh:
        writer = Writer(fh)
        writer.start()
        writer.finish()
    with pytest.raises(InputFileError, match="no channels"):
        read(path)


def test_bad_well_metadata_names_the_record(tmp_path: Path) -> None:
    path = tmp_path / "w.mcap"
    with path.open("wb") as fh:
        writer = Writer(fh)
        writer.start()
        writer.add_metadata("gyropipe.well", {"latitude": "north"})
        writer.finish()
    with pytest.raises(InputFileError, match=r"gyropipe.well at byte \d+: latitude"):
        read(path)


def test_well_records_whose_dates_contradict_name_the_record(tmp_path: Path) -> None:
    """A later record's last day before an earlier one's survey date: the file's error, at
    the later record (was a ParameterError naming no file)."""
    path = tmp_path / "w.mcap"
    with path.open("wb") as fh:
        writer = Writer(fh)
        writer.start()
        writer.add_metadata("gyropipe.well", {"survey_date": "2026-03-05"})
        writer.add_metadata("gyropipe.well", {"survey_date_last": "2026-03-01"})
        writer.finish()
    with pytest.raises(InputFileError, match=r"gyropipe.well at byte \d+: .*survey_date_last"):
        read(path)


def test_options_are_validated() -> None:
    with pytest.raises(ValidationError, match="unknown columns"):
        McapOptions(columns={"gyro_w": "x"})
    with pytest.raises(ValidationError, match="unknown unit"):
        McapOptions(units={"gyro": "furlong"})
    with pytest.raises(ValidationError, match="not a raw-samples column"):
        McapOptions(units={"azi": "deg"})
    with pytest.raises(ValidationError):
        McapOptions(speed=3)
    assert McapOptions(conventions=Conventions(axes=("x", "-y", "-z"))).join == "exact"


# -------------------------------------------------------------------------------- fuzz


@pytest.fixture(scope="module")
def fuzz_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[bytes, Any]]:
    root = tmp_path_factory.mktemp("fuzz")
    own, table = gyropipe_file(root, rows=300)
    json_path = root / "json.mcap"
    write_json(json_path, flat_messages(imu_values(60)))
    return {
        "gyropipe": (own.read_bytes(), (table, WELL)),
        "json": (json_path.read_bytes(), read(json_path, **UNITS)),
    }


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    kind=st.sampled_from(["gyropipe", "json"]),
    cut=st.one_of(st.none(), st.floats(0, 1, exclude_max=True)),
    flips=st.lists(st.tuples(st.floats(0, 1, exclude_max=True), st.integers(1, 255)), max_size=3),
)
def test_mutated_files_raise_typed_errors_or_read_exactly(
    fuzz_files: dict[str, tuple[bytes, Any]], tmp_path: Path, kind: str, cut: float | None, flips
) -> None:
    original, (table, well) = fuzz_files[kind]
    data = bytearray(original if cut is None else original[: int(cut * len(original))])
    for where, mask in flips:
        if data:
            data[int(where * len(data))] ^= mask
    path = tmp_path / f"fuzz-{kind}.mcap"
    path.write_bytes(bytes(data))
    options = UNITS if kind == "json" else {}
    try:
        got, got_well = read(path, **options)
    except (InputFileError, UnitError):
        return
    same_bits(got, table)  # a mutation that still reads must not change a single value
    assert got_well == well

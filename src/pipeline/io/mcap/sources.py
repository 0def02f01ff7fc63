"""Foreign MCAP channels as raw samples: which channels are readable, ROS 2 decoding, and
the join of several channels on one time base.

Each channel becomes a :class:`~pipeline.io.mcap.keyed.Source`: its sample times (integer
ns from the message log time or a ROS header stamp, or seconds from a time key) and
canonical columns in canonical units (°/h, m/s², nT, m, deg; station/position integers),
converted to the canonical conventions with the option ``conventions``.

**ROS 2**: ``sensor_msgs/msg/Imu`` (angular velocity rad/s, linear acceleration m/s² as
specific force per REP 145, so by default the accelerometers are negated to the gravity
convention) and ``sensor_msgs/msg/MagneticField`` (tesla), ``ros2msg`` schemas decoded with
mcap-ros2-support; time is ``header.stamp``, or the log time when every stamp is zero.
JSON and protobuf: see :mod:`pipeline.io.mcap.keyed`.

**Join** (several channels): the base is the channel with gyro columns (else the one with
the most samples); its times are the table's. With ``join: exact`` (default) another
channel's sample lands on the base sample with the very same time and its columns are null
elsewhere (a lower-rate magnetometer sharing the IMU clock); a sample that matches no base
time is an error. With ``join: interpolate`` the other channel's columns are interpolated
linearly at the base times within its time span and null outside it. Times in ns are made
relative to the base's first sample (kept in the schema metadata as
``gyropipe.time_origin_ns``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from mcap.records import Channel, Schema

from pipeline.errors import InputFileError
from pipeline.io.conventions import Conventions, to_canonical
from pipeline.io.mcap import keyed
from pipeline.io.mcap.keyed import Source
from pipeline.io.mcap.options import McapOptions
from pipeline.io.mcap.records import McapFile, Messages, iter_payloads, messages_of
from pipeline.units import conversion_factor

IMU = "sensor_msgs/msg/Imu"
MAGNETIC_FIELD = "sensor_msgs/msg/MagneticField"
ROS_TYPES = (IMU, MAGNETIC_FIELD)
ROS_SPECIFIC_FORCE = Conventions(accelerometer="specific_force")
"""Conventions of a ROS Imu when the user declares none (REP 145: specific force)."""
TIME_ORIGIN_KEY = b"gyropipe.time_origin_ns"
"""Schema metadata: the sample-time origin (ns) of a table timed by stamps or log times."""


def readable(channel: Channel, schema: Schema | None) -> str | None:
    """Why a channel cannot be read as samples, or None if it can."""
    encoding = channel.message_encoding
    if encoding == "json":
        return None
    if encoding == "cdr":
        name = schema.name if schema else "no schema"
        if schema is not None and schema.encoding == "ros2msg" and name in ROS_TYPES:
            return None
        return f"ROS 2 messages of type {name} (readable: {', '.join(ROS_TYPES)} as ros2msg)"
    if encoding == "protobuf":
        if schema is None or schema.encoding != "protobuf":
            return "schema-less protobuf: the file must carry the FileDescriptorSet schema"
        return None
    return f"unknown message encoding {encoding!r} (readable: json, cdr, protobuf)"


def decode(file: McapFile, channel: Channel, schema: Schema | None, options: McapOptions) -> Source:
    """A readable channel (see :func:`readable`) as a :class:`Source` in its conventions."""
    messages = messages_of(file, channel.id)
    where = f"topic {channel.topic!r}"
    if not messages:
        raise file.fail(f"{where} has no messages")
    if channel.message_encoding == "cdr":
        assert schema is not None
        source = _ros(file, channel, schema, messages)
        conventions = options.conventions or (ROS_SPECIFIC_FORCE if schema.name == IMU else None)
    else:
        if channel.message_encoding == "json":
            leaves = keyed.json_leaves(file, where, messages, options)
        else:
            assert schema is not None
            leaves = keyed.checked_leaves(
                file, where, keyed.protobuf_rows(file, schema, messages), options
            )
        source = keyed.mapped(file, channel, schema, messages, leaves, options)
        conventions = options.conventions
    if conventions is None:
        return source
    table = to_canonical(pa.table(source.columns), conventions)
    source.columns = {name: table.column(name).to_numpy() for name in table.column_names}
    return source


# -------------------------------------------------------------------------------- ROS 2


def _ros(file: McapFile, channel: Channel, schema: Schema, messages: Messages) -> Source:
    """Imu (rad/s → °/h; m/s² specific force, negated later by the conventions) or
    MagneticField (T → nT) messages; time from header.stamp (log time if all zero)."""
    from mcap_ros2.decoder import DecoderFactory

    where = f"topic {channel.topic!r}"
    try:
        decoder = DecoderFactory().decoder_for("cdr", schema)
    except Exception as exc:  # the schema parser raises assorted errors on bad text
        raise file.fail(f"{where}: cannot parse ROS 2 schema {schema.name!r}: {exc}") from None
    assert decoder is not None
    imu = schema.name == IMU
    fields = ("angular_velocity", "linear_acceleration") if imu else ("magnetic_field",)
    stamps, log_times, rows = [], [], []
    for data, log_time, located in iter_payloads(messages):
        try:
            message = decoder(data)
            stamp = message.header.stamp
            stamps.append(int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec))
            vectors = [getattr(message, name) for name in fields]
            rows.append([float(getattr(v, axis)) for v in vectors for axis in "xyz"])
        except Exception as exc:  # CDR decoding of a corrupt payload raises assorted errors
            raise file.fail(f"{located}: bad CDR: {exc}") from None
        log_times.append(log_time)
    values = np.array(rows, dtype=np.float64)
    time = np.array(stamps if any(stamps) else log_times, dtype=np.int64)
    if imu:
        rate = conversion_factor("rad/s", "angular_rate")
        names = [f"{t}_{a}" for t in ("gyro", "acc") for a in "xyz"]
        factors = [rate] * 3 + [1.0] * 3
    else:
        names = [f"mag_{a}" for a in "xyz"]
        factors = [conversion_factor("tesla", "magnetic_field")] * 3
    columns = {n: values[:, i] * f for i, (n, f) in enumerate(zip(names, factors, strict=True))}
    return Source(channel.topic, True, time, columns)


# ---------------------------------------------------------------------------------- join


def join(path: Path, sources: list[Source], how: str) -> tuple[dict[str, Any], int | None]:
    """Columns of the joined table (``time`` in s first) and the time origin in ns (None
    when the times were given in seconds). See the module docstring for the rule."""
    base = max(sources, key=lambda s: (any(n.startswith("gyro") for n in s.columns), len(s.time)))
    if len({s.in_ns for s in sources}) > 1:
        raise InputFileError(
            path, "some topics are timed in ns (log time/stamps), others by a time key in s"
        )
    seen: dict[str, str] = {}
    for source in sources:
        for name in source.columns:
            if name in seen:
                raise InputFileError(
                    path,
                    f"column {name} comes from topics {seen[name]!r} and {source.topic!r}; "
                    "choose topics with the option topics",
                )
            seen[name] = source.topic
    _sort(base)
    origin = int(base.time[0]) if base.in_ns else None
    base_time = _relative(base.time, origin)
    columns: dict[str, Any] = {"time": base_time, **base.columns}
    for source in sources:
        if source is not base:
            _sort(source)
            columns.update(_joined(path, base, source, base_time, origin, how))
    return columns, origin


def _sort(source: Source) -> None:
    order = np.argsort(source.time, kind="stable")
    if np.any(order != np.arange(len(order))):
        source.time = source.time[order]
        source.columns = {n: v[order] for n, v in source.columns.items()}


def _relative(time: np.ndarray, origin: int | None) -> np.ndarray:
    if origin is None:
        return time
    seconds: np.ndarray = (time - origin) / 1e9
    return seconds


def _joined(
    path: Path, base: Source, other: Source, base_time: np.ndarray, origin: int | None, how: str
) -> dict[str, pa.Array]:
    times = _relative(other.time, origin)
    if how == "interpolate":
        inside = (base_time >= times[0]) & (base_time <= times[-1])
        return {
            n: pa.array(np.interp(base_time, times, v), mask=~inside)
            for n, v in other.columns.items()
        }
    at = np.searchsorted(base.time, other.time)
    hit = at < len(base.time)
    hit[hit] = base.time[at[hit]] == other.time[hit]
    if not hit.all() or len(np.unique(at)) != len(at):
        missed = int((~hit).sum()) or len(at) - len(np.unique(at))
        shared = np.flatnonzero(np.diff(at) == 0) + 1
        first = int(np.flatnonzero(~hit)[0]) if not hit.all() else int(shared[0])
        raise InputFileError(
            path,
            f"{missed} of {len(at)} samples of topic {other.topic!r} have no sample of "
            f"{base.topic!r} at the same time (or share one), the first at time "
            f"{float(times[first])!r} s; set the option join: interpolate to interpolate them "
            "at its times",
        )
    present = np.zeros(len(base.time), dtype=bool)
    present[at] = True
    joined = {}
    for name, values in other.columns.items():
        full = np.zeros(len(base.time), dtype=values.dtype)
        full[at] = values
        joined[name] = pa.array(full, mask=~present)
    return joined

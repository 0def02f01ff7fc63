"""Keyed messages — per-sample JSON objects and protobuf messages — as canonical columns.

**JSON** (message encoding ``json``): one sample per message, an object of numbers. Nested
objects are flattened with dots (``{"gyro": {"x": 1}}`` → ``gyro.x``) and arrays get
indices (``{"gyro": [1, 2, 3]}`` → ``gyro[0]``…); a key maps to its canonical column by
the option ``columns`` or the mnemonic tables (``gyro[0]`` maps as ``gyro x``, and
``gyro.x`` as ``gyrox``). Every message must have exactly the first message's keys, all
numbers; keys to skip are listed in ``ignore``. The messages are decoded in bulk: the
payloads are gathered with NumPy into one newline-delimited buffer (raw newlines inside a
payload can only be whitespace in valid JSON and become spaces) and parsed by
``pyarrow.json``; on any anomaly a message-by-message pass finds and names the bad message.

**Protobuf**: messages whose channel has a ``protobuf`` schema (a FileDescriptorSet),
decoded with mcap-protobuf-support and flattened like JSON; a ``google.protobuf.Timestamp``
field is a time key in ns (it needs no unit).

Units: the option ``units`` (canonical column or triad), else the channel metadata
``units`` (a JSON object key → unit; a triad's parent key such as ``gyro`` covers its
elements), else a JSON schema's ``unit`` keyword on the property. Time: a key mapped to
``time`` (in its declared unit), else the message log time in ns.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.json as pajson
from mcap.records import Channel, Schema

from pipeline import jsontext
from pipeline.errors import UnitError
from pipeline.io.mcap.options import SAMPLE_COLUMNS, McapOptions
from pipeline.io.mcap.records import (
    MESSAGE_HEAD,
    McapFile,
    Messages,
    count,
    describe,
    iter_payloads,
)
from pipeline.io.mnemonics import CURVES, canonical_name
from pipeline.io.numbers import scaled
from pipeline.io.threads import reader_threads
from pipeline.units import conversion_factor

INTEGER_COLUMNS = ("station", "position")


class Nanoseconds(int):
    """A protobuf Timestamp flattened to integer ns (a time key that needs no unit)."""


@dataclass
class Source:
    """One channel's samples: ``time`` int64 ns if ``in_ns`` else float64 s; canonical
    columns in canonical units (float64; station/position int64)."""

    topic: str
    in_ns: bool
    time: np.ndarray
    columns: dict[str, np.ndarray] = field(default_factory=dict)


# ------------------------------------------------------------------------------- JSON


def json_leaves(
    file: McapFile, where: str, messages: Messages, options: McapOptions
) -> dict[str, np.ndarray]:
    """Numeric leaves of the JSON messages by flattened key: in bulk when the messages are
    regular, else message by message (which names the first bad message)."""
    block, rows = messages[0]
    try:
        first = jsontext.loads(block.payload(int(rows[0])).tobytes())
    except ValueError:
        first = None
    schema = _arrow_schema(first, options.ignore) if isinstance(first, dict) else None
    if schema is not None:
        table = _parse_bulk(messages, schema)
        if table is not None:
            leaves = _bulk_leaves(table, _flatten(first), options.ignore)
            if leaves is not None:
                return leaves
    return checked_leaves(file, where, _json_rows(messages), options)


def _arrow_schema(first: dict[str, Any], ignore: list[str]) -> pa.Schema | None:
    """Arrow schema of the first message's numeric structure (objects → structs, arrays of
    numbers → lists); None when it is not all numbers (the slow path explains why)."""

    def arrow_type(value: Any, key: str) -> pa.DataType | None:
        if isinstance(value, dict):
            fields = [(k, arrow_type(v, f"{key}.{k}")) for k, v in value.items()]
            kept = [pa.field(k, t) for k, t in fields if t is not None]
            return pa.struct(kept) if kept else None
        if _ignored(key, ignore):
            return None
        if isinstance(value, list) and value and all(_is_number(v) for v in value):
            return pa.list_(pa.float64())
        if _is_number(value):
            return pa.float64()
        raise TypeError(key)

    try:
        types = [(k, arrow_type(v, k)) for k, v in first.items()]
    except TypeError:
        return None
    return pa.schema([pa.field(k, t) for k, t in types if t is not None])


def _parse_bulk(messages: Messages, schema: pa.Schema) -> pa.Table | None:
    """All payloads as one newline-delimited buffer parsed by pyarrow.json; None if that
    fails or the row count differs from the message count."""
    parts = []
    for block, rows in messages:
        start = block.payload_start(rows)
        end = start + block.size[rows] - MESSAGE_HEAD
        bounds = np.zeros(2 * len(rows) + 2, dtype=np.int64)
        bounds[1:-1:2], bounds[2:-1:2], bounds[-1] = start, end, len(block.data)
        inside = np.zeros(len(bounds) - 1, dtype=bool)
        inside[1::2] = True  # runs: outside, payload, outside, payload, …, outside
        payload = block.data[np.repeat(inside, np.diff(bounds))]
        payload[(payload == 10) | (payload == 13)] = 32
        parts.append(np.insert(payload, np.cumsum(end - start), 10))
    text = np.concatenate(parts)
    try:
        table = pajson.read_json(
            pa.BufferReader(pa.py_buffer(text)),
            read_options=pajson.ReadOptions(use_threads=reader_threads() > 1, block_size=1 << 24),
            parse_options=pajson.ParseOptions(
                explicit_schema=schema, unexpected_field_behavior="infer"
            ),
        )
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        return None
    return table if table.num_rows == count(messages) else None


def _bulk_leaves(
    table: pa.Table, first: dict[str, Any], ignore: list[str]
) -> dict[str, np.ndarray] | None:
    """Flattened float64 leaves of the bulk table; None unless every message had exactly
    the first message's keys (no nulls, no extra keys, arrays of the same length) and
    every value is finite."""
    while any(pa.types.is_struct(f.type) for f in table.schema):
        table = table.flatten()
    leaves: dict[str, np.ndarray] = {}
    expected = {k for k in first if not _ignored(k, ignore)}
    for name, column in zip(table.column_names, table.columns, strict=True):
        if _ignored(name, ignore):
            continue
        if column.null_count or not (
            pa.types.is_floating(column.type) or pa.types.is_list(column.type)
        ):
            return None
        if pa.types.is_list(column.type):
            width = sum(1 for k in first if k.startswith(f"{name}["))
            lengths = pc.list_value_length(column)
            if pc.min(lengths).as_py() != width or pc.max(lengths).as_py() != width:
                return None
            flat = pc.list_flatten(column)
            if flat.null_count:
                return None
            values = flat.to_numpy().reshape(-1, width)
            leaves.update({f"{name}[{i}]": values[:, i].copy() for i in range(width)})
        else:
            leaves[name] = column.to_numpy()
    if set(leaves) != expected or not all(np.isfinite(v).all() for v in leaves.values()):
        return None  # the message-by-message pass decides (NaN, huge integers)
    return leaves


def _json_rows(messages: Messages) -> Iterator[tuple[Any, int, str]]:
    for data, log_time, where in iter_payloads(messages):
        try:
            yield jsontext.loads(data), log_time, where
        except ValueError as exc:
            yield _Invalid(f"not valid JSON: {exc}"), log_time, where


@dataclass(frozen=True)
class _Invalid:
    reason: str


# ---------------------------------------------------------------------- message by message


def checked_leaves(
    file: McapFile, where: str, rows: Iterator[tuple[Any, int, str]], options: McapOptions
) -> dict[str, np.ndarray]:
    """Numeric leaves of decoded messages, checked message by message: each must be an
    object with exactly the first message's keys, every value a number."""
    keys: list[str] | None = None
    values: list[list[float]] = []
    places: list[str] = []
    for message, _, at in rows:
        places.append(at)
        if isinstance(message, _Invalid):
            raise file.fail(f"{at}: {message.reason}")
        if not isinstance(message, dict):
            raise file.fail(f"{at}: expected an object of numbers, got {type(message).__name__}")
        flat = {k: v for k, v in _flatten(message).items() if not _ignored(k, options.ignore)}
        if keys is None:
            keys = list(flat)
        elif flat.keys() != set(keys):
            missing = sorted(set(keys) - flat.keys())
            extra = sorted(flat.keys() - set(keys))
            raise file.fail(
                f"{at}: keys differ from the first message's"
                + (f"; missing {missing}" if missing else "")
                + (f"; extra {extra} (skip keys with the option ignore)" if extra else "")
            )
        bad = [k for k in keys if not _is_number(flat[k])]
        if bad:
            raise file.fail(
                f"{at}: key {bad[0]!r} is {flat[bad[0]]!r}, not a number "
                f"(skip keys with the option ignore)"
            )
        values.append([flat[k] for k in keys])
    if keys is None:
        raise file.fail(f"{where} has no messages")
    if not keys:
        raise file.fail(f"{where}: the messages have no numeric keys")
    array = np.array(values, dtype=object)
    leaves = {}
    for i, key in enumerate(keys):
        try:
            leaves[key] = _numbers(array[:, i])
        except OverflowError:
            row = next(j for j, v in enumerate(array[:, i]) if _too_large(v))
            raise file.fail(
                f"{places[row]}: key {key!r} has a number too large for float64"
            ) from None
    return leaves


def _too_large(value: Any) -> bool:
    try:
        float(value)
    except OverflowError:
        return True
    return False


def _numbers(column: np.ndarray) -> np.ndarray:
    if all(isinstance(v, Nanoseconds) for v in column):
        return column.astype(np.int64)
    return column.astype(np.float64)


def _flatten(value: Any, key: str = "", out: dict[str, Any] | None = None) -> dict[str, Any]:
    """Leaves of nested objects/arrays by dotted/indexed key (``a.b``, ``a[0]``)."""
    out = {} if out is None else out
    if isinstance(value, dict):
        for k, v in value.items():
            _flatten(v, f"{key}.{k}" if key else str(k), out)
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _flatten(v, f"{key}[{i}]", out)
    else:
        out[key] = value
    return out


def _is_number(value: Any) -> bool:
    return type(value) in (int, float, Nanoseconds)


def _ignored(key: str, ignore: list[str]) -> bool:
    return any(key == i or key.startswith((f"{i}.", f"{i}[")) for i in ignore)


# ------------------------------------------------------------------- keys → canonical


def mapped(
    file: McapFile,
    channel: Channel,
    schema: Schema | None,
    messages: Messages,
    leaves: dict[str, np.ndarray],
    options: McapOptions,
) -> Source:
    """Leaves mapped to canonical columns and converted to canonical units."""
    where = f"topic {channel.topic!r}"
    chosen = {key: canonical for canonical, key in options.columns.items()}
    targets: dict[str, str] = {}
    for key, values in leaves.items():
        canonical = chosen.get(key) or _auto_name(key, values)
        if canonical is None:
            raise file.fail(
                f"{where}: key {key!r} names no raw-samples column; map it with the option "
                f"columns (e.g. columns: {{gyro_x: {key!r}}}) or skip it with ignore: [{key!r}]"
            )
        if canonical in targets.values():
            other = next(k for k, c in targets.items() if c == canonical)
            raise file.fail(
                f"{where}: keys {other!r} and {key!r} both give {canonical}; choose one with "
                f"the option columns or skip one with ignore"
            )
        targets[key] = canonical
    units = _declared_units(file, channel, schema)
    columns: dict[str, np.ndarray] = {}
    for key, canonical in targets.items():
        values = leaves[key]
        quantity = CURVES[canonical].quantity
        if canonical in INTEGER_COLUMNS:
            columns[canonical] = _integers(file, messages, key, values)
        elif canonical == "time" and values.dtype == np.int64:  # protobuf Timestamp: ns
            columns[canonical] = values
        else:
            assert quantity is not None
            unit = _unit(options, units, key, canonical)
            if unit is None:
                raise file.fail(
                    f"{where}: no unit for key {key!r} ({canonical}): declare it with the "
                    f"option units (e.g. units: {{{canonical}: ...}}) or in the channel "
                    f"metadata 'units' (a JSON object key → unit)"
                )
            try:
                columns[canonical] = scaled(values, conversion_factor(unit, quantity))
            except UnitError as exc:
                raise file.fail(f"{where}, key {key!r}: {exc}") from None
    time = columns.pop("time", None)
    if time is None:
        time = np.concatenate([block.log_time[rows] for block, rows in messages])
    return Source(channel.topic, time.dtype == np.int64, time, columns)


def _auto_name(key: str, values: np.ndarray) -> str | None:
    if values.dtype == np.int64:
        return "time"
    name = canonical_name(key)
    if name is None and key.endswith(("[0]", "[1]", "[2]")):
        name = canonical_name(key[:-3] + "xyz"[int(key[-2])])
    return name if name in SAMPLE_COLUMNS else None


def _integers(file: McapFile, messages: Messages, key: str, values: np.ndarray) -> np.ndarray:
    """``values`` (one per message) as integers; a fraction names its message."""
    integral = (np.abs(values) < 2.0**63) & (values == np.round(values))
    if not integral.all():
        row = int(np.flatnonzero(~integral)[0])
        raise file.fail(
            f"{describe(messages, row)}: key {key!r} is {float(values[row])!r}, not an integer"
        )
    ints: np.ndarray = values.astype(np.int64)
    return ints


def _unit(options: McapOptions, units: dict[str, str], key: str, canonical: str) -> str | None:
    triad = canonical.split("_")[0]
    parent = key.rsplit(".", 1)[0] if "." in key else key.split("[")[0]
    for table, name in (
        (options.units, canonical),
        (options.units, triad),
        (units, key),
        (units, parent),
        (units, canonical),
    ):
        if name in table:
            return table[name]
    return None


def _declared_units(file: McapFile, channel: Channel, schema: Schema | None) -> dict[str, str]:
    """Units by key from the channel metadata ``units`` (JSON object) and a JSON schema's
    ``unit`` keywords (the channel metadata wins)."""
    units: dict[str, str] = {}
    if schema is not None and schema.encoding == "jsonschema":
        try:
            _schema_units(jsontext.loads(schema.data), "", units)
        except (ValueError, AttributeError, TypeError) as exc:
            why = f": {exc}" if isinstance(exc, jsontext.TooDeep) else ""
            raise file.fail(
                f"topic {channel.topic!r}: schema {schema.name!r} is not a JSON schema{why}"
            ) from None
    raw = channel.metadata.get("units")
    if raw is not None:
        try:
            declared = jsontext.loads(raw)
            if not isinstance(declared, dict) or not all(
                isinstance(v, str) for v in declared.values()
            ):
                raise ValueError("not an object of strings")
        except ValueError as exc:
            raise file.fail(
                f"topic {channel.topic!r}: channel metadata 'units' must be a JSON object "
                f"key → unit: {exc}"
            ) from None
        units.update(declared)
    return units


def _schema_units(node: dict[str, Any], prefix: str, units: dict[str, str]) -> None:
    for name, prop in node.get("properties", {}).items():
        key = f"{prefix}.{name}" if prefix else name
        if isinstance(prop.get("unit"), str):
            units[key] = prop["unit"]
        _schema_units(prop, key, units)


# ----------------------------------------------------------------------------- protobuf


def protobuf_rows(
    file: McapFile, schema: Schema, messages: Messages
) -> Iterator[tuple[Any, int, str]]:
    from mcap_protobuf.decoder import DecoderFactory

    try:
        decoder = DecoderFactory().decoder_for("protobuf", schema)
    except Exception as exc:  # descriptor parsing raises assorted errors on a bad schema
        raise file.fail(f"cannot load protobuf schema {schema.name!r}: {exc}") from None
    assert decoder is not None
    for data, log_time, located in iter_payloads(messages):
        try:
            yield _proto_dict(decoder(data)), log_time, located
        except Exception as exc:  # protobuf raises DecodeError and others on bad payloads
            yield _Invalid(f"bad protobuf payload: {exc}"), log_time, located


def _proto_dict(message: Any) -> dict[str, Any]:
    """A protobuf message as nested dicts/lists (Timestamps as :class:`Nanoseconds`)."""
    out: dict[str, Any] = {}
    for fd in message.DESCRIPTOR.fields:
        value = getattr(message, fd.name)
        if fd.message_type is None:
            out[fd.name] = list(value) if fd.is_repeated else value
        else:
            out[fd.name] = (
                [_proto_value(v) for v in value] if fd.is_repeated else _proto_value(value)
            )
    return out


def _proto_value(message: Any) -> Any:
    if message.DESCRIPTOR.full_name == "google.protobuf.Timestamp":
        return Nanoseconds(message.seconds * 1_000_000_000 + message.nanos)
    return _proto_dict(message)

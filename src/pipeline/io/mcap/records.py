"""Low-level MCAP scanning for the MCAP reader: records, CRCs, chunks and message positions.

The file is read into memory and walked record by record (``opcode u8, length u64, body``)
without the mcap library's per-message Python objects: messages are located by one tight
loop per chunk and their channel ids and log times gathered with NumPy, so later stages
can decode a channel's payloads in bulk (zero-copy views of those bytes for uncompressed
chunks). Read, not mapped: a mapped file cut short while its views are in use kills the
process with SIGBUS; the copy costs ~0.15 s CPU per 170 MB and no more peak memory (the
mapped pages counted in the RSS as well).

Bounds: a compressed chunk's declared size is charged to a budget of :data:`MAX_INFLATION`
times the file's size before it is decompressed, and it is decompressed into that many bytes
at most (a chunk claiming 6 GiB in a 197 kB file is refused at once).

Integrity: every CRC the file carries is checked before anything is decoded — the data
section CRC (DataEnd record) when non-zero, which covers every data-section byte; otherwise
each chunk's uncompressed CRC; and the summary CRC in the footer. A file whose chunks carry
no CRC (CRC 0) cannot be checked: Arrow IPC and CDR payloads have no checksum of their own.
Every problem raises :class:`~pipeline.errors.InputFileError` naming the byte offset.
"""

from __future__ import annotations

import importlib
import struct
import zlib
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from mcap.records import Channel, Schema

from pipeline.errors import InputFileError

MAGIC = b"\x89MCAP0\r\n"
HEADER, FOOTER, SCHEMA, CHANNEL, MESSAGE, CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
METADATA, DATA_END = 0x0C, 0x0F
MESSAGE_HEAD = 22
"""Bytes of a Message record body before its data: channel u16, sequence u32, log and
publish time u64."""
FOOTER_BODY = 20
MAX_INFLATION = 100
"""Compressed chunks may hold at most this many times the file's size in records (sensor
data compresses ~1.5×, per-sample JSON ~10×; a chunk of zeros claiming gigabytes, far more)."""
MIN_DECOMPRESSED = 64 << 20
"""The budget of decompressed bytes of a small file (bytes)."""

_OP_LEN = struct.Struct("<BQ")
_CHUNK_HEAD = struct.Struct("<QQQII")
_U64 = struct.Struct("<Q")
_U32 = struct.Struct("<I")
_FOOTER = struct.Struct("<QQI")


@dataclass
class Block:
    """Messages inside one run of records (a chunk's records, or the data section of an
    unchunked file): ``data`` holds the records; ``pos`` the offset of each Message record
    (its opcode byte) in ``data``, ``size`` its body length, ``channel`` and ``log_time``
    (ns) its header fields."""

    data: np.ndarray
    where: str
    pos: np.ndarray
    size: np.ndarray
    channel: np.ndarray
    log_time: np.ndarray
    channels: dict[int, Channel] = field(default_factory=dict)
    """the file's channels by id (for the topic of a message)"""

    def payload_start(self, rows: np.ndarray) -> np.ndarray:
        """Offsets in ``data`` of the message data of messages ``rows``."""
        start: np.ndarray = self.pos[rows] + 9 + MESSAGE_HEAD
        return start

    def payload(self, row: int) -> np.ndarray:
        """Message data of message ``row`` (a view of ``data``)."""
        start = int(self.pos[row]) + 9 + MESSAGE_HEAD
        view: np.ndarray = self.data[start : start + int(self.size[row]) - MESSAGE_HEAD]
        return view

    def locate(self, row: int) -> str:
        """Where message ``row`` is in the file, for error messages."""
        return f"{self.where}, record at offset {int(self.pos[row])}"

    def describe(self, row: int, index: int) -> str:
        """Message ``row``, the ``index``-th of its channel, for error messages: its index,
        log time, topic and place in the file."""
        channel = self.channels.get(int(self.channel[row]))
        topic = channel.topic if channel is not None else f"channel {int(self.channel[row])}"
        seconds = _seconds(int(self.log_time[row]))
        return f"message {index} (log time {seconds} s, topic {topic}; {self.locate(row)})"


def _seconds(ns: int) -> str:
    """Integer ns as exact decimal seconds: ``1.25``, ``100``, ``1763700000.060000777``."""
    whole, frac = divmod(ns, 1_000_000_000)
    return f"{whole}.{frac:09d}".rstrip("0").rstrip(".")


Messages = list[tuple[Block, np.ndarray]]
"""A channel's messages: per block, the rows of its messages."""


@dataclass
class McapFile:
    """What the scan found: schemas and channels by id, metadata records (name, entries,
    file offset) and the message blocks in file order."""

    path: Path
    size: int = 0
    """bytes in the file"""
    decompressed: int = 0
    """declared bytes of the compressed chunks seen so far (:func:`_charge`)"""
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    metadata: list[tuple[str, dict[str, str], int]] = field(default_factory=list)
    blocks: list[Block] = field(default_factory=list)

    def fail(self, message: str) -> InputFileError:
        return InputFileError(self.path, message)


def scan(path: Path) -> McapFile:
    """Read ``path``, check its structure and CRCs, and locate every message."""
    data = np.frombuffer(_read_whole(path), dtype=np.uint8)
    if bytes(data[:8]) != MAGIC:
        raise InputFileError(path, "not an MCAP file: no MCAP magic at byte 0")
    file = McapFile(path, len(data))
    records = _top_level(file, data)
    verified = _check_crcs(file, data, records)
    top_messages: list[int] = []
    for op, pos, length in records:
        body = data[pos + 9 : pos + 9 + length]
        if op == CHUNK:
            file.blocks.append(_chunk(file, body, pos, verified))
        elif op == MESSAGE:
            top_messages.append(pos)
        elif op in (SCHEMA, CHANNEL, METADATA):
            _definition(file, op, body, f"record at byte {pos}", pos)
    if top_messages:
        file.blocks.append(_block(file, data, "data section", np.array(top_messages)))
    return file


def _read_whole(path: Path) -> pa.Buffer:
    """The bytes of ``path``, read into memory (not mapped: the tables hand out zero-copy
    views of these bytes, and a mapped file cut short while they are in use is a SIGBUS
    that kills the process). A file whose size changes while it is read is refused."""
    try:
        with pa.OSFile(str(path)) as fh:
            size = fh.size()
            if size < 2 * len(MAGIC):
                raise InputFileError(path, f"not an MCAP file: {size} bytes, too short")
            buf = fh.read_buffer(size)
            now = fh.size()
    except OSError as exc:
        raise InputFileError(path, f"cannot read: {exc}") from None
    if len(buf) != size or now != size:
        raise InputFileError(
            path, f"the file changed while it was read ({size} bytes, then {now}; read {len(buf)})"
        )
    return buf


def _top_level(file: McapFile, data: np.ndarray) -> list[tuple[int, int, int]]:
    """(opcode, offset, body length) of every record up to the footer, which must be
    followed by the closing magic and the end of the file."""
    size = len(data)
    pos = len(MAGIC)
    records: list[tuple[int, int, int]] = []
    while True:
        if pos + 9 > size:
            raise file.fail(f"truncated: record header at byte {pos} runs past the end ({size})")
        op, length = _OP_LEN.unpack_from(data.data, pos)
        end = pos + 9 + length
        if end > size:
            raise file.fail(
                f"truncated or corrupt: record at byte {pos} (opcode 0x{op:02x}) claims "
                f"{length} bytes, the file has {size - pos - 9} after its header"
            )
        if op == HEADER and records:
            raise file.fail(f"second Header record at byte {pos}")
        if not records and op != HEADER:
            raise file.fail(f"expected a Header record at byte {pos}, got opcode 0x{op:02x}")
        records.append((op, pos, length))
        pos = end
        if op == FOOTER:
            break
    if length != FOOTER_BODY:
        raise file.fail(f"Footer record at byte {records[-1][1]} has length {length}, not 20")
    if bytes(data[pos:]) != MAGIC:
        raise file.fail(
            f"expected the closing MCAP magic and the end of the file at byte {pos} "
            f"(file size {size})"
        )
    return records


def _check_crcs(file: McapFile, data: np.ndarray, records: list[tuple[int, int, int]]) -> bool:
    """Check the data section CRC (DataEnd) and the summary CRC (Footer), when non-zero;
    True if the data section CRC covered every data-section byte."""
    ends = [(pos, length) for op, pos, length in records if op == DATA_END]
    if len(ends) != 1:
        raise file.fail(f"expected one DataEnd record, found {len(ends)}")
    end, length = ends[0]
    if length < 4:
        raise file.fail(f"DataEnd record at byte {end} is too short ({length} bytes)")
    (expected,) = _U32.unpack_from(data.data, end + 9)
    if expected and zlib.crc32(data[:end].data) != expected:
        raise file.fail(f"data section CRC mismatch (DataEnd record at byte {end}): corrupt file")
    footer = records[-1][1]
    summary_start, _, summary_crc = _FOOTER.unpack_from(data.data, footer + 9)
    start = summary_start or footer
    if summary_crc:
        if not end < start <= footer:
            raise file.fail(f"Footer at byte {footer}: summary start {summary_start} is invalid")
        if zlib.crc32(data[start : footer + 25].data) != summary_crc:
            raise file.fail(f"summary CRC mismatch (Footer at byte {footer}): corrupt file")
    return bool(expected)


def _chunk(file: McapFile, body: np.ndarray, offset: int, verified: bool) -> Block:
    """The messages of one Chunk record; its CRC is checked unless ``verified`` (the data
    section CRC already covered its bytes)."""
    where = f"chunk at byte {offset}"
    if len(body) < _CHUNK_HEAD.size:
        raise file.fail(f"{where}: record too short ({len(body)} bytes)")
    _, _, raw_size, crc, name_length = _CHUNK_HEAD.unpack_from(body.data)
    at = _CHUNK_HEAD.size + name_length
    if at + 8 > len(body):
        raise file.fail(f"{where}: compression name runs past the record")
    compression = _text(file, body[_CHUNK_HEAD.size : at], where)
    (stored,) = _U64.unpack_from(body.data, at)
    if at + 8 + stored > len(body):
        raise file.fail(f"{where}: records ({stored} bytes) run past the record")
    records = _decompress(file, body[at + 8 : at + 8 + stored], compression, raw_size, where)
    if crc and not verified and zlib.crc32(records.data) != crc:
        raise file.fail(f"{where}: chunk CRC mismatch: corrupt file")
    return _walk(file, records, where)


def _decompress(
    file: McapFile, stored: np.ndarray, compression: str, raw_size: int, where: str
) -> np.ndarray:
    """A chunk's records, decompressed into at most ``raw_size`` bytes (its declared size,
    charged to the file's budget first: :func:`_charge`), never more."""
    if compression == "":
        if len(stored) != raw_size:
            raise file.fail(f"{where}: {len(stored)} record bytes, header says {raw_size}")
        return stored
    module = {"zstd": "zstandard", "lz4": "lz4.frame"}.get(compression)
    if module is None:
        raise file.fail(f"{where}: unknown compression {compression!r} (known: zstd, lz4)")
    try:
        codec = importlib.import_module(module)
    except ImportError:
        raise file.fail(f"{where}: {compression} chunks need the package {module}") from None
    _charge(file, raw_size, where)
    try:  # one byte more than declared: a chunk that holds more is refused, not decoded
        if compression == "zstd":
            with codec.ZstdDecompressor().stream_reader(stored.data) as reader:
                raw = reader.read(raw_size + 1)
        else:
            raw = codec.LZ4FrameDecompressor().decompress(stored.data, max_length=raw_size + 1)
    except Exception as exc:  # each codec has its own error types; all mean a corrupt chunk
        raise file.fail(f"{where}: cannot decompress {compression}: {exc}") from None
    if len(raw) != raw_size:
        got = f"more than {raw_size}" if len(raw) > raw_size else str(len(raw))
        raise file.fail(f"{where}: decompressed to {got} bytes, header says {raw_size}")
    return np.frombuffer(raw, dtype=np.uint8)


def _charge(file: McapFile, raw_size: int, where: str) -> None:
    """Count a compressed chunk's declared size against the file's budget of decompressed
    bytes (:data:`MAX_INFLATION` × the file's size, at least :data:`MIN_DECOMPRESSED`),
    before anything is allocated for it."""
    budget = max(MIN_DECOMPRESSED, MAX_INFLATION * file.size)
    file.decompressed += raw_size
    if file.decompressed > budget:
        raise file.fail(
            f"{where}: declares {raw_size:,} bytes of records; the compressed chunks would "
            f"hold {file.decompressed:,} bytes, more than {budget:,} ({MAX_INFLATION} times "
            f"the file's {file.size:,} bytes, at least {MIN_DECOMPRESSED:,}): refused"
        )


def _walk(file: McapFile, records: np.ndarray, where: str) -> Block:
    """Locate the messages in a chunk's records; schemas and channels are registered."""
    size = len(records)
    pos = 0
    messages: list[int] = []
    definitions: list[tuple[int, int, int]] = []
    append = messages.append
    unpack = _OP_LEN.unpack_from
    view = records.data
    try:
        while pos < size:  # the hot loop: one unpack per record
            op, length = unpack(view, pos)
            if op == MESSAGE:
                append(pos)
            elif op in (SCHEMA, CHANNEL):
                definitions.append((op, pos, length))
            pos += 9 + length
    except struct.error:
        raise file.fail(f"{where}: truncated record at offset {pos} of its records") from None
    if pos != size:
        raise file.fail(f"{where}: the last record runs {pos - size} bytes past the chunk")
    for op, at, length in definitions:
        _definition(file, op, records[at + 9 : at + 9 + length], f"{where}, offset {at}", -1)
    return _block(file, records, where, np.array(messages, dtype=np.int64))


def _block(file: McapFile, data: np.ndarray, where: str, pos: np.ndarray) -> Block:
    """The Block of the Message records at offsets ``pos`` of ``data``."""
    size = _gather_u64(data, pos + 1)
    short = np.flatnonzero(size < MESSAGE_HEAD)
    if len(short):
        raise file.fail(f"{where}: Message record at offset {pos[short[0]]} is too short")
    channel = data[pos + 9].astype(np.uint16) | (data[pos + 10].astype(np.uint16) << 8)
    log_time = _gather_u64(data, pos + 9 + 6)
    return Block(data, where, pos, size, channel, log_time, file.channels)


def _gather_u64(data: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Little-endian u64 fields at offsets ``at`` of ``data``, as int64."""
    raw = data[at[:, None] + np.arange(8)]
    values: np.ndarray = np.ascontiguousarray(raw).view("<u8").reshape(-1).astype(np.int64)
    return values


def _definition(file: McapFile, op: int, body: np.ndarray, where: str, offset: int) -> None:
    """Parse a Schema, Channel or Metadata record body into ``file``."""
    cursor = _Cursor(body.tobytes())
    try:
        if op == METADATA:
            file.metadata.append((cursor.text(), cursor.mapping(), offset))
            return
        parsed: Schema | Channel
        if op == SCHEMA:
            parsed = Schema(
                id=cursor.int(2), name=cursor.text(), encoding=cursor.text(), data=cursor.blob()
            )
        else:
            parsed = Channel(
                id=cursor.int(2),
                schema_id=cursor.int(2),
                topic=cursor.text(),
                message_encoding=cursor.text(),
                metadata=cursor.mapping(),
            )
    except ValueError as exc:
        raise file.fail(f"{where}: malformed record (opcode 0x{op:02x}): {exc}") from None
    known: dict[int, Any] = file.schemas if isinstance(parsed, Schema) else file.channels
    if parsed.id in known and known[parsed.id] != parsed:
        kind = type(parsed).__name__
        raise file.fail(f"{where}: {kind} id {parsed.id} redefined with different content")
    known[parsed.id] = parsed


class _Cursor:
    """Reads MCAP record fields from a record body, refusing to run past its end."""

    def __init__(self, body: bytes) -> None:
        self.body = body
        self.at = 0

    def take(self, n: int) -> bytes:
        if self.at + n > len(self.body):
            raise ValueError(f"field of {n} bytes at offset {self.at} runs past the record")
        self.at += n
        return self.body[self.at - n : self.at]

    def int(self, n: int) -> int:
        return int.from_bytes(self.take(n), "little")

    def blob(self) -> bytes:
        return self.take(self.int(4))

    def text(self) -> str:
        try:
            return self.blob().decode()
        except UnicodeDecodeError:
            raise ValueError("a string field is not UTF-8") from None

    def mapping(self) -> dict[str, str]:
        end = self.int(4) + self.at
        if end > len(self.body):
            raise ValueError("map runs past the record")
        entries: dict[str, str] = {}
        while self.at < end:
            key = self.text()
            entries[key] = self.text()
        if self.at != end:
            raise ValueError("map entries overrun the map length")
        return entries


def _text(file: McapFile, raw: np.ndarray, where: str) -> str:
    try:
        return raw.tobytes().decode()
    except UnicodeDecodeError:
        raise file.fail(f"{where}: a string field is not UTF-8") from None


def messages_of(file: McapFile, channel: int) -> Messages:
    """The messages of ``channel``, block by block, in file order."""
    found = []
    for block in file.blocks:
        rows = np.flatnonzero(block.channel == channel)
        if len(rows):
            found.append((block, rows))
    return found


def count(messages: Messages) -> int:
    return sum(len(rows) for _, rows in messages)


def iter_messages(messages: Messages) -> Iterator[tuple[int, Block, int]]:
    """(index in the channel, block, row in the block) of each message."""
    index = 0
    for block, rows in messages:
        for row in rows.tolist():
            yield index, block, row
            index += 1


def describe(messages: Messages, index: int) -> str:
    """The ``index``-th message of a channel, for error messages (:meth:`Block.describe`)."""
    for block, rows in messages:
        if index < len(rows):
            return block.describe(int(rows[index]), index)
        index -= len(rows)
    raise IndexError(index)


def iter_payloads(messages: Messages) -> Iterator[tuple[bytes, int, str]]:
    """(data, log time ns, description: index, log time, topic, place) of each message."""
    for index, block, row in iter_messages(messages):
        yield block.payload(row).tobytes(), int(block.log_time[row]), block.describe(row, index)

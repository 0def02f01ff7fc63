"""The data section's CRC of a file the ``mcap`` library writes, each chunk's bytes read once.

With ``enable_data_crcs`` the library runs CRC-32 over every byte of the data section, the
chunks' messages included, which it has already run CRC-32 over for each chunk's own
``uncompressed_crc``: a continuous well's full-rate series (5.8 MB) is read twice for its
CRCs, ≈ 1.5 ms each time. :class:`DataSection` is the stream the library writes into with
its data CRC off: it carries the running CRC over each write itself, and where a write is
one uncompressed chunk record it CRCs only the record's head and continues the CRC over the
messages from the chunk's ``uncompressed_crc`` (:func:`crc32_combine`, zlib's arithmetic)
instead of reading them again; :meth:`DataSection.seal` then writes that CRC into the
``DataEnd`` record. The file is the same, byte for byte, as the library's own with
``enable_data_crcs``.
"""

from __future__ import annotations

import struct
import zlib
from functools import lru_cache
from typing import BinaryIO

_POLY = 0xEDB88320
"""CRC-32's polynomial, bit-reversed (bit 31 is x⁰)."""
CHUNK = 0x06
"""The Chunk record's opcode."""
DATA_END = b"\x0f" + struct.pack("<QI", 4, 0)
"""A DataEnd record of CRC 0: opcode, length, ``data_section_crc``."""
_CHUNK_HEAD = struct.Struct("<BQQQQIIQ")
"""A Chunk record's head with no compression name: opcode, length, start and end times,
``uncompressed_size``, ``uncompressed_crc``, the compression's length (0), the records'."""


def _multiply(a: int, b: int) -> int:
    """a·b modulo CRC-32's polynomial (bit-reversed, as zlib's ``multmodp``; a ≠ 0)."""
    m, p = 1 << 31, 0
    while True:
        if a & m:
            p ^= b
            if not a & (m - 1):
                return p
        m >>= 1
        b = (b >> 1) ^ _POLY if b & 1 else b >> 1


_SQUARES = [1 << 30]  # x^(2^k) for k = 0…31 (x¹ first)
for _ in range(31):
    _SQUARES.append(_multiply(_SQUARES[-1], _SQUARES[-1]))


@lru_cache(maxsize=64)
def _shift(length: int) -> int:
    """x^(8·length) modulo the polynomial: a CRC carried past ``length`` zero bytes (a
    file's chunks are mostly of a few sizes)."""
    p, k = 1 << 31, 3
    while length:
        if length & 1:
            p = _multiply(_SQUARES[k & 31], p)
        length >>= 1
        k += 1
    return p


def crc32_combine(crc1: int, crc2: int, length2: int) -> int:
    """The CRC-32 of A + B from A's (``crc1``), B's (``crc2``) and B's length in bytes
    (zlib's ``crc32_combine``): ``zlib.crc32(b, crc1)`` without reading ``b``."""
    return _multiply(_shift(length2), crc1) ^ crc2 if length2 else crc1


class DataSection:
    """A binary file as the ``mcap`` library's writer output (``enable_data_crcs=False``,
    ``enable_crcs=True``: the chunks' CRCs are what the data CRC continues from) that
    carries the data section's CRC, from the file's first byte to its ``DataEnd`` record."""

    def __init__(self, fh: BinaryIO) -> None:
        self.fh = fh
        self.crc = 0
        self.data_end: int | None = None
        """offset of the DataEnd record (None: not written yet)"""

    def write(self, data: bytes | bytearray | memoryview) -> int:
        if self.data_end is None:
            if len(data) == len(DATA_END) and bytes(data) == DATA_END:
                self.data_end = self.fh.tell()
            else:
                self.crc = self._continued(memoryview(data))
        return self.fh.write(data)

    def _continued(self, data: memoryview) -> int:
        """The running CRC continued over ``data``; an uncompressed chunk record's messages
        from the chunk's own CRC of them."""
        head = _CHUNK_HEAD.size
        if len(data) > head and data[0] == CHUNK:
            _, length, _, _, size, crc, name, records = _CHUNK_HEAD.unpack(data[:head])
            whole = name == 0 and records == size and length + 9 == len(data) == head + records
            if whole and crc != 0:  # 0: the chunk's CRC not computed (or truly 0): run it
                return crc32_combine(zlib.crc32(data[:head], self.crc), crc, records)
        return zlib.crc32(data, self.crc)

    def tell(self) -> int:
        return self.fh.tell()

    def flush(self) -> None:
        self.fh.flush()

    def seal(self) -> None:
        """Write the data section's CRC into the DataEnd record (after the writer's
        ``finish``)."""
        if self.data_end is None:
            raise RuntimeError("no DataEnd record was written")
        end = self.fh.tell()
        self.fh.seek(self.data_end + 9)
        self.fh.write(struct.pack("<I", self.crc))
        self.fh.seek(end)

"""The charts' font in the HTML report: DejaVu Sans, regular and bold, embedded in the page.

Chart text is measured with DejaVu Sans metrics (:func:`~.charts.scene.text_width`), so a
page shown in any other font may let labels overflow their boxes or collide. The page
therefore carries the PDF's shipped repertoire subsets (:data:`~.pdf_fonts.REPERTOIRE`:
Latin-1, Greek and the symbols gyropipe prints, 44 KB each) as ``@font-face`` rules with
``data:`` URLs, under :data:`FAMILY`, a name no installed font has. The subsets leave out
the ``kern`` table (the PDF positions its glyphs itself) while the layout kerns, so the
page's copies get it back: the repertoire's kerning pairs shipped beside each subset, as
a TrueType ``kern`` table (format 0) that browsers apply. Built and base64-encoded once
per process: 134 KB of HTML (two fonts of 52 and 49 KB, base64), about 5 ms.
"""

from __future__ import annotations

import base64
import struct
from functools import cache

from pipeline.reports.pdf_fonts import REPERTOIRE, pdf_font

FAMILY = "gyropipe-dejavu-sans"
"""The embedded font's family name (no installed font is called so)."""
SANS = "DejaVu Sans"


def _kern_table(pairs: list[tuple[int, int, int]]) -> bytes:
    """A ``kern`` table (version 0, one horizontal format-0 subtable) of ``pairs`` (left
    glyph id, right glyph id, adjustment in font units)."""
    n = len(pairs)
    power = 1 << max(n.bit_length() - 1, 0)
    body = b"".join(struct.pack(">HHh", a, b, v) for a, b, v in sorted(pairs))
    subtable = struct.pack(
        ">HHHHHHH", 0, 14 + len(body), 0x0001, n, 6 * power, power.bit_length() - 1, 6 * (n - power)
    )
    return struct.pack(">HH", 0, 1) + subtable + body


def _checksum(data: bytes) -> int:
    """The TrueType checksum of ``data``: the sum of its big-endian 32-bit words, padded."""
    padded = data + bytes(-len(data) % 4)
    words: tuple[int, ...] = struct.unpack(f">{len(padded) // 4}L", padded)
    return sum(words) & 0xFFFFFFFF


def _with_table(font: bytes, tag: bytes, table: bytes) -> bytes:
    """The TrueType ``font`` with ``table`` added as ``tag`` (its table directory, offsets
    and checksums written anew)."""
    version, count = struct.unpack(">LH", font[:6])
    tables = {}
    for k in range(count):
        name, _, offset, length = struct.unpack(">4sLLL", font[12 + 16 * k : 28 + 16 * k])
        tables[name] = font[offset : offset + length]
    tables[tag] = table
    head = bytearray(tables[b"head"])
    head[8:12] = bytes(4)  # checkSumAdjustment: set once the whole font is summed
    tables[b"head"] = bytes(head)
    count = len(tables)
    power = 1 << (count.bit_length() - 1)
    directory = [
        struct.pack(
            ">LHHHH", version, count, 16 * power, power.bit_length() - 1, 16 * (count - power)
        )
    ]
    body, offset, head_at = [], 12 + 16 * count, 0
    for name in sorted(tables):
        data = tables[name]
        directory.append(struct.pack(">4sLLL", name, _checksum(data), offset, len(data)))
        head_at = offset if name == b"head" else head_at
        body.append(data + bytes(-len(data) % 4))
        offset += len(body[-1])
    whole = bytearray(b"".join(directory + body))
    adjustment = (0xB1B0AFBA - _checksum(bytes(whole))) & 0xFFFFFFFF
    whole[head_at + 8 : head_at + 12] = struct.pack(">L", adjustment)
    return bytes(whole)


@cache
def embedded_font(bold: bool) -> bytes:
    """The repertoire subset of DejaVu Sans (``bold`` or regular) with its kerning pairs."""
    font = pdf_font(SANS, bold)
    subset, ids, _, _ = font.subset(set(REPERTOIRE))
    pairs = [(ids[a], ids[b], v) for (a, b), v in font.kerning().items() if a in ids and b in ids]
    return _with_table(subset, b"kern", _kern_table(pairs))


@cache
def font_faces() -> str:
    """CSS ``@font-face`` rules of :data:`FAMILY` (regular and bold) with the fonts
    inline, for the page's ``<style>``."""
    return "".join(
        f"@font-face {{ font-family: {FAMILY}; font-weight: {weight}; font-style: normal; "
        "src: url(data:font/ttf;base64,"
        f"{base64.b64encode(embedded_font(bold)).decode('ascii')}) format('truetype'); }}\n"
        for bold, weight in ((False, 400), (True, 700))
    )

"""Pages of the PDF report as drawing operations — text and filled rectangles placed in
inches from the page's bottom-left corner, and the vector figures' path operators
(:mod:`.charts.pdf`) — and the PDF file they make, written directly (PDF 1.4: one content
stream per page, fonts embedded as subsets by :mod:`.pdf_fonts`). The same pages give the
same bytes (no creation date)."""

from __future__ import annotations

import itertools
import zlib
from dataclasses import dataclass, field
from functools import cache, lru_cache
from pathlib import Path
from typing import NamedTuple

from pipeline.reports.charts.scene import rgb
from pipeline.reports.pdf_fonts import PdfFont, pdf_font

PT = 72.0
"""Points per inch."""
SANS = "DejaVu Sans"
MONO = "DejaVu Sans Mono"
LEVEL = 6
"""zlib's compression level of the font programs (deflated once per process)."""
PAGE_LEVEL = 1
"""zlib's compression level of each report's own streams (pages, figures): level 1 deflates
a continuous survey's pages in a third of level 6's CPU time (≈ 9 against 31 ms), the file
13 % larger."""


@cache
def _rgb(colour: str) -> str:
    return " ".join(_num(c) for c in rgb(colour))


def fill_colour(colour: str) -> str:
    """The PDF operator setting the fill colour."""
    return f"{_rgb(colour)} rg"


def stroke_colour(colour: str) -> str:
    """The PDF operator setting the stroke colour."""
    return f"{_rgb(colour)} RG"


NUMBERS = 4096
"""Most numbers whose PDF text a process keeps (text and rectangle positions and sizes
recur on every page and in every report: some 800 distinct among 3,000 a report)."""


@lru_cache(maxsize=NUMBERS)
def _num(value: float) -> str:
    """A PDF number: three decimals at most, no trailing zeros (−0 is 0, so a value equal
    to another writes as it does)."""
    out = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if out in ("-0", "") else out


class _Text(NamedTuple):
    font: tuple[str, bool]
    size: float
    x: float
    y: float
    """baseline origin, points"""
    content: str
    colour: str
    angle: int = 0
    """0, or 90: reading upwards"""


class _Rect(NamedTuple):
    x: float
    y: float
    w: float
    h: float
    colour: str


class _Raw(NamedTuple):
    """Graphics operators as they are (paths, clipping), coordinates in points."""

    content: str


@dataclass
class Page:
    """One page: what is drawn on it, in order (later over earlier)."""

    width: float
    height: float
    """inches"""
    ops: list[_Text | _Rect | _Raw] = field(default_factory=list)

    def text(
        self,
        x: float,
        y: float,
        content: str,
        size: float,
        *,
        bold: bool = False,
        family: str = SANS,
        colour: str = "black",
        ha: str = "left",
        va: str = "top",
    ) -> None:
        """``content`` at ``size`` points; (x, y) inches is its left, right or centre
        (``ha``) and its top or baseline (``va``: the top is that of its tallest glyph or
        of 'l', whichever is higher)."""
        if not content:
            return
        font = pdf_font(family, bold)
        x_pt, y_pt = x * PT, y * PT
        if ha != "left":
            x_pt -= font.width(content, size) / (2.0 if ha == "center" else 1.0)
        if va == "top":
            y_pt -= font.top(content) * size / font.upem
        self.ops.append(_Text((family, bold), size, x_pt, y_pt, content, colour))

    def rect(self, x: float, y: float, w: float, h: float, colour: str) -> None:
        """A filled rectangle with its bottom-left corner at (x, y), inches."""
        self.ops.append(_Rect(x * PT, y * PT, w * PT, h * PT, colour))

    def glyphs(
        self,
        x: float,
        y: float,
        content: str,
        size: float,
        colour: str,
        *,
        bold: bool = False,
        angle: int = 0,
    ) -> None:
        """``content`` in the sans font with its baseline origin at (x, y) points, reading
        right (``angle`` 0) or up (90)."""
        if content:
            self.ops.append(_Text((SANS, bold), size, x, y, content, colour, angle))

    def raw(self, content: str) -> None:
        """Graphics operators drawn as they are (points from the page's bottom-left)."""
        self.ops.append(_Raw(content))


@dataclass
class _Embedded:
    """A font as embedded in one file: resource name, subset glyph ids, the font."""

    name: str
    codes: dict[int, str]
    """character (code point) → its glyph's id as one character (``chr(id)``), for the
    file's characters (a ``str.translate`` table: a text translated and written as
    UTF-16BE hex is its glyph ids' four hex digits each — one translation to single
    characters, which ``str.translate`` does fast, not to four-character strings)"""
    font: PdfFont
    kept: dict[str, tuple[tuple[int, ...], str]]
    """the subset's :attr:`_Program.runs` (kept across files)"""
    runs: dict[str, str] = field(default_factory=dict)
    """text → its glyph runs (the ``TJ`` operand), for the texts shown so far"""


class _Writer:
    def __init__(self) -> None:
        self.objects: list[bytes] = []

    def reserve(self) -> int:
        self.objects.append(b"")
        return len(self.objects)

    def put(self, body: str | bytes, number: int | None = None) -> int:
        number = number or self.reserve()
        self.objects[number - 1] = body.encode("latin-1") if isinstance(body, str) else body
        return number

    def stream(self, entries: str, data: bytes) -> int:
        """A stream of ``data``, deflated."""
        return self.deflated(entries, zlib.compress(data, PAGE_LEVEL))

    def deflated(self, entries: str, data: bytes) -> int:
        """A stream of ``data`` deflated already."""
        entries = f"{entries} /Filter /FlateDecode"
        head = f"<< {entries} /Length {len(data)} >>\nstream\n".encode("latin-1")
        return self.put(head + data + b"\nendstream")

    def bytes(self, root: int, info: int) -> bytes:
        out = bytearray(b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n")
        offsets = []
        for number, body in enumerate(self.objects, 1):
            offsets.append(len(out))
            out += f"{number} 0 obj\n".encode() + body + b"\nendobj\n"
        xref = len(out)
        out += f"xref\n0 {len(self.objects) + 1}\n0000000000 65535 f \n".encode()
        out += b"".join(f"{o:010d} 00000 n \n".encode() for o in offsets)
        out += (
            f"trailer\n<< /Size {len(self.objects) + 1} /Root {root} 0 R /Info {info} 0 R >>\n"
            f"startxref\n{xref}\n%%EOF\n"
        ).encode()
        return bytes(out)


def _text_string(value: str) -> str:
    """A PDF text string (UTF-16BE with its byte-order mark), hex."""
    return "<FEFF" + value.encode("utf-16-be").hex().upper() + ">"


@dataclass(frozen=True)
class _Program:
    """What a font subset embeds as, the same in every file: the font file and its
    ``ToUnicode`` map (both deflated), the glyph widths and the glyph ids."""

    base: str
    length: int
    font_file: bytes
    widths: str
    to_unicode: bytes
    codes: dict[str, str]
    """glyph name → its glyph id as the four hex digits a text string shows"""
    runs: dict[str, tuple[tuple[int, ...], str]] = field(default_factory=dict, compare=False)
    """kerned text → the kerning it was laid out with and its glyph runs, for the first
    :data:`RUNS` texts shown in this subset (a subset's glyph ids are the same in every
    file: a batch's labels, units, headings and tick labels recur in every report)"""


_PROGRAMS: dict[tuple[str, str], _Program] = {}
"""(font file, subset tag) → the subset's embedded form, for the first :data:`PROGRAMS`"""
PROGRAMS = 16
"""Most font subsets whose embedded form a process keeps (most reports share a few)."""
RUNS = 4096
"""Most kerned texts whose glyph runs a kept font subset keeps (:attr:`_Program.runs`:
some 160 a continuous report, 150 of them in the next well's too; its numbers mostly are
not, so the runs of every text ever shown would grow with the batch)."""


def _program(font: PdfFont, chars: set[str]) -> _Program:
    """The embedded form of ``font``'s subset for ``chars``, made once per process for
    the subsets used first (most reports share the repertoire's: :mod:`.pdf_fonts`)."""
    tag = font.subset_tag(chars)
    found = _PROGRAMS.get((font.path, tag))
    if found is None:
        found = _make_program(font, tag, chars)
        if len(_PROGRAMS) < PROGRAMS:
            _PROGRAMS[font.path, tag] = found
    return found


def _make_program(font: PdfFont, tag: str, chars: set[str]) -> _Program:
    data, ids, widths, text = font.subset(chars)
    pairs = sorted(text.items())
    chunks = [pairs[k : k + 100] for k in range(0, len(pairs), 100)]
    cmap = (
        "/CIDInit /ProcSet findresource begin 12 dict begin begincmap /CIDSystemInfo << "
        "/Registry (Adobe) /Ordering (UCS) /Supplement 0 >> def /CMapName /Adobe-Identity-UCS "
        "def /CMapType 2 def 1 begincodespacerange <0000> <FFFF> endcodespacerange\n"
        + "".join(
            f"{len(chunk)} beginbfchar\n"
            + "".join(f"<{g:04X}> <{c.encode('utf-16-be').hex().upper()}>\n" for g, c in chunk)
            + "endbfchar\n"
            for chunk in chunks
        )
        + "endcmap CMapName currentdict /CMap defineresource pop end end"
    )
    return _Program(
        base=f"{tag}+{font.name.replace(' ', '')}",
        length=len(data),
        font_file=zlib.compress(data, LEVEL),
        widths=" ".join(map(str, widths)),
        to_unicode=zlib.compress(cmap.encode("ascii"), LEVEL),
        codes={glyph: f"{k:04X}" for glyph, k in ids.items()},
    )


def _embed_font(w: _Writer, font: PdfFont, chars: set[str], name: str) -> tuple[int, _Embedded]:
    program = _program(font, chars)
    base = program.base
    file = w.deflated(f"/Length1 {program.length}", program.font_file)
    scale = 1000.0 / font.upem
    descriptor = w.put(
        f"<< /Type /FontDescriptor /FontName /{base} /Flags 32 /FontBBox "
        f"[{' '.join(str(round(v * scale)) for v in font.bbox)}] /ItalicAngle 0 "
        f"/Ascent {round(font.ascent * scale)} /Descent {round(font.descent * scale)} "
        f"/CapHeight {round(font.cap_height * scale)} /StemV 80 /FontFile2 {file} 0 R >>"
    )
    cid = w.put(
        f"<< /Type /Font /Subtype /CIDFontType2 /BaseFont /{base} /CIDSystemInfo << "
        f"/Registry (Adobe) /Ordering (Identity) /Supplement 0 >> /FontDescriptor "
        f"{descriptor} 0 R /W [0 [{program.widths}]] /CIDToGIDMap /Identity >>"
    )
    unicode = w.deflated("", program.to_unicode)
    number = w.put(
        f"<< /Type /Font /Subtype /Type0 /BaseFont /{base} /Encoding /Identity-H "
        f"/DescendantFonts [{cid} 0 R] /ToUnicode {unicode} 0 R >>"
    )
    codes = {ord(c): chr(int(program.codes.get(font.glyph(c), "0000"), 16)) for c in chars}
    return number, _Embedded(name, codes, font, program.runs)


def _show(op: _Text, embedded: _Embedded) -> str:
    """The text operators of ``op``."""
    runs = embedded.runs.get(op.content)
    if runs is None:
        runs = embedded.runs[op.content] = _kept_runs(op.content, embedded)
    matrix = "0 1 -1 0" if op.angle == 90 else "1 0 0 1"
    return (
        f"BT /{embedded.name} {_num(op.size)} Tf {_rgb(op.colour)} rg {matrix} {_num(op.x)} "
        f"{_num(op.y)} Tm [{runs}] TJ ET"
    )


def _kept_runs(content: str, embedded: _Embedded) -> str:
    """:func:`_runs` of ``content``, kept by the font subset for a kerned font (where the
    text is laid out with the kerning it was kept with: a font's kerning is read again
    from its own tables when a text leaves the repertoire)."""
    font = embedded.font
    if not font.kerned:  # one run, no layout: as cheap as looking it up
        return _runs(content, embedded)
    kerns = font.layout(content)[1]
    found = embedded.kept.get(content)
    if found is not None and found[0] == kerns:
        return found[1]
    runs = _runs(content, embedded)
    if len(embedded.kept) < RUNS:
        embedded.kept[content] = (kerns, runs)
    return runs


def _runs(content: str, embedded: _Embedded) -> str:
    """The glyph runs of ``content``, split where kerning moves a glyph."""
    ids = _glyph_hex(content, embedded.codes)  # four hex digits a character
    if not embedded.font.kerned:  # one run (the table rows: no layout to work out)
        return f"<{ids}>"
    kerns = embedded.font.layout(content)[1]
    upem = embedded.font.upem
    parts: list[str] = []
    start = 0
    for k in itertools.compress(range(len(kerns)), kerns):  # never the first glyph
        parts.append(f"<{ids[4 * start : 4 * k]}> {_num(-kerns[k] * 1000 / upem)}")
        start = k
    parts.append(f"<{ids[4 * start :]}>")
    return " ".join(parts)


def _glyph_hex(content: str, codes: dict[int, str]) -> str:
    """The glyph ids of ``content``'s characters (``codes``: :attr:`_Embedded.codes`), four
    hex digits each (a glyph id in the surrogates' range written as its two bytes too)."""
    return content.translate(codes).encode("utf-16-be", "surrogatepass").hex().upper()


def write_pdf(pages: list[Page], path: Path, title: str, creator: str) -> None:
    """Write ``pages`` to ``path`` as one PDF with ``title`` and ``creator`` in its
    document information."""
    w = _Writer()
    root, tree = w.reserve(), w.reserve()
    chars: dict[tuple[str, bool], set[str]] = {}
    for page in pages:
        for op in page.ops:
            if isinstance(op, _Text):
                chars.setdefault(op.font, set()).update(op.content)
    fonts: dict[tuple[str, bool], _Embedded] = {}
    font_refs = []
    for k, (key, used) in enumerate(sorted(chars.items())):
        number, fonts[key] = _embed_font(w, pdf_font(*key), used, f"F{k + 1}")
        font_refs.append(f"/F{k + 1} {number} 0 R")
    kids = []
    for page in pages:
        content: list[str] = []
        for op in page.ops:
            if isinstance(op, _Text):
                content.append(_show(op, fonts[op.font]))
            elif isinstance(op, _Rect):
                content.append(
                    f"{_rgb(op.colour)} rg {_num(op.x)} {_num(op.y)} {_num(op.w)} {_num(op.h)} re f"
                )
            else:
                content.append(op.content)
        stream = w.stream("", "\n".join(content).encode("latin-1"))
        kids.append(
            w.put(
                f"<< /Type /Page /Parent {tree} 0 R /MediaBox [0 0 {_num(page.width * PT)} "
                f"{_num(page.height * PT)}] /Resources << /Font << {' '.join(font_refs)} >> "
                f">> /Contents {stream} 0 R >>"
            )
        )
    w.put(
        f"<< /Type /Pages /Kids [{' '.join(f'{k} 0 R' for k in kids)}] /Count {len(kids)} >>",
        tree,
    )
    w.put(f"<< /Type /Catalog /Pages {tree} 0 R >>", root)
    info = w.put(f"<< /Title {_text_string(title)} /Creator {_text_string(creator)} >>")
    path.write_bytes(w.bytes(root, info))

"""The PDF report's fonts: DejaVu Sans and Sans Mono (regular and bold), measured from their
own tables and embedded as subsets.

Widths come from the fonts' advance widths and ``kern`` pairs (the glyph positions a PDF
viewer uses), in font units, so measuring text costs a dictionary look-up per character.
The fonts ship with the package (:data:`FONTS`, DejaVu's licence beside them) as lean
copies without the OpenType layout tables (GSUB, GPOS, GDEF), which a PDF viewer never
reads and which make subsetting slow. Each font used is embedded as a TrueType subset
(fontTools), written as a ``Type0`` font with ``Identity-H`` encoding and a ``ToUnicode``
map (text can be searched and copied). A report whose characters all lie in
:data:`REPERTOIRE` (Latin-1, Greek and the symbols gyropipe prints) embeds that
repertoire's subset, shipped beside the fonts, so most reports subset nothing (fontTools'
subsetter is not even imported); other text gets a subset of exactly its characters.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import json
import logging
import os
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fontTools.ttLib import TTFont  # type: ignore[import-untyped]

FONTS = Path(__file__).parent / "fonts"
"""The report's fonts (lean copies) and their repertoire subsets."""
FILES = {
    ("DejaVu Sans", False): "DejaVuSans.ttf",
    ("DejaVu Sans", True): "DejaVuSans-Bold.ttf",
    ("DejaVu Sans Mono", False): "DejaVuSansMono.ttf",
    ("DejaVu Sans Mono", True): "DejaVuSansMono-Bold.ttf",
}
DROPPED = ("FFTM", "MATH", "kern", "GSUB", "GPOS", "GDEF")
"""Tables the embedded subset leaves out (kerning is in the glyph positions already)."""
REPERTOIRE = frozenset(
    [chr(c) for c in (*range(0x20, 0x7F), *range(0xA0, 0x100), *range(0x391, 0x3CA))]
    + list("–—‘’“”•…‰′″−×÷±≤≥≠≈∞√∑∆∂∫∇∝→←↔↑↓·µ⁰¹²³⁴⁵⁶⁷⁸⁹⁻₀₁₂₃ĪİėĊ")
)
"""Characters of the cached subset every report can share (Latin-1, Greek, symbols)."""
Subset = tuple[bytes, dict[str, int], list[int], dict[int, str]]
"""font file bytes, glyph name → glyph id, advance of each glyph (1/1000 em), id → text"""
Layout = tuple[tuple[str, ...], tuple[int, ...], int]
"""glyph names, the kerning before each and the total advance (font units)"""
MEASURED = 50_000
"""Most texts a font keeps the layout of (a process making many reports stays bounded)."""


@dataclass
class PdfFont:
    """One TrueType font: its metrics for layout, and subsets of it to embed. The metrics of
    the :data:`REPERTOIRE` are read from the index shipped beside its subset (no font
    table is parsed); the whole font is read only when text leaves the repertoire."""

    path: str

    def __post_init__(self) -> None:
        meta = _index(self.path)["metrics"]
        self.name: str = meta["name"]
        self.upem: int = meta["upem"]
        self.bbox: tuple[int, int, int, int] = tuple(meta["bbox"])
        self.ascent: int = meta["ascent"]
        self.descent: int = meta["descent"]
        self.cap_height: int = meta["cap_height"]
        self._cmap: dict[int, str] = {ord(c): g for c, g in meta["cmap"].items()}
        self._advance: dict[str, int] = meta["advance"]
        self._kern: dict[tuple[str, str], int] = {(a, b): v for a, b, v in meta["kern"]}
        self._top: dict[str, int] = meta["top"]
        self._font: TTFont | None = None
        """the whole font, once text outside the repertoire needs it"""
        self._layouts: dict[str, Layout] = {}
        """text → its layout, for the texts measured so far (a report repeats most of its
        labels, units and numbers on every page)"""
        self._tops: dict[str, int] = {}
        self._glyphs: dict[str, str] = {}
        """character → its glyph's name, for the characters met so far (kept when the whole
        font is read, as :attr:`_char_tops` is)"""
        self._char_tops: dict[str, int] = {}
        """character → its glyph's top (font units), for the characters met so far (what the
        repertoire's index says of a character is what the whole font says: kept when the
        whole font is read)"""

    def _whole(self) -> TTFont:
        """The font's own tables: every glyph's cmap entry, advance, kerning and top."""
        if self._font is None:
            tt = self._font = _read_font(self.path)
            self._cmap = tt.getBestCmap()
            self._advance = {n: m[0] for n, m in tt["hmtx"].metrics.items()}
            if "kern" in tt:
                self._kern = dict(tt["kern"].kernTables[0].kernTable)
            self._layouts.clear()  # measured with the repertoire's tables only
            self._tops.clear()
        return self._font

    def glyph(self, char: str) -> str:
        """Glyph name of ``char`` (``.notdef`` if the font has none)."""
        found = self._cmap.get(ord(char))
        if found is None and self._font is None:
            self._whole()
            found = self._cmap.get(ord(char))
        return found or ".notdef"

    def layout(self, text: str) -> Layout:
        """Glyph names of ``text``, the kerning before each (font units) and the total
        advance (font units); measured once per text."""
        found = self._layouts.get(text)
        if found is None:
            glyphs = self._glyph_names(text)
            if self._kern and glyphs:
                pairs = itertools.pairwise(glyphs)
                kerns = (0, *map(self._kern.get, pairs, itertools.repeat(0)))
            else:
                kerns = (0,) * len(glyphs)
            found = (glyphs, kerns, sum(map(self._advance.__getitem__, glyphs)) + sum(kerns))
            if len(self._layouts) < MEASURED:
                self._layouts[text] = found
        return found

    def _glyph_names(self, text: str) -> tuple[str, ...]:
        """The glyph names of ``text``'s characters (each character looked up once)."""
        known = self._glyphs
        try:
            return tuple(map(known.__getitem__, text))
        except KeyError:
            for c in set(text) - known.keys():
                known[c] = self.glyph(c)  # may read the whole font
            return tuple(map(known.__getitem__, text))

    @property
    def kerned(self) -> bool:
        """True if the font's tables read so far hold kerning pairs (a monospaced font's
        have none: its text is never split into runs)."""
        return bool(self._kern)

    def width(self, text: str, size: float) -> float:
        """Advance of ``text`` at ``size`` points, in points."""
        return self.layout(text)[2] * size / self.upem

    def top(self, text: str) -> int:
        """Highest point of ``text``'s glyphs and of 'l' above the baseline, font units (what
        a text aligned by its top is hung from)."""
        best = self._tops.get(text)
        if best is not None:
            return best
        chars, tops = {*text, "l"}, self._char_tops
        for c in chars - tops.keys():  # each character's top looked up once
            name = self._glyph_names(c)[0]
            if name not in self._top:
                self._top[name] = _glyph_top(self._whole(), name)
            tops[c] = self._top[name]
        best = max(0, *map(tops.__getitem__, chars))
        if len(self._tops) < MEASURED:
            self._tops[text] = best
        return best

    def subset(self, chars: set[str]) -> Subset:
        """The subset to embed for ``chars``: the cached :data:`REPERTOIRE` subset when it
        holds them all, else a subset of exactly ``chars``."""
        if chars <= REPERTOIRE:
            return self._repertoire()
        return _make_subset(self.path, chars)

    def subset_tag(self, chars: set[str]) -> str:
        """:meth:`tag` of the subset embedded for ``chars`` (of the characters it holds)."""
        return repertoire_tag() if chars <= REPERTOIRE else self.tag(chars)

    def _repertoire(self) -> Subset:
        """The :data:`REPERTOIRE`'s subset (embedded once per process: :mod:`.pdf_canvas`)."""
        meta = _index(self.path)
        cached = FONTS / f"{Path(self.path).stem}-{repertoire_tag()}.ttf"
        try:
            data = cached.read_bytes()
        except OSError:
            data = _make_subset(self.path, set(REPERTOIRE))[0]
        return data, meta["ids"], meta["widths"], {int(k): v for k, v in meta["text"].items()}

    def kerned_repertoire(self) -> bytes:
        """The :data:`REPERTOIRE` subset with the font's ``kern`` table, for a browser (which
        kerns only as the font says, where the PDF positions each glyph itself); shipped
        beside the fonts, made when missing."""
        cached = FONTS / f"{Path(self.path).stem}-{repertoire_tag()}-kern.ttf"
        try:
            return cached.read_bytes()
        except OSError:
            data = _make_subset(self.path, set(REPERTOIRE), kern=True)[0]
            _store(cached, data)
            return data

    @staticmethod
    def tag(chars: set[str]) -> str:
        """Six capitals naming the subset of ``chars`` (the same characters, the same tag)."""
        digest = hashlib.sha256("".join(sorted(chars)).encode()).digest()
        return "".join(chr(65 + b % 26) for b in digest[:6])


TEXTS = 4096
"""Most texts whose width a process keeps: a batch worker meets new well names, numbers and
dates in every report, so a cache of every text ever measured would grow with the batch."""


@cache
def repertoire_tag() -> str:
    """:meth:`PdfFont.tag` of the :data:`REPERTOIRE` (worked out once)."""
    return PdfFont.tag(set(REPERTOIRE))


def _make_subset(path: str, chars: set[str], *, kern: bool = False) -> Subset:
    """A subset of the font at ``path`` holding exactly ``chars`` (with its ``kern`` table
    if ``kern``)."""
    from fontTools import subset  # type: ignore[import-untyped]

    options = subset.Options()
    options.drop_tables += [t for t in DROPPED if not (kern and t == "kern")]
    options.legacy_kern = kern
    options.notdef_outline = True
    options.name_IDs = [1, 2, 4, 6]
    options.glyph_names = True
    font = _read_font(path)
    subsetter = subset.Subsetter(options)
    subsetter.populate(unicodes=sorted(ord(c) for c in chars))
    logging.getLogger("fontTools.subset").setLevel(logging.ERROR)
    upem = font["head"].unitsPerEm
    subsetter.subset(font)
    out = io.BytesIO()
    font.save(out)
    order = font.getGlyphOrder()
    ids = {name: k for k, name in enumerate(order)}
    widths = [round(font["hmtx"].metrics[n][0] * 1000 / upem) for n in order]
    cmap = font.getBestCmap()
    text = {ids[cmap[ord(c)]]: c for c in sorted(chars) if cmap.get(ord(c)) in ids}
    return out.getvalue(), ids, widths, text


def _read_font(path: str) -> TTFont:
    """The font at ``path``, its tables parsed when first used, from its bytes in memory
    (a font read lazily from its file keeps the file open as long as the font lives)."""
    from fontTools.ttLib import TTFont

    return TTFont(io.BytesIO(Path(path).read_bytes()), lazy=True)


def _glyph_top(font: TTFont, name: str) -> int:
    """Highest point of glyph ``name`` above the baseline, font units."""
    outline = font["glyf"][name]
    return int(getattr(outline, "yMax", 0) or 0)


def _metrics(path: str) -> dict[str, Any]:
    """Layout metrics of the :data:`REPERTOIRE`'s glyphs, read from the font at ``path``."""
    tt = _read_font(path)
    cmap = tt.getBestCmap()
    chars = {c: cmap[ord(c)] for c in sorted(REPERTOIRE) if ord(c) in cmap}
    glyphs = {*chars.values(), ".notdef"}
    advance = {n: m[0] for n, m in tt["hmtx"].metrics.items() if n in glyphs}
    kern = tt["kern"].kernTables[0].kernTable if "kern" in tt else {}
    head, hhea = tt["head"], tt["hhea"]
    return {
        "name": tt["name"].getDebugName(6) or Path(path).stem,
        "upem": head.unitsPerEm,
        "bbox": [head.xMin, head.yMin, head.xMax, head.yMax],
        "ascent": hhea.ascent,
        "descent": hhea.descent,
        "cap_height": getattr(tt["OS/2"], "sCapHeight", hhea.ascent),
        "cmap": chars,
        "advance": advance,
        "kern": sorted([a, b, v] for (a, b), v in kern.items() if a in glyphs and b in glyphs),
        "top": {n: _glyph_top(tt, n) for n in sorted(glyphs)},
    }


@cache
def _index(path: str) -> dict[str, Any]:
    """What is shipped beside the repertoire's subset of the font at ``path``: the subset's
    glyph ids, widths and text, and the repertoire's metrics; made (and written, if the
    directory allows) when missing."""
    stem = Path(path).stem
    tag = repertoire_tag()
    font_file, index = FONTS / f"{stem}-{tag}.ttf", FONTS / f"{stem}-{tag}.json"
    try:
        found: dict[str, Any] = json.loads(index.read_text())
        if "metrics" in found:
            return found
    except (OSError, ValueError):
        pass
    data, ids, widths, text = _make_subset(path, set(REPERTOIRE))
    made = {"ids": ids, "widths": widths, "text": text, "metrics": _metrics(path)}
    _store(font_file, data)
    _store(index, json.dumps(made).encode())
    return made


def _store(target: Path, content: bytes) -> None:
    """Write a made subset or index beside the fonts, if the directory allows."""
    partial = target.with_suffix(f".{os.getpid()}.tmp")
    try:
        partial.write_bytes(content)
        partial.replace(target)  # atomic: parallel batch workers may write it at once
    except OSError:
        partial.unlink(missing_ok=True)


@cache
def pdf_font(family: str, bold: bool) -> PdfFont:
    """The metrics of ``family``, bold or regular, loaded once."""
    return PdfFont(str(FONTS / FILES[family, bold]))

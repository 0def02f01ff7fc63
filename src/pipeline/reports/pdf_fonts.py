"""The PDF report's fonts: DejaVu Sans and Sans Mono (regular and bold), measured from their
own tables and embedded as subsets.

Widths come from the fonts' advance widths and ``kern`` pairs (the glyph positions a PDF
viewer uses), in font units, so measuring text costs a dictionary look-up per character.
Each font used is embedded as a TrueType subset of the glyphs the pages use (fontTools),
written as a ``Type0`` font with ``Identity-H`` encoding and a ``ToUnicode`` map (text can be
searched and copied). The subset is made from a lean copy without the OpenType layout
tables (GSUB, GPOS, GDEF), which a PDF viewer never reads and which make subsetting slow.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import logging
import os
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import matplotlib
from fontTools import subset  # type: ignore[import-untyped]
from fontTools.ttLib import TTFont  # type: ignore[import-untyped]
from matplotlib.font_manager import FontProperties, findfont

LAYOUT_TABLES = ("GSUB", "GPOS", "GDEF")
DROPPED = ("FFTM", "MATH", "kern", *LAYOUT_TABLES)
"""Tables the embedded subset leaves out (kerning is in the glyph positions already)."""


@cache
def lean_font(family: str, bold: bool) -> str:
    """Path of ``family`` (bold or regular) without its layout tables, kept in matplotlib's
    cache directory (written once per font version); the font itself if the copy cannot
    be written."""
    weight = "bold" if bold else "normal"
    source = Path(findfont(FontProperties(family=family, weight=weight)))
    stat = source.stat()
    target = Path(matplotlib.get_cachedir()) / "gyropipe-fonts"
    lean = target / f"{source.stem}-{stat.st_size}-{stat.st_mtime_ns}.ttf"
    if lean.is_file():
        return str(lean)
    try:
        target.mkdir(parents=True, exist_ok=True)
        font = TTFont(source)
        for tag in LAYOUT_TABLES:
            if tag in font:
                del font[tag]
        partial = lean.with_suffix(f".{os.getpid()}.tmp")
        font.save(partial)
        partial.replace(lean)  # atomic: parallel batch workers may write it at once
    except OSError:
        return str(source)
    return str(lean)


@dataclass
class PdfFont:
    """One TrueType font: its metrics for layout, and subsets of it to embed."""

    path: str

    def __post_init__(self) -> None:
        tt = TTFont(self.path, lazy=True)
        self.name: str = tt["name"].getDebugName(6) or Path(self.path).stem
        self.upem: int = tt["head"].unitsPerEm
        self.bbox = (tt["head"].xMin, tt["head"].yMin, tt["head"].xMax, tt["head"].yMax)
        self.ascent: int = tt["hhea"].ascent
        self.descent: int = tt["hhea"].descent
        self.cap_height: int = getattr(tt["OS/2"], "sCapHeight", self.ascent)
        self._cmap: dict[int, str] = tt.getBestCmap()
        self._advance: dict[str, int] = {n: m[0] for n, m in tt["hmtx"].metrics.items()}
        self._kern: dict[tuple[str, str], int] = (
            dict(tt["kern"].kernTables[0].kernTable) if "kern" in tt else {}
        )
        self._glyf = tt["glyf"]
        self._top: dict[str, int] = {}

    def glyph(self, char: str) -> str:
        """Glyph name of ``char`` (``.notdef`` if the font has none)."""
        return self._cmap.get(ord(char), ".notdef")

    def layout(self, text: str) -> tuple[list[str], list[int], int]:
        """Glyph names of ``text``, the kerning before each (font units) and the total
        advance (font units)."""
        glyphs = [self.glyph(c) for c in text]
        kerns = [self._kern.get(pair, 0) for pair in itertools.pairwise(glyphs)]
        kerns = [0, *kerns] if glyphs else []
        return glyphs, kerns, sum(self._advance[g] for g in glyphs) + sum(kerns)

    def width(self, text: str, size: float) -> float:
        """Advance of ``text`` at ``size`` points, in points."""
        return self.layout(text)[2] * size / self.upem

    def top(self, text: str) -> int:
        """Highest point of ``text``'s glyphs and of 'l' above the baseline, font units (what
        a text aligned by its top is hung from)."""
        best = 0
        for name in {self.glyph(c) for c in text + "l"}:
            if name not in self._top:
                outline = self._glyf[name]
                self._top[name] = int(getattr(outline, "yMax", 0) or 0)
            best = max(best, self._top[name])
        return best

    def subset(self, chars: set[str]) -> tuple[bytes, dict[str, int], list[int], dict[int, str]]:
        """The subset holding ``chars``: font file bytes, glyph name → glyph id in the
        subset, advance of each subset glyph (1/1000 em), glyph id → its character."""
        options = subset.Options()
        options.drop_tables += list(DROPPED)
        options.notdef_outline = True
        options.name_IDs = [1, 2, 4, 6]
        options.glyph_names = True
        font = TTFont(self.path, lazy=True)
        subsetter = subset.Subsetter(options)
        subsetter.populate(unicodes=sorted(ord(c) for c in chars))
        logging.getLogger("fontTools.subset").setLevel(logging.ERROR)
        subsetter.subset(font)
        out = io.BytesIO()
        font.save(out)
        order = font.getGlyphOrder()
        ids = {name: k for k, name in enumerate(order)}
        widths = [round(font["hmtx"].metrics[n][0] * 1000 / self.upem) for n in order]
        text = {ids[self.glyph(c)]: c for c in sorted(chars) if self.glyph(c) in ids}
        return out.getvalue(), ids, widths, text

    @staticmethod
    def tag(chars: set[str]) -> str:
        """Six capitals naming the subset of ``chars`` (the same characters, the same tag)."""
        digest = hashlib.sha256("".join(sorted(chars)).encode()).digest()
        return "".join(chr(65 + b % 26) for b in digest[:6])


@cache
def pdf_font(family: str, bold: bool) -> PdfFont:
    """The metrics of ``family``, bold or regular (its lean copy), loaded once."""
    return PdfFont(lean_font(family, bold))

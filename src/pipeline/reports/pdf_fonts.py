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
        self._shared: Subset | None = None

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

    def subset(self, chars: set[str]) -> Subset:
        """The subset to embed for ``chars``: the cached :data:`REPERTOIRE` subset when it
        holds them all, else a subset of exactly ``chars``."""
        if chars <= REPERTOIRE:
            return self._repertoire()
        return self._make_subset(chars)

    def subset_chars(self, chars: set[str]) -> set[str]:
        """The characters the subset embedded for ``chars`` holds (names it: :meth:`tag`)."""
        return set(REPERTOIRE) if chars <= REPERTOIRE else chars

    def _repertoire(self) -> Subset:
        if self._shared is None:
            self._shared = self._load_repertoire()
        return self._shared

    def _load_repertoire(self) -> Subset:
        cached = FONTS / f"{Path(self.path).stem}-{self.tag(set(REPERTOIRE))}"
        font_file, index = cached.with_suffix(".ttf"), cached.with_suffix(".json")
        try:
            meta = json.loads(index.read_text())
            return (
                font_file.read_bytes(),
                meta["ids"],
                meta["widths"],
                {int(k): v for k, v in meta["text"].items()},
            )
        except (OSError, ValueError, KeyError):
            pass
        made = self._make_subset(set(REPERTOIRE))
        try:
            for path, data in (
                (font_file, made[0]),
                (index, json.dumps({"ids": made[1], "widths": made[2], "text": made[3]}).encode()),
            ):
                partial = path.with_suffix(f".{os.getpid()}.tmp")
                partial.write_bytes(data)
                partial.replace(path)  # atomic: parallel batch workers may write it at once
        except OSError:
            pass
        return made

    def _make_subset(self, chars: set[str]) -> Subset:
        from fontTools import subset  # type: ignore[import-untyped]

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
    """The metrics of ``family``, bold or regular, loaded once."""
    return PdfFont(str(FONTS / FILES[family, bold]))

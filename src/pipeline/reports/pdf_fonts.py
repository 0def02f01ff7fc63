"""The PDF report's fonts, lean: DejaVu Sans and Sans Mono without their OpenType layout
tables (GSUB, GPOS, GDEF), kept in matplotlib's cache directory.

The PDF embeds a subset of each font it uses (:mod:`matplotlib.backends.backend_pdf`, with
fontTools), and subsetting DejaVu's large layout tables is most of that work (about 0.5 s a
font, four fonts, twice each). A PDF viewer never reads those tables, and matplotlib lays
text out with the glyph advances and the ``kern`` table, which stay: the pages are the same,
made four times faster. The lean copy is written once per font version and reused.
"""

from __future__ import annotations

import os
from functools import cache
from pathlib import Path

import matplotlib
from matplotlib.font_manager import FontProperties, findfont

LAYOUT_TABLES = ("GSUB", "GPOS", "GDEF")


@cache
def lean_font(family: str, bold: bool) -> str:
    """Path of ``family`` (bold or regular) without its layout tables; the font itself if
    the lean copy cannot be written."""
    weight = "bold" if bold else "normal"
    source = Path(findfont(FontProperties(family=family, weight=weight)))
    stat = source.stat()
    target = Path(matplotlib.get_cachedir()) / "gyropipe-fonts"
    lean = target / f"{source.stem}-{stat.st_size}-{stat.st_mtime_ns}.ttf"
    if lean.is_file():
        return str(lean)
    try:
        from fontTools.ttLib import TTFont  # type: ignore[import-untyped]

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

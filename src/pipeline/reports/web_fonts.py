"""The charts' font in the HTML report: DejaVu Sans, regular and bold, embedded in the page.

Chart text is measured with DejaVu Sans metrics (:func:`~.charts.scene.text_width`), so a
page shown in any other font may let labels overflow their boxes or collide. The page
therefore carries the PDF's shipped repertoire subsets (:data:`~.pdf_fonts.REPERTOIRE`:
Latin-1, Greek and the symbols gyropipe prints, 44 KB each) as ``@font-face`` rules with
``data:`` URLs, under :data:`FAMILY`, a name no installed font has. The subsets leave out
the ``kern`` table (the PDF positions its glyphs itself) while the layout kerns, so the
page embeds the same subsets with the ``kern`` table kept (shipped beside them, made by
fontTools when missing), which browsers apply. Read and base64-encoded once per process:
134 KB of HTML (two fonts of 52 and 49 KB, base64), about 1 ms.
"""

from __future__ import annotations

import base64
from functools import cache

from pipeline.reports.pdf_fonts import pdf_font

FAMILY = "gyropipe-dejavu-sans"
"""The embedded font's family name (no installed font is called so)."""
SANS = "DejaVu Sans"


@cache
def embedded_font(bold: bool) -> bytes:
    """The repertoire subset of DejaVu Sans (``bold`` or regular) with its kerning pairs."""
    return pdf_font(SANS, bold).kerned_repertoire()


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

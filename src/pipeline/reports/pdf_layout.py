"""Page primitives of the PDF report: the A4 page geometry, text and rectangles placed in
inches from the page's bottom-left corner, text measurement and wrapping, and the flow that
puts pieces on pages."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

from pipeline.reports.pdf_canvas import MONO, PT, SANS, Page
from pipeline.reports.pdf_fonts import TEXTS, pdf_font
from pipeline.reports.plots import INK

__all__ = ["MONO", "SANS", "Page"]

PAGE_W, PAGE_H = 8.27, 11.69
LEFT, RIGHT = 0.7, 0.7
TOP, BOTTOM = 0.85, 0.8
WIDTH = PAGE_W - LEFT - RIGHT
MUTED = "#616e7c"

Draw = Callable[[Page, float], None]
"""Draws one piece onto a page with its top at the given height (inches)."""


@lru_cache(maxsize=TEXTS)
def text_width(text: str, size: float, bold: bool = False, family: str = SANS) -> float:
    """Width of ``text`` in inches at ``size`` points (the font's advances and kerning)."""
    return pdf_font(family, bold).width(text, size) / PT


def _fits(line: str, estimate: float, width: float, size: float, bold: bool) -> bool:
    """True if ``line`` is at most ``width`` inches wide: from ``estimate`` (the sum of its
    words and spaces) unless that is within 3 % of the width, measured then."""
    if estimate < 0.97 * width:
        return True
    if estimate > 1.03 * width:
        return False
    return text_width(line, size, bold) <= width


def wrap(text: str, width: float, size: float, bold: bool = False) -> list[str]:
    """Greedy word wrap of ``text`` into lines no wider than ``width`` inches (a word
    longer than a line is cut)."""
    lines: list[str] = []
    space = text_width("a a", size, bold) - 2 * text_width("a", size, bold)
    for paragraph in text.split("\n"):
        line, used = "", 0.0
        for word in paragraph.split(" "):
            trial = f"{line} {word}" if line else word
            estimate = used + (space if line else 0.0) + text_width(word, size, bold)
            if _fits(trial, estimate, width, size, bold):
                line, used = trial, estimate
                continue
            if line:
                lines.append(line)
            while text_width(word, size, bold) > width and len(word) > 1:
                cut = max(1, int(len(word) * width / text_width(word, size, bold)) - 1)
                lines.append(word[:cut])
                word = word[cut:]
            line, used = word, text_width(word, size, bold)
        lines.append(line)
    return lines


def text(
    page: Page,
    x: float,
    y: float,
    content: str,
    size: float,
    *,
    bold: bool = False,
    family: str = SANS,
    color: str = INK,
    ha: str = "left",
    va: str = "top",
) -> None:
    """Text at (x, y) inches: ``ha`` left/right/center, ``va`` top/baseline."""
    page.text(x, y, content, size, bold=bold, family=family, colour=color, ha=ha, va=va)


def lines(
    page: Page,
    x: float,
    top: float,
    rows: Sequence[str],
    size: float,
    step: float,
    *,
    bold: bool = False,
    color: str = INK,
) -> None:
    """Lines of text ``step`` inches apart, the first with its top at ``top``."""
    for k, row in enumerate(rows):
        text(page, x, top - k * step, row, size, bold=bold, color=color)


def rect(page: Page, x: float, y: float, w: float, h: float, colour: str) -> None:
    """A filled rectangle with its bottom-left corner at (x, y) inches."""
    page.rect(x, y, w, h, colour)


@dataclass
class Flow:
    """Pieces placed on pages from the top down: each page a list of (draw, top)."""

    pages: list[list[tuple[Draw, float]]] = field(default_factory=lambda: [[]])
    y: float = PAGE_H - TOP

    def room(self) -> float:
        """Inches left on the current page."""
        return self.y - BOTTOM

    def new_page(self) -> None:
        self.pages.append([])
        self.y = PAGE_H - TOP

    def place(self, height: float, draw: Draw, keep: float = 0.0) -> None:
        """Put a piece of ``height`` here (with ``keep`` more inches after it on the same
        page), or at the top of a new page if it does not fit."""
        if height + keep > self.room() and self.pages[-1]:
            self.new_page()
        self.pages[-1].append((draw, self.y))
        self.y -= height

"""A :class:`~pipeline.reports.document.Document` as an A4 PDF, laid out here and written
directly (:mod:`.pdf_canvas`): text is vector text in embedded fonts, figures are the vector
drawings the HTML's figures are (:class:`~pipeline.reports.figures.Figures`, each laid out
once) placed in a region of the page, tables continue over pages (:mod:`.pdf_table`)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from pipeline.reports.charts import pdf as chart_pdf
from pipeline.reports.charts.scene import Scene
from pipeline.reports.document import (
    Block,
    Document,
    Fields,
    Paragraph,
    Plot,
    Section,
    Table,
    Verdict,
)
from pipeline.reports.figures import Figures
from pipeline.reports.pdf_canvas import Page, write_pdf
from pipeline.reports.pdf_layout import (
    BOTTOM,
    LEFT,
    MUTED,
    PAGE_H,
    PAGE_W,
    TOP,
    WIDTH,
    Flow,
    lines,
    rect,
    text,
    text_width,
    wrap,
)
from pipeline.reports.pdf_table import place_table
from pipeline.reports.plots import GREY, NAVY

LEVEL_COLOURS = {
    "ok": ("#23867a", "#e6f4f1"),
    "warn": ("#b7791f", "#fdf4e3"),
    "fail": ("#c0392b", "#fbe9e7"),
    "info": ("#2f6fb0", "#eef4fb"),
}
FIELD_GAP = 0.35
"""Inches between side-by-side field blocks."""
LINE = 0.15
"""Line pitch of 7.5 pt body text, inches."""


Numbered = Iterator[tuple[int, Scene]]
"""The report's figures in order: (figure number, laid-out chart)."""


def render_pdf(doc: Document, path: Path, drawn: Figures | None = None) -> None:
    """Write ``doc`` to ``path`` as an A4 PDF (no creation date: same content, same bytes);
    figures from ``drawn`` (shared with the HTML)."""
    drawn = drawn or Figures()
    flow = Flow()
    flow.place(1.35, lambda page, top: _title_block(page, top, doc))
    numbers = ((n, drawn.scene(p)) for n, p in enumerate(doc.plots(), 1))
    for index, section in enumerate(doc.sections, 1):
        _section(flow, section, index, numbers)
    total = len(flow.pages)
    pages = []
    for number, pieces in enumerate(flow.pages, 1):
        page = Page(PAGE_W, PAGE_H)
        _page_frame(page, doc, number, total)
        for draw, top in pieces:
            draw(page, top)
        pages.append(page)
    write_pdf(pages, path, f"{doc.title} — {doc.subject}", "gyropipe")


def _title_block(page: Page, top: float, doc: Document) -> None:
    rect(page, LEFT, top - 0.06, WIDTH, 0.06, NAVY)
    text(page, LEFT, top - 0.16, "GYROPIPE", 7.5, bold=True, color=NAVY)
    text(page, LEFT, top - 0.34, doc.title, 19, bold=True, color=NAVY)
    text(page, LEFT, top - 0.74, doc.subject, 14, bold=True)
    text(page, LEFT, top - 1.02, doc.subtitle, 8.5, color=MUTED)
    text(page, LEFT + WIDTH, top - 0.16, doc.issued, 7.5, color=MUTED, ha="right")


def _page_frame(page: Page, doc: Document, number: int, total: int) -> None:
    """Running header (after the first page) and footer with the page number."""
    if number > 1:
        top = PAGE_H - TOP + 0.38
        text(page, LEFT, top, doc.title, 7.5, bold=True, color=NAVY, va="baseline")
        text(page, LEFT + WIDTH, top, doc.subject, 7.5, color=MUTED, ha="right", va="baseline")
        rect(page, LEFT, top - 0.09, WIDTH, 0.012, NAVY)
    foot = BOTTOM - 0.38
    rect(page, LEFT, foot + 0.16, WIDTH, 0.006, GREY)
    for k, line in enumerate(wrap(doc.footer, WIDTH - 1.0, 6.5)[:2]):
        text(page, LEFT, foot + 0.1 - 0.12 * k, line, 6.5, color=MUTED)
    text(page, LEFT + WIDTH, foot + 0.1, f"Page {number} of {total}", 6.5, color=MUTED, ha="right")


def _section(flow: Flow, section: Section, number: int, figures: Numbered) -> None:
    heading = f"{number}. {section.title}"

    def draw_heading(page: Page, top: float) -> None:
        text(page, LEFT, top - 0.12, heading, 11.5, bold=True, color=NAVY)
        rect(page, LEFT, top - 0.36, WIDTH, 0.018, NAVY)

    keep = _first_height(section.blocks[0]) if section.blocks else 0.0
    flow.place(0.5, draw_heading, keep=min(keep, PAGE_H - TOP - BOTTOM - 0.5))
    pending: list[Fields] = []
    for block in section.blocks:
        if isinstance(block, Fields) and _fits_half(block):
            pending.append(block)
            if len(pending) == 2:
                _fields_row(flow, pending)
                pending = []
            continue
        if pending:
            _fields_row(flow, pending)
            pending = []
        if isinstance(block, Fields):
            _fields_row(flow, [block])
        else:
            _block(flow, block, figures)
    if pending:
        _fields_row(flow, pending)


def _fits_half(block: Fields) -> bool:
    """True if ``block`` fits half the text width without wrapping (then it may share
    the row with another)."""
    half = (WIDTH - FIELD_GAP) / 2
    label_w = max((text_width(k, 7.5) for k, _ in block.items), default=0.0) + 0.15
    return all(text_width(v, 7.5, bold=True) <= half - label_w for _, v in block.items)


def _first_height(block: Block) -> float:
    """About how much of ``block`` must follow its section heading on the same page."""
    if isinstance(block, Plot):
        return _plot_height(block) + 0.8
    if isinstance(block, Fields):
        return 0.42 + LINE * len(block.items)
    return 1.0


def _plot_height(plot: Plot) -> float:
    """Height of ``plot`` scaled to the text width, inches."""
    return plot.size[1] * min(WIDTH, plot.size[0]) / plot.size[0]


def _block(flow: Flow, block: Block, figures: Numbered) -> None:
    if isinstance(block, Table):
        place_table(flow, block)
    elif isinstance(block, Verdict):
        _verdict(flow, block)
    elif isinstance(block, Paragraph):
        rows = wrap(block.text, WIDTH, 7.5)
        flow.place(
            LINE * len(rows) + 0.1,
            lambda page, top: lines(page, LEFT, top, rows, 7.5, LINE, color=MUTED),
        )
    elif isinstance(block, Plot):
        _plot(flow, block, *next(figures))
    else:
        raise TypeError(f"not a report block: {block!r}")


def _fields_row(flow: Flow, group: list[Fields]) -> None:
    """One or two field blocks side by side: grey labels, bold values wrapped to fit."""
    width = (WIDTH - FIELD_GAP * (len(group) - 1)) / len(group)
    laid = []
    for block in group:
        label_w = max((text_width(k, 7.5) for k, _ in block.items), default=0.0) + 0.15
        values = [wrap(v, width - label_w, 7.5, bold=True) for _, v in block.items]
        laid.append((block, label_w, values))
    height = max(0.3 + LINE * sum(len(v) for v in values) for _, _, values in laid) + 0.12

    def draw(page: Page, top: float) -> None:
        for col, (block, label_w, values) in enumerate(laid):
            x = LEFT + col * (width + FIELD_GAP)
            text(page, x, top, block.title, 8.5, bold=True, color=NAVY)
            y = top - 0.26
            for (label, _), value in zip(block.items, values, strict=True):
                text(page, x, y, label, 7.5, color=MUTED)
                lines(page, x + label_w, y, value, 7.5, LINE, bold=True)
                y -= LINE * len(value)

    flow.place(height, draw)


def _verdict(flow: Flow, block: Verdict) -> None:
    edge, fill = LEVEL_COLOURS[block.level]
    rows = wrap(block.text, WIDTH - 0.35, 8.5, bold=True)
    height = 0.16 * len(rows) + 0.14

    def draw(page: Page, top: float) -> None:
        rect(page, LEFT, top - height, WIDTH, height, fill)
        rect(page, LEFT, top - height, 0.06, height, edge)
        lines(page, LEFT + 0.17, top - 0.07, rows, 8.5, 0.16, bold=True)

    flow.place(height + 0.12, draw)


def _plot(flow: Flow, plot: Plot, number: int, scene: Scene) -> None:
    """The figure scaled to the text width, its numbered title and caption below."""
    width = min(WIDTH, plot.size[0])
    height = _plot_height(plot)
    heading = wrap(f"Figure {number}. {plot.title}.", WIDTH, 7.5, bold=True)
    caption = wrap(plot.caption, WIDTH, 7.5)
    x0 = LEFT + (WIDTH - width) / 2

    def draw(page: Page, top: float) -> None:
        chart_pdf.draw(page, scene, x0, top, width)
        below = top - height - 0.06
        lines(page, LEFT, below, heading, 7.5, LINE, bold=True)
        lines(page, LEFT, below - LINE * len(heading), caption, 7.5, LINE, color=MUTED)

    flow.place(height + LINE * (len(heading) + len(caption)) + 0.25, draw)

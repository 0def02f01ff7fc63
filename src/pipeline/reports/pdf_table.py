"""Tables of the PDF report, set in a monospaced font: each printed line of a row is one
string whose columns align by character count, which keeps a long survey listing to a few
dozen text objects per page. Tables continue over pages with their header repeated."""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass
from functools import cache, lru_cache

from pipeline.reports.document import Table
from pipeline.reports.pdf_layout import (
    LEFT,
    MONO,
    MUTED,
    WIDTH,
    Draw,
    Flow,
    Page,
    lines,
    rect,
    text,
    text_width,
    wrap,
)
from pipeline.reports.plots import NAVY

FONT_SIZES = (7.0, 6.5, 6.0, 5.5, 5.0)
GAP = 2
"""Spaces between columns at least."""
STRETCH_ABOVE = 0.55
"""Tables wider than this share of the text width are spread over all of it."""
MIN_ROWS = 4
"""A table starts on a new page unless this many of its rows fit below the header."""
KEEP_WHOLE = 20
"""Tables of at most this many rows are not split (they move to the next page)."""
MIN_WRAP = 12
"""Characters a wrapped column keeps at least."""
SHORT_HEADER = 6
"""Headers of at most this many characters ('σ AZI') are not wrapped."""
TAIL = 0.15
"""Space below a table, inches."""
ZEBRA = "#f3f5f8"
MARKED = "#fbe3e0"
FLAGGED = "#fcebc0"
FLAG_EDGE = "#d9a21b"
UNIT_INK = "#d5dfeb"
WRAPPED = 1024
"""Most (text, width) pairs whose wrapped lines a process keeps (headers and QC labels
recur in every report)."""


@cache
def char_width(size: float) -> float:
    """Advance of one character of the monospaced font, inches."""
    return text_width("0", size, family=MONO)


@dataclass(frozen=True)
class _Setting:
    size: float
    widths: list[int]
    gaps: list[int]
    header: list[str]
    unit: str
    rows: list[list[str]]
    """per table row, its printed lines"""

    @property
    def pitch(self) -> float:
        return self.size * 1.32 / 72.0

    @property
    def width(self) -> float:
        return (sum(self.widths) + sum(self.gaps) + 2) * char_width(self.size)

    def row_height(self, k: int) -> float:
        return len(self.rows[k]) * self.pitch + 0.035

    def cell_span(self, j: int) -> tuple[float, float]:
        """Left edge and width of column ``j``, inches from the table's left edge (half a
        character of padding each side, within the gaps)."""
        start = 1 + sum(self.widths[:j]) + sum(self.gaps[:j])
        char = char_width(self.size)
        return (start - 0.5) * char, (self.widths[j] + 1.0) * char


def _setting(table: Table) -> _Setting:
    cols = table.columns
    data = list(zip(*table.rows, strict=True)) if table.rows else [()] * len(cols)
    natural = [
        max(
            max(map(len, data[j]), default=0),
            len(col.header)
            if len(col.header) <= SHORT_HEADER
            else max((len(w) for w in col.header.split()), default=0),
            len(col.unit),
        )
        for j, col in enumerate(cols)
    ]
    gaps = [GAP] * (len(cols) - 1)
    for size in FONT_SIZES:
        room = math.floor(WIDTH / char_width(size)) - 2 - sum(gaps)
        fixed = sum(w for w, c in zip(natural, cols, strict=True) if not c.wrap)
        wraps = [j for j, c in enumerate(cols) if c.wrap]
        if fixed + MIN_WRAP * len(wraps) <= room or size == FONT_SIZES[-1]:
            break
    widths = list(natural)
    spare = room - fixed
    for j in wraps:
        widths[j] = max(MIN_WRAP, min(natural[j], spare // len(wraps)))
    used = sum(widths) + sum(gaps) + 2
    if used * char_width(size) > STRETCH_ABOVE * WIDTH and gaps:
        extra = max(room + sum(gaps) + 2 - used, 0)
        gaps = [
            g + extra // len(gaps) + (1 if k < extra % len(gaps) else 0) for k, g in enumerate(gaps)
        ]
    line = _line(widths, gaps, table).format
    header_lines = [_wrapped(c.header, w) for c, w in zip(cols, widths, strict=True)]
    depth = max(len(h) for h in header_lines)
    padded = [[""] * (depth - len(h)) + list(h) for h in header_lines]  # headers sit on the units
    header = [line(*(p[i] for p in padded)) for i in range(depth)]
    unit = line(*(c.unit for c in cols)) if any(c.unit for c in cols) else ""
    rows = []
    for row in table.rows:
        if not wraps:
            rows.append([line(*row)])
            continue
        wrapped = {j: _wrapped(row[j], widths[j]) for j in wraps}
        depth = max(map(len, wrapped.values()))
        printed = []
        for i in range(depth):  # the wrapped cells' i-th lines, the others' first line only
            cells = list(row) if i == 0 else [""] * len(row)
            for j, found in wrapped.items():
                cells[j] = found[i] if i < len(found) else ""
            printed.append(line(*cells))
        rows.append(printed)
    return _Setting(size, widths, gaps, header, unit, rows)


@lru_cache(maxsize=WRAPPED)
def _wrapped(value: str, width: int) -> tuple[str, ...]:
    """``value`` wrapped into lines of ``width`` characters at most (a word cut if longer);
    one empty line for an empty value."""
    return tuple(textwrap.wrap(value, width, break_long_words=True)) or ("",)


def _line(widths: list[int], gaps: list[int], table: Table) -> str:
    """The format of a printed line: a leading space, then each column's cell aligned in
    its width and the gap after it."""
    out = " "
    for j, (width, col) in enumerate(zip(widths, table.columns, strict=True)):
        out += f"{{:{'>' if col.align == 'right' else '<'}{width}}}"
        if j < len(gaps):
            out += " " * gaps[j]
    return out


def place_table(flow: Flow, table: Table) -> None:
    """Put ``table`` on the pages, continued with its header repeated where it breaks."""
    setting = _setting(table)
    flagged: dict[int, list[int]] = {}  # row → its flagged columns, once for every piece
    for k, j in sorted(table.cells):
        flagged.setdefault(k, []).append(j)
    head_h = (len(setting.header) + (1 if setting.unit else 0)) * setting.pitch + 0.07
    title_h = 0.26 if table.title else 0.0
    count = len(setting.rows)
    start = 0
    while True:
        room = flow.room() - title_h - head_h - TAIL
        end, used = start, 0.0
        while end < count and used + setting.row_height(end) <= room:
            used += setting.row_height(end)
            end += 1
        short = start == 0 and count <= KEEP_WHOLE and end < count
        if (short or end - start < min(MIN_ROWS, count - start)) and flow.pages[-1]:
            flow.new_page()
            continue
        end = min(max(end, start + 1), count)
        chunk = range(start, end)
        title = table.title if start == 0 else f"{table.title} (continued)"
        height = title_h + head_h + sum(setting.row_height(k) for k in chunk) + TAIL
        flow.place(height, _piece(table, setting, flagged, chunk, title, head_h))
        start = end
        if start >= count:
            break
        flow.new_page()
    if table.note:
        note = wrap(table.note, WIDTH, 7)
        flow.place(
            0.13 * len(note) + 0.12,
            lambda page, top: lines(page, LEFT, top, note, 7, 0.13, color=MUTED),
        )


def _piece(
    table: Table,
    setting: _Setting,
    flagged: dict[int, list[int]],
    rows: range,
    title: str,
    head_h: float,
) -> Draw:
    size, pitch, width = setting.size, setting.pitch, setting.width

    def draw(page: Page, top: float) -> None:
        y = top
        if table.title:
            text(page, LEFT, y, title, 8.5, bold=True, color=NAVY)
            y -= 0.26
        rect(page, LEFT, y - head_h, width, head_h, NAVY)
        for i, line in enumerate(setting.header):
            text(
                page, LEFT, y - 0.035 - i * pitch, line, size, bold=True, family=MONO, color="white"
            )
        if setting.unit:
            text(
                page,
                LEFT,
                y - 0.035 - len(setting.header) * pitch,
                setting.unit,
                size,
                family=MONO,
                color=UNIT_INK,
            )
        y -= head_h
        for n, k in enumerate(rows):
            h = setting.row_height(k)
            if k in table.marked:
                rect(page, LEFT, y - h, width, h, MARKED)
            elif n % 2:
                rect(page, LEFT, y - h, width, h, ZEBRA)
            for j in flagged.get(k, ()):
                x, w = setting.cell_span(j)
                rect(page, LEFT + x, y - h, w, h, FLAGGED)
                rect(page, LEFT + x, y - h, 0.02, h, FLAG_EDGE)
            for i, line in enumerate(setting.rows[k]):
                text(page, LEFT, y - 0.02 - i * pitch, line, size, family=MONO)
            y -= h
        rect(page, LEFT, y - 0.006, width, 0.006, NAVY)

    return draw

"""The content of a report as plain data, rendered alike to HTML (:mod:`.html`) and PDF
(:mod:`.pdf`): a title block, then sections of key–value fields, tables, verdicts,
paragraphs and figures. Building the content once and rendering it twice is what keeps the
two formats the same report."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from pipeline.reports.plots import Canvas

Level = Literal["ok", "warn", "fail", "info"]
Align = Literal["left", "right"]


@dataclass(frozen=True)
class Fields:
    """Labelled values (``label``, ``value``), e.g. the well header."""

    title: str
    items: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class Column:
    """A table column: header text, unit (shown under the header) and alignment."""

    header: str
    unit: str = ""
    align: Align = "right"
    wrap: bool = False
    """long text: wrapped to the width left by the other columns"""


@dataclass(frozen=True)
class Table:
    """A table of preformatted cells. ``marked`` rows are highlighted (failed QC)."""

    title: str
    columns: tuple[Column, ...]
    rows: tuple[tuple[str, ...], ...]
    kind: str = "table"
    """CSS class / identifier (``listing`` for the survey listing)"""
    note: str = ""
    marked: frozenset[int] = frozenset()


@dataclass(frozen=True)
class Verdict:
    """A highlighted statement: a QC outcome or the linearity verdict."""

    level: Level
    text: str


@dataclass(frozen=True)
class Paragraph:
    """A line of explanatory text."""

    text: str


@dataclass(frozen=True)
class Plot:
    """A figure drawn by ``draw`` into a matplotlib figure or subfigure of ``size``
    (width, height in inches; the PDF scales it to the text width)."""

    key: str
    title: str
    caption: str
    draw: Callable[[Canvas], None]
    size: tuple[float, float] = (7.0, 4.2)


Block = Fields | Table | Verdict | Paragraph | Plot


@dataclass(frozen=True)
class Section:
    """A titled part of the report."""

    title: str
    blocks: tuple[Block, ...]
    key: str = ""


@dataclass(frozen=True)
class Document:
    """A whole report: what the title block says and the sections below it."""

    title: str
    subject: str
    """the well (or instrument) the report is about"""
    subtitle: str
    issued: str
    """date line of the title block"""
    footer: str
    """short provenance line printed on every page"""
    sections: tuple[Section, ...] = field(default_factory=tuple)

    def plots(self) -> list[Plot]:
        """Every figure of the report, in order."""
        return [b for s in self.sections for b in s.blocks if isinstance(b, Plot)]


def fmt(value: float | None, decimals: int = 2) -> str:
    """A number with fixed decimals; blank for null, '—' for NaN."""
    if value is None:
        return ""
    if math.isnan(value):
        return "—"
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    text = f"{value:.{decimals}f}"
    return text.replace("-", "−") if text.lstrip("-").strip("0. ") else text.lstrip("-")


def fmt_sig(value: float | None, digits: int = 3) -> str:
    """A number with ``digits`` significant digits (small σ, p-values)."""
    if value is None:
        return ""
    if not math.isfinite(value):
        return fmt(value)
    return f"{value:.{digits}g}".replace("-", "−")


def items(pairs: Sequence[tuple[str, str | None]]) -> tuple[tuple[str, str], ...]:
    """Label–value pairs without the empty ones."""
    return tuple((k, v) for k, v in pairs if v not in (None, ""))

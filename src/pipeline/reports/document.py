"""The content of a report as plain data, rendered alike to HTML (:mod:`.html`) and PDF
(:mod:`.pdf`): a title block, then sections of key–value fields, tables, verdicts,
paragraphs and figures. Building the content once and rendering it twice is what keeps the
two formats the same report."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

from pipeline.reports.numbers import fmt, fmt_azimuth, fmt_sig, fmt_sigma

if TYPE_CHECKING:
    from pipeline.reports.charts.model import Chart

__all__ = [
    "Align",
    "Block",
    "Column",
    "Document",
    "Fields",
    "Level",
    "Paragraph",
    "Plot",
    "Section",
    "Table",
    "Verdict",
    "fmt",
    "fmt_azimuth",
    "fmt_sig",
    "fmt_sigma",
    "items",
]

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
    """A table of preformatted cells. ``marked`` rows are highlighted whole (a station that
    failed QC); ``cells`` are highlighted one by one (a value a flag applies to)."""

    title: str
    columns: tuple[Column, ...]
    rows: tuple[tuple[str, ...], ...]
    kind: str = "table"
    """CSS class / identifier (``listing`` for the survey listing)"""
    note: str = ""
    marked: frozenset[int] = frozenset()
    """indices of rows marked whole"""
    cells: frozenset[tuple[int, int]] = frozenset()
    """(row, column) indices of cells marked one by one"""


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
    """A figure: ``draw`` describes it as a chart of ``size`` (width, height in inches; the
    PDF scales it to the text width)."""

    key: str
    title: str
    caption: str
    draw: Callable[[tuple[float, float]], Chart]
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


def items(pairs: Sequence[tuple[str, str | None]]) -> tuple[tuple[str, str], ...]:
    """Label–value pairs without the empty ones."""
    return tuple((k, v) for k, v in pairs if v not in (None, ""))

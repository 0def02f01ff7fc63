"""What plugins add to the reports, through the hook ``gyropipe_register_report_parts``.

A :class:`ReportDef` can do two things: state the method of the stage of the same name
(``method``: a :class:`MethodNote` in the report's Method table, its papers cited), and add a
whole section (``section``: a :class:`ReportSection` of paragraphs, tables with units and an
optional figure). Both are plain data, drawn alike by the HTML and the PDF renderer, so one
description serves both documents. Built-in stages describe themselves the same way.
Client documents speak to clients: cite methods by their published papers
(:meth:`ReportContext.cite`), never by internal stage or parameter names.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import pyarrow as pa

from pipeline.provenance import Provenance, StageSetup
from pipeline.well import WellMetadata

DocumentKind = Literal["survey", "calibration"]
"""The reports: the survey report (stage ``report``), the drift calibration report."""


@dataclass(frozen=True)
class MethodNote:
    """A stage's line in the report's Method table: ``label`` (e.g. "Gyrocompassing") and
    what was done, in the client's words. The first stage of a run giving a label states it."""

    label: str
    text: str


@dataclass(frozen=True)
class ReportTable:
    """A table of preformatted cells: ``columns`` are (header, unit) pairs (unit "" for
    none); the first column is aligned left, the others right."""

    title: str
    columns: tuple[tuple[str, str], ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""


@dataclass(frozen=True)
class ReportLine:
    """One series of a figure: y against x (same length; NaN breaks the line)."""

    label: str
    x: Sequence[float]
    y: Sequence[float]


@dataclass(frozen=True)
class ReportFigure:
    """A line chart: the series against one x axis, a legend of their labels."""

    title: str
    caption: str
    x_label: str
    y_label: str
    lines: tuple[ReportLine, ...]
    height: float = 3.4
    """inches, at the report's 6.9 in figure width"""


@dataclass(frozen=True)
class ReportSection:
    """A whole section of a report: paragraphs, then tables, then the figure."""

    title: str
    paragraphs: tuple[str, ...] = ()
    tables: tuple[ReportTable, ...] = ()
    figure: ReportFigure | None = None


class ReportContext(Protocol):
    """What a report part is given: the document being made and what it is made of."""

    @property
    def document(self) -> DocumentKind: ...

    @property
    def tables(self) -> Mapping[str, pa.Table]:
        """The report stage's input tables by port (``trajectory``, ``stations``, ``qc``…;
        the calibration report: ``result``, ``series``, ``readings``), those wired only."""
        ...

    @property
    def well(self) -> WellMetadata: ...

    @property
    def provenance(self) -> Provenance:
        """The run: its stages with their params (``provenance.stages``), inputs, versions."""
        ...

    def cite(self, work: str) -> str:
        """The citation mark ('[2]') of a published ``work`` (its reference-list entry),
        listed under References in the order of first citation."""
        ...

    def error_model(self, name: str) -> tuple[str, bool]:
        """The title of the tool (error) model ``name`` (its name if it cannot be found)
        and whether it is a gyro model (it reads the latitude)."""
        ...


MethodFunc = Callable[[StageSetup, ReportContext], MethodNote | None]
SectionFunc = Callable[[ReportContext], ReportSection | None]


@dataclass(frozen=True)
class ReportDef:
    """A report part. ``method(stage, ctx)`` states the method of a run's stage whose
    ``uses`` is ``name`` (None: nothing to state); ``section(ctx)`` adds a section to each
    report it returns one for (None: not this document, or nothing to show), after the
    built-in sections and before Provenance, in the order the plugins were loaded. A part
    that raises or returns something else fails the report, naming its plugin."""

    name: str
    method: MethodFunc | None = None
    section: SectionFunc | None = None

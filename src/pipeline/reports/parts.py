"""The report parts plugins register (:mod:`pipeline.reporting`), called for one document:
the Method table's statements of the run's stages and the sections plugins add, turned
into the document's blocks. A part that raises or returns something else is a
:class:`~pipeline.errors.PluginError` naming its plugin (the report stage fails with it)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeVar

import numpy as np
import pyarrow as pa

from pipeline.errors import PluginError
from pipeline.registry import PluginInfo, Provenance
from pipeline.reporting import (
    DocumentKind,
    MethodNote,
    ReportContext,
    ReportDef,
    ReportFigure,
    ReportSection,
    ReportTable,
)
from pipeline.reports.charts.model import Axis, Chart, Line, Panel, grid
from pipeline.reports.document import Block, Column, Paragraph, Plot, Section, Table
from pipeline.reports.literature import Citations
from pipeline.reports.plots import series_colour
from pipeline.reports.sections import error_model
from pipeline.uncertainty.engine import ModelCatalogue
from pipeline.well import WellMetadata

T = TypeVar("T")
Registered = Sequence[tuple[ReportDef, PluginInfo]]
"""Report parts with the plugins that registered them (``StageContext.report_parts()``)."""


class _Uncounted(Citations):
    """Citations that number nothing: a statement is asked with them before it is kept."""

    def cite(self, work: str) -> str:
        return ""


@dataclass(frozen=True)
class Parts:
    """The report parts as one document calls them: the
    :class:`~pipeline.reporting.ReportContext` they are given."""

    registered: Registered
    document: DocumentKind
    tables: Mapping[str, pa.Table]
    well: WellMetadata
    provenance: Provenance
    citations: Citations

    def cite(self, work: str) -> str:
        return self.citations.cite(work)

    def error_model(self, name: str) -> tuple[str, bool]:
        return error_model(name, ModelCatalogue.of(self.provenance.tool_models))

    def methods(self) -> list[tuple[str, str]]:
        """(label, statement) of the run's stages that state their method, the first stage
        of each label; only the statements printed cite their papers."""
        by_stage = {
            part.name: (part.method, part, info)
            for part, info in self.registered
            if part.method is not None
        }
        probe: ReportContext = dataclasses.replace(self, citations=_Uncounted())
        found: dict[str, str] = {}
        for stage in self.provenance.stages:
            if stage.uses not in by_stage:
                continue
            method, part, info = by_stage[stage.uses]
            said = _called(part, info, "method", partial(method, stage, probe), MethodNote)
            if said is None or said.label in found:
                continue
            note = _called(part, info, "method", partial(method, stage, self), MethodNote)
            if note is not None:
                found[note.label] = note.text
        return list(found.items())

    def sections(self) -> list[Section]:
        """The sections plugins add to this document, in registration order."""
        made = []
        for part, info in self.registered:
            if part.section is None:
                continue
            section = _called(part, info, "section", partial(part.section, self), ReportSection)
            if section is not None:
                made.append(_blocks(part, info, section))
        return made


def _called(
    part: ReportDef, info: PluginInfo, what: str, call: Callable[[], Any], kind: type[T]
) -> T | None:
    """``call()``: None or a ``kind``; anything else, or an exception, is the plugin's error."""
    try:
        result = call()
    except Exception as exc:  # a part's bug is reported against its plugin
        raise _error(part, info, f"{what} raised {type(exc).__name__}: {exc}") from exc
    if result is not None and not isinstance(result, kind):
        raise _error(
            part, info, f"{what} returned a {type(result).__name__}, not a {kind.__name__}"
        )
    return result


def _error(part: ReportDef, info: PluginInfo, message: str) -> PluginError:
    return PluginError(info.name, info.version, f"report part {part.name!r}: {message}")


def _blocks(part: ReportDef, info: PluginInfo, section: ReportSection) -> Section:
    """A plugin's section as the document's: paragraphs, tables, the figure."""
    key = "part-" + part.name.replace(".", "-").replace("_", "-")
    blocks: list[Block] = [Paragraph(str(text)) for text in section.paragraphs]
    for table in section.tables:
        blocks.append(_table(part, info, table))
    if section.figure is not None:
        figure = section.figure
        for line in figure.lines:
            if len(line.x) != len(line.y):
                raise _error(part, info, f"figure line {line.label!r}: x and y differ in length")
        blocks.append(
            Plot(
                key,
                figure.title,
                figure.caption,
                partial(line_chart, figure=figure),
                (6.9, figure.height),
            )
        )
    return Section(section.title, tuple(blocks), key=key)


def _table(part: ReportDef, info: PluginInfo, table: ReportTable) -> Table:
    width = len(table.columns)
    for k, row in enumerate(table.rows, 1):
        if len(row) != width or not all(isinstance(cell, str) for cell in row):
            raise _error(
                part,
                info,
                f"table {table.title!r} row {k}: expected {width} text cells, got {row!r}",
            )
    columns = tuple(
        Column(header, unit, align="left" if i == 0 else "right")
        for i, (header, unit) in enumerate(table.columns)
    )
    return Table(table.title, columns, tuple(table.rows), kind="part", note=table.note)


def line_chart(size: tuple[float, float], figure: ReportFigure) -> Chart:
    """A plugin's figure: its lines against one x axis, labelled in a legend."""
    (box,) = grid(size)
    labelled = any(line.label for line in figure.lines)
    panel = Panel(
        box, Axis(figure.x_label), Axis(figure.y_label), legend="upper right" if labelled else None
    )
    for k, line in enumerate(figure.lines):
        x, y = np.asarray(line.x, dtype=float), np.asarray(line.y, dtype=float)
        panel.add(Line(x, y, series_colour(k), label=line.label))
    return Chart(size, [panel])

"""A chart to show or save: SVG in a notebook (``_repr_svg_``), ``.svg`` or ``.pdf`` files —
what the notebook API returns."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pipeline.reports.charts.layout import lay_out
from pipeline.reports.charts.model import Chart
from pipeline.reports.charts.svg import to_svg


@dataclass
class Drawing:
    """``chart``, drawn: Jupyter shows it, :meth:`save` writes it as vector graphics."""

    chart: Chart

    def svg(self) -> str:
        """The chart as an SVG document."""
        return to_svg(lay_out(self.chart))

    def _repr_svg_(self) -> str:
        return self.svg()

    def save(self, path: str | Path) -> Path:
        """Write the chart to ``path``: ``.svg`` (with the fonts its text was measured
        with embedded, ≈ 134 KB) or ``.pdf`` (its size, vector)."""
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix == ".svg":
            from pipeline.reports.web_fonts import font_faces

            svg = to_svg(lay_out(self.chart), style=font_faces())
            path.write_text(svg, encoding="utf-8")
        elif suffix == ".pdf":
            from pipeline.reports.charts.pdf import chart_pdf

            chart_pdf(lay_out(self.chart), path)
        else:
            raise ValueError(f"{path}: a chart is saved as .svg or .pdf, not {suffix!r}")
        return path

"""Figures of a report, each laid out once and shared by the HTML and the PDF: a plot's
chart (:mod:`.charts.model`) is laid out on first use into a scene of vector primitives
(:mod:`.charts.layout`) that the HTML writes as inline SVG and the PDF as path operators
— the same drawing in both, nothing rasterised."""

from __future__ import annotations

from pipeline.reports.charts.layout import lay_out
from pipeline.reports.charts.scene import Scene
from pipeline.reports.charts.svg import to_svg
from pipeline.reports.document import Plot


class Figures:
    """The figures of one report: :meth:`scene` for the PDF, :meth:`svg` for the HTML."""

    def __init__(self) -> None:
        self._scenes: dict[int, tuple[Plot, Scene]] = {}

    def scene(self, plot: Plot) -> Scene:
        """``plot`` laid out (once) at its size, points."""
        found = self._scenes.get(id(plot))
        if found is None:
            found = (plot, lay_out(plot.draw(plot.size)))
            self._scenes[id(plot)] = found  # the plot is kept, so its id stays its own
        return found[1]

    def svg(self, plot: Plot) -> str:
        """``plot`` as an SVG element for the HTML page (its ids prefixed by its key)."""
        return to_svg(self.scene(plot), f"{plot.key}-", plot.title)

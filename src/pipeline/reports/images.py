"""Figures of a report, each drawn once and shared by the HTML and the PDF.

A plot is drawn into one matplotlib figure and rasterised once at :data:`PRINT_DPI`
(palette-quantised): that raster is the PDF's figure, and the HTML's PNG is the same
drawing scaled to the page's ``dpi``. ``svg`` asks for the same figure saved as SVG for the
HTML. Quantising is Pillow's fast octree (a plot's few colours and their anti-aliased
blends fit 256 entries); the PNG is compressed once (no trial of filters).
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Literal

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from pipeline.reports.document import Plot
from pipeline.reports.plots import STYLE

ImageFormat = Literal["auto", "png", "svg"]
"""Figures in the HTML: ``png`` (``auto``, the default, is PNG too) or ``svg``."""
CSS_DPI = 96
PRINT_DPI = 200
"""Resolution of the raster every figure is drawn to once (the PDF's figures), dots/inch."""


@dataclass(frozen=True)
class Encoded:
    """An encoded figure: MIME type, bytes and its display size in CSS pixels."""

    mime: str
    data: bytes
    width: int
    height: int


@dataclass
class _Drawn:
    figure: Figure
    rgb: Image.Image | None = None
    raster: Image.Image | None = None


class Figures:
    """The figures of one report, each drawn on first use and kept for every later one:
    :meth:`raster` for the PDF, :meth:`encode` for the HTML (``dpi`` for its PNGs)."""

    def __init__(self, image_format: ImageFormat = "auto", dpi: int = 110) -> None:
        self.image_format = image_format
        self.dpi = dpi
        self.raster_dpi = max(PRINT_DPI, dpi)
        self._drawn: dict[int, tuple[Plot, _Drawn]] = {}

    def _figure(self, plot: Plot) -> _Drawn:
        found = self._drawn.get(id(plot))
        if found is None:
            with matplotlib.rc_context(STYLE):
                fig = Figure(figsize=plot.size, dpi=self.raster_dpi)
                FigureCanvasAgg(fig)
                plot.draw(fig)
            found = (plot, _Drawn(fig))
            self._drawn[id(plot)] = found  # the plot is kept, so its id stays its own
        return found[1]

    def raster(self, plot: Plot) -> Image.Image:
        """``plot`` at :attr:`raster_dpi`, quantised to at most 256 colours (mode ``P``)."""
        drawn = self._figure(plot)
        if drawn.raster is None:
            with matplotlib.rc_context(STYLE):
                canvas = drawn.figure.canvas
                canvas.draw()
                rgba = np.asarray(canvas.buffer_rgba())  # type: ignore[attr-defined]
            drawn.rgb = Image.fromarray(rgba).convert("RGB")
            drawn.raster = _quantise(drawn.rgb)
        return drawn.raster

    def encode(self, plot: Plot) -> Encoded:
        """``plot`` for the HTML: PNG at :attr:`dpi` (from the shared raster) or SVG."""
        width, height = round(plot.size[0] * CSS_DPI), round(plot.size[1] * CSS_DPI)
        if self.image_format == "svg":
            return Encoded("image/svg+xml", self._svg(plot), width, height)
        image = self.raster(plot)
        if self.dpi != self.raster_dpi:
            rgb = self._figure(plot).rgb
            assert rgb is not None  # drawn by raster()
            size = (round(plot.size[0] * self.dpi), round(plot.size[1] * self.dpi))
            image = _quantise(rgb.resize(size, Image.Resampling.LANCZOS, reducing_gap=2.0))
        out = io.BytesIO()
        image.save(out, format="PNG")
        return Encoded("image/png", out.getvalue(), width, height)

    def _svg(self, plot: Plot) -> bytes:
        out = io.BytesIO()
        with matplotlib.rc_context(STYLE):
            self._figure(plot).figure.savefig(
                out, format="svg", dpi=self.dpi, metadata={"Date": None}
            )
        return out.getvalue()


def _quantise(image: Image.Image) -> Image.Image:
    return image.quantize(256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)

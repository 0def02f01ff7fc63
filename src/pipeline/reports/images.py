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


@dataclass(frozen=True)
class _Drawn:
    raster: Image.Image
    html: Encoded | None


class Figures:
    """The figures of one report, each drawn on first use and kept, as images, for every
    later one: :meth:`raster` for the PDF, :meth:`encode` for the HTML (``dpi`` for its PNGs;
    ``html=False`` when no HTML is written). A figure's matplotlib drawing and full-colour
    pixels are released as soon as its images are made: a report holds compressed images,
    not canvases."""

    def __init__(self, image_format: ImageFormat = "auto", dpi: int = 110, *, html: bool = True):
        self.image_format = image_format
        self.dpi = dpi
        self.html = html
        self.raster_dpi = max(PRINT_DPI, dpi)
        self._drawn: dict[int, tuple[Plot, _Drawn]] = {}

    def _images(self, plot: Plot) -> _Drawn:
        found = self._drawn.get(id(plot))
        if found is None:
            found = (plot, self._draw(plot))
            self._drawn[id(plot)] = found  # the plot is kept, so its id stays its own
        return found[1]

    def _draw(self, plot: Plot) -> _Drawn:
        with matplotlib.rc_context(STYLE):
            fig = Figure(figsize=plot.size, dpi=self.raster_dpi)
            FigureCanvasAgg(fig)
            plot.draw(fig)
            fig.canvas.draw()
            rgba = np.asarray(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
            rgb = Image.fromarray(rgba).convert("RGB")
            raster = _quantise(rgb)
            html = None
            if self.html:
                html = (
                    self._svg(fig, plot)
                    if self.image_format == "svg"
                    else self._png(rgb, raster, plot)
                )
        return _Drawn(raster, html)

    def raster(self, plot: Plot) -> Image.Image:
        """``plot`` at :attr:`raster_dpi`, quantised to at most 256 colours (mode ``P``)."""
        return self._images(plot).raster

    def encode(self, plot: Plot) -> Encoded:
        """``plot`` for the HTML: PNG at :attr:`dpi` (from the shared raster) or SVG."""
        html = self._images(plot).html
        if html is None:
            raise ValueError("these figures were drawn without their HTML images (html=False)")
        return html

    def _png(self, rgb: Image.Image, raster: Image.Image, plot: Plot) -> Encoded:
        image = raster
        if self.dpi != self.raster_dpi:
            size = (round(plot.size[0] * self.dpi), round(plot.size[1] * self.dpi))
            image = _quantise(rgb.resize(size, Image.Resampling.LANCZOS, reducing_gap=2.0))
        out = io.BytesIO()
        image.save(out, format="PNG")
        return Encoded("image/png", out.getvalue(), *_css_size(plot))

    def _svg(self, fig: Figure, plot: Plot) -> Encoded:
        out = io.BytesIO()
        fig.savefig(out, format="svg", dpi=self.dpi, metadata={"Date": None})
        return Encoded("image/svg+xml", out.getvalue(), *_css_size(plot))


def _css_size(plot: Plot) -> tuple[int, int]:
    return round(plot.size[0] * CSS_DPI), round(plot.size[1] * CSS_DPI)


def _quantise(image: Image.Image) -> Image.Image:
    return image.quantize(256, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)

"""Figures of a report rendered to self-contained image bytes (PNG or SVG) for the HTML."""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import Literal

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from pipeline.reports.document import Plot
from pipeline.reports.plots import STYLE

ImageFormat = Literal["auto", "png", "svg"]
CSS_DPI = 96


@dataclass(frozen=True)
class Encoded:
    """An encoded figure: MIME type, bytes and its display size in CSS pixels."""

    mime: str
    data: bytes
    width: int
    height: int


def encode(plot: Plot, image_format: ImageFormat = "auto", dpi: int = 110) -> Encoded:
    """``plot`` as PNG (``dpi``, palette-quantised) or SVG; ``auto`` keeps the smaller."""
    width, height = round(plot.size[0] * CSS_DPI), round(plot.size[1] * CSS_DPI)
    formats = ("png", "svg") if image_format == "auto" else (image_format,)
    candidates = [
        Encoded(f"image/{'svg+xml' if f == 'svg' else f}", _save(plot, f, dpi), width, height)
        for f in formats
    ]
    return min(candidates, key=lambda image: len(image.data))


def _save(plot: Plot, image_format: str, dpi: int) -> bytes:
    out = io.BytesIO()
    with matplotlib.rc_context(STYLE):
        fig = Figure(figsize=plot.size, dpi=dpi)
        FigureCanvasAgg(fig)
        plot.draw(fig)
        fig.savefig(out, format=image_format, dpi=dpi, metadata=_no_date(image_format))
    if image_format != "png":
        return out.getvalue()
    out.seek(0)
    image = Image.open(out).convert("RGB").quantize(256, dither=Image.Dither.NONE)
    small = io.BytesIO()
    image.save(small, format="PNG", optimize=True)
    return small.getvalue()


def _no_date(image_format: str) -> dict[str, str | None]:
    """Metadata that keeps the bytes reproducible (no creation date)."""
    return {"Date": None} if image_format == "svg" else {}

"""A panel's legend: one row per labelled artist (a sample of its line, marker or fill and
the label), in a corner of the panel, the corner covering the fewest data points
(``best``), or right of the panel (``outside``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pipeline.reports.charts.model import Band, Bars, ErrorBars, Line, Panel, Polygon, Span
from pipeline.reports.charts.scene import (
    Group,
    Item,
    Marks,
    Path,
    Stroke,
    anchored,
    covered,
    faded,
    points,
    text_width,
)

INK = "#1f2933"
ORDER = (
    "upper right",
    "upper left",
    "lower left",
    "lower right",
    "center right",
    "center left",
    "lower center",
    "upper center",
)
"""Where ``best`` looks, in this order (ties go to the first)."""


def _handle(a: object, x: float, y: float, length: float, size: float) -> list[Item]:
    """The legend's sample of artist ``a`` spanning ``length`` pt from (x, y) (its middle
    line)."""
    segment = np.array([[x, y], [x + length, y]])
    middle = np.array([[x + length / 2, y]])
    swatch = np.array(
        [
            [x, y - 0.35 * size],
            [x + length, y - 0.35 * size],
            [x + length, y + 0.35 * size],
            [x, y + 0.35 * size],
        ]
    )
    if isinstance(a, Line):
        out: list[Item] = []
        colour = faded(a.colour, a.alpha)
        if a.width > 0:
            out.append(Path((segment,), Stroke(colour, a.width, a.dash)))
        if a.marker is not None:
            m = a.marker
            out.append(Marks(middle, m.shape, m.size, colour, m.hollow, m.edge))
        return out
    if isinstance(a, Band):
        return [Path((swatch,), fill=a.colour, closed=True)]
    if isinstance(a, Bars):
        return [Path((swatch,), Stroke(a.colour, a.line), a.fill, closed=True)]
    if isinstance(a, Span):
        if a.low == a.high:
            return [Path((segment,), Stroke(a.colour, a.width))]
        return [Path((swatch,), fill=a.colour, closed=True)]
    if isinstance(a, Polygon):
        return [Path((segment,), Stroke(a.colour, a.width))]
    if isinstance(a, ErrorBars):
        bar = np.array([[x + length / 2, y - 0.5 * size], [x + length / 2, y + 0.5 * size]])
        m = a.marker
        return [
            Path((bar,), Stroke(a.colour, a.width)),
            Marks(middle, m.shape, m.size, a.colour, m.hollow, m.edge),
        ]
    return []


def _meet(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """True if boxes (x0, y0, x1, y1) share area."""
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def legend(
    panel: Panel,
    data: Group,
    box: tuple[float, float, float, float],
    avoid: Sequence[tuple[float, float, float, float]] = (),
) -> Group | None:
    """The legend of ``panel`` (None when nothing is labelled); ``best`` keeps clear of the
    drawn points and of the boxes ``avoid`` (x0, y0, x1, y1: the panel's text)."""
    entries = [a for a in panel.artists if getattr(a, "label", "") and not hasattr(a, "text")]
    if not entries:
        return None
    fs = panel.legend_size
    pad, pitch, handle = 0.4 * fs, 1.3 * fs, 2.0 * fs
    width = 2 * pad + handle + 0.8 * fs + max(text_width(a.label, fs) for a in entries)  # type: ignore[union-attr]
    height = 2 * pad + pitch * len(entries)
    x0, y0, w, h = box
    gap = 0.5 * fs

    def corner(loc: str) -> tuple[float, float]:
        vertical, horizontal = loc.split(" ")
        left = {"left": x0 + gap, "right": x0 + w - gap - width, "center": x0 + (w - width) / 2}
        top = {"upper": y0 + gap, "lower": y0 + h - gap - height, "center": y0 + (h - height) / 2}
        if vertical == "center":
            return left[horizontal], top["center"]
        return left[horizontal], top[vertical]

    if panel.legend == "outside":
        left, top = x0 + w + gap, y0
    elif panel.legend == "best":
        drawn = points(data)

        areas = [(lx, ty, lx + width, ty + height) for lx, ty in map(corner, ORDER)]
        costs = [
            int(n) + 1000 * sum(_meet(area, other) for other in avoid)
            for n, area in zip(covered(drawn, areas), areas, strict=True)
        ]
        left, top = areas[costs.index(min(costs))][:2]
    else:
        left, top = corner(str(panel.legend))
    group = Group(kind="legend")
    for k, a in enumerate(entries):
        y = top + pad + (k + 0.5) * pitch
        group.add(*_handle(a, left + pad, y, handle, fs))
        group.add(anchored(left + pad + handle + 0.8 * fs, y, a.label, fs, INK, va="center"))  # type: ignore[union-attr]
    return group

"""A figure as data: a :class:`Chart` of :class:`Panel` s placed on it, each with two
:class:`Axis` and the artists drawn in data coordinates. Sizes are in inches (layout) and
points (line widths, marker sizes, fonts); colours are ``#rrggbb``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
Shape = Literal["o", "s", "v", "^", "x", "D", "."]
LegendLoc = Literal["upper left", "upper right", "lower left", "lower right", "best", "outside"]


def _array(values: ArrayLike) -> FloatArray:
    return np.asarray(values, dtype=float).ravel()


@dataclass(frozen=True)
class Box:
    """A region of the chart: left and top edge, width and height, inches from the
    chart's top-left corner."""

    left: float
    top: float
    width: float
    height: float


@dataclass(frozen=True)
class Marker:
    """How a point is marked: ``shape``, ``size`` (pt across), filled or ``hollow``."""

    shape: Shape = "o"
    size: float = 3.5
    hollow: bool = False
    edge: float = 0.6
    """outline width of hollow and ``x`` markers, pt"""


@dataclass(frozen=True)
class Line:
    """A polyline through (x, y) (NaN breaks it), optionally marked at each point;
    ``step``: steps changing midway between points. ``width`` 0 draws markers only."""

    x: FloatArray
    y: FloatArray
    colour: str
    width: float = 1.3
    dash: tuple[float, ...] = ()
    marker: Marker | None = None
    step: bool = False
    label: str = ""
    alpha: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", _array(self.x))
        object.__setattr__(self, "y", _array(self.y))


@dataclass(frozen=True)
class Band:
    """The area between ``low`` and ``high`` over x (``step``: steps changing midway)."""

    x: FloatArray
    low: FloatArray
    high: FloatArray
    colour: str
    step: bool = False
    label: str = ""

    def __post_init__(self) -> None:
        for name in ("x", "low", "high"):
            object.__setattr__(self, name, _array(getattr(self, name)))


@dataclass(frozen=True)
class Span:
    """A horizontal (``axis='y'``: y from ``low`` to ``high`` across the panel) or vertical
    strip; ``low == high`` draws a reference line ``width`` pt wide."""

    low: float
    high: float
    colour: str
    axis: Literal["x", "y"] = "y"
    width: float = 0.8
    label: str = ""


@dataclass(frozen=True)
class Polygon:
    """A closed outline (and fill) through (x, y)."""

    x: FloatArray
    y: FloatArray
    colour: str
    width: float = 1.2
    fill: str | None = None
    label: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", _array(self.x))
        object.__setattr__(self, "y", _array(self.y))


@dataclass(frozen=True)
class Bars:
    """Bars from 0 to ``height`` over [left, left + width)."""

    left: FloatArray
    width: FloatArray
    height: FloatArray
    fill: str
    colour: str
    line: float = 0.5


@dataclass(frozen=True)
class ErrorBars:
    """Markers at (x, y) with error bars of half-length ``err`` along ``axis`` and caps
    ``cap`` pt either side; the bars are ids ``<id>-<k>`` in an SVG."""

    x: FloatArray
    y: FloatArray
    err: FloatArray
    colour: str
    marker: Marker
    axis: Literal["x", "y"] = "y"
    cap: float = 3.0
    width: float = 1.0
    label: str = ""
    id: str = ""


@dataclass(frozen=True)
class Text:
    """Text at data point (x, y), moved by (dx, dy) pt (dy up); ``box``: on a white
    background; ``clear``: in whichever corner around (x, y), |dx| and |dy| away, covers the
    fewest drawn points within the panel (``ha``, ``va`` and the signs of dx, dy then
    follow the corner)."""

    x: float
    y: float
    text: str
    size: float = 7.0
    colour: str = "#1f2933"
    dx: float = 0.0
    dy: float = 0.0
    ha: Literal["left", "center", "right"] = "left"
    va: Literal["top", "center", "bottom", "baseline"] = "baseline"
    bold: bool = False
    box: bool = False
    clear: bool = False
    id: str = ""


Artist = Line | Band | Span | Polygon | Bars | ErrorBars | Text


@dataclass(frozen=True)
class Axis:
    """One axis: label, scale, limits (None: the data's, with a margin), inverted;
    ``ticks`` (and their ``labels``) fixed, or chosen (None)."""

    label: str = ""
    scale: Literal["linear", "log"] = "linear"
    limits: tuple[float, float] | None = None
    inverted: bool = False
    ticks: Sequence[float] | None = None
    labels: Sequence[str] | None = None
    tick_labels: bool = True
    """False: ticks without labels (a panel sharing the axis of the one below)"""
    grid: bool = True
    label_size: float = 8.0
    tick_size: float = 7.5


@dataclass
class Panel:
    """Axes in a ``box`` of the chart and what is drawn in them. ``frame`` False: no axes
    at all (a projection drawn by its builder); ``equal``: one data unit is as long on
    both axes (the limits widen to fit)."""

    box: Box
    x: Axis = field(default_factory=Axis)
    y: Axis = field(default_factory=Axis)
    artists: list[Artist] = field(default_factory=list)
    title: str = ""
    title_colour: str = "#1b365d"
    legend: LegendLoc | None = None
    legend_size: float = 7.0
    equal: bool = False
    frame: bool = True
    id: str = ""

    def add(self, *artists: Artist) -> Panel:
        """Append ``artists`` (later ones drawn over earlier ones)."""
        self.artists.extend(artists)
        return self


@dataclass
class Chart:
    """A whole figure: ``size`` (width, height) inches and its panels (drawn, shown and
    saved by :class:`~.drawing.Drawing`)."""

    size: tuple[float, float]
    panels: list[Panel] = field(default_factory=list)


def grid(
    size: tuple[float, float],
    nrows: int = 1,
    ncols: int = 1,
    *,
    left: float = 0.75,
    right: float = 0.2,
    bottom: float = 0.5,
    top: float = 0.3,
    hspace: float = 0.35,
    wspace: float = 0.6,
    width_ratios: Sequence[float] | None = None,
) -> list[Box]:
    """Boxes of a grid of panels with margins and gaps in inches (so text never collides,
    whatever the chart's size), row by row."""
    width, height = size
    ratios = np.asarray(width_ratios or [1.0] * ncols, dtype=float)
    inner_w = max(width - left - right - wspace * (ncols - 1), 0.1)
    inner_h = max(height - top - bottom - hspace * (nrows - 1), 0.1)
    widths = inner_w * ratios / ratios.sum()
    row_h = inner_h / nrows
    boxes = []
    for i in range(nrows):
        x = left
        for j in range(ncols):
            boxes.append(Box(x, top + i * (row_h + hspace), float(widths[j]), row_h))
            x += float(widths[j]) + wspace
    return boxes

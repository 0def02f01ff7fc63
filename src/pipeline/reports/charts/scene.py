"""A laid-out chart: primitives in points from the top-left corner (y down) that the
SVG and PDF writers serialise one to one. Text is measured with the PDF's own font
metrics (:mod:`~pipeline.reports.pdf_fonts`), so labels sit alike in both."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cache, lru_cache
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.reports.pdf_fonts import TEXTS, pdf_font

Points = NDArray[np.float64]
"""(n, 2) x, y in points"""
SANS = "DejaVu Sans"
NAMED = {"white": "#ffffff", "black": "#000000"}
BASELINE = {"baseline": 0.0, "top": 0.76, "center": 0.36, "bottom": -0.24}
"""Where the baseline lies below an anchor at a text's top, centre or bottom, in ems."""


@cache
def rgb(colour: str) -> tuple[float, float, float]:
    """``#rrggbb`` (or white, black) as red, green, blue in 0…1."""
    code = NAMED.get(colour, colour)
    if len(code) != 7 or code[0] != "#":
        raise ValueError(f"not a chart colour: {colour!r} (use #rrggbb)")
    return int(code[1:3], 16) / 255, int(code[3:5], 16) / 255, int(code[5:7], 16) / 255


def faded(colour: str, alpha: float) -> str:
    """``colour`` at ``alpha`` over white, as an opaque colour."""
    if alpha >= 1.0:
        return colour
    mixed = (1 - alpha + alpha * c for c in rgb(colour))
    return "#" + "".join(f"{round(255 * c):02x}" for c in mixed)


@lru_cache(maxsize=TEXTS)
def text_width(text: str, size: float, bold: bool = False) -> float:
    """Advance of ``text`` at ``size`` points in the report's sans font, points."""
    return pdf_font(SANS, bold).width(text, size)


@dataclass(frozen=True)
class Stroke:
    colour: str
    width: float
    dash: tuple[float, ...] = ()


@dataclass(frozen=True)
class Path:
    """Subpaths (each (n, 2) points) stroked and/or filled; ``closed`` closes each."""

    parts: tuple[Points, ...]
    stroke: Stroke | None = None
    fill: str | None = None
    closed: bool = False


@dataclass(frozen=True)
class Marks:
    """The same marker at each of ``xy``: ``size`` pt across."""

    xy: Points
    shape: str
    size: float
    colour: str
    hollow: bool = False
    edge: float = 0.6


@dataclass(frozen=True)
class Label:
    """Text with its baseline through (x, y) (before rotation), ``anchor`` its start,
    middle or end; ``angle`` 90 reads upwards; ``box``: a white box behind it."""

    x: float
    y: float
    text: str
    size: float
    colour: str
    anchor: Literal["start", "middle", "end"] = "start"
    bold: bool = False
    angle: int = 0
    box: bool = False

    def width(self) -> float:
        return text_width(self.text, self.size, self.bold)

    def extent(self) -> tuple[float, float, float, float]:
        """Unrotated box (x0, y0, x1, y1) of the text, points (y down): its advance across,
        the font's ascent and descent (0.93 and 0.24 em) up and down."""
        w = self.width()
        x0 = self.x - {"start": 0.0, "middle": w / 2, "end": w}[self.anchor]
        return x0, self.y - 0.93 * self.size, x0 + w, self.y + 0.24 * self.size


Item = Path | Marks | Label
"""A primitive"""


@dataclass
class Group:
    """Primitives (and groups) in drawing order, optionally named (``id`` in SVG: unique in
    a report), of a ``kind`` (``class`` in SVG: x and y ticks, legends) and clipped to a
    rectangle (x, y, w, h points)."""

    items: list[Item | Group] = field(default_factory=list)
    id: str = ""
    clip: tuple[float, float, float, float] | None = None
    kind: str = ""

    def add(self, *items: Item | Group) -> None:
        self.items.extend(items)


def points(group: Group) -> Points:
    """Every vertex and marker centre drawn in ``group`` (what a legend or label should not
    cover); the outlines of filled areas are left out."""
    found: list[Points] = [np.zeros((0, 2))]
    for item in group.items:
        if isinstance(item, Group):
            found.append(points(item))
        elif isinstance(item, Path):
            found.extend(p for p in item.parts if not item.closed or len(p) > 4)
        elif isinstance(item, Marks):
            found.append(item.xy)
    return np.concatenate(found)


def paths(group: Group) -> list[Path]:
    """Every path drawn in ``group`` (not in drawing order: a group's before those of the
    groups in it)."""
    found, groups = [], [group]
    for outer in groups:  # the groups met so far, the list growing as they are met
        for item in outer.items:
            if isinstance(item, Group):
                groups.append(item)
            elif isinstance(item, Path):
                found.append(item)
    return found


def covered(xy: Points, boxes: list[tuple[float, float, float, float]]) -> NDArray[np.intp]:
    """How many of the points ``xy`` lie in each of ``boxes`` (x0, y0, x1, y1), counted
    for all the boxes at once."""
    b = np.array(boxes)
    x, y = xy[:, 0], xy[:, 1]
    inside = (x >= b[:, 0:1]) & (x <= b[:, 2:3]) & (y >= b[:, 1:2]) & (y <= b[:, 3:4])
    counts: NDArray[np.intp] = np.count_nonzero(inside, axis=1)
    return counts


@dataclass
class Scene:
    """A chart laid out: its size (points) and everything on it."""

    width: float
    height: float
    root: Group


def anchored(
    x: float,
    y: float,
    text: str,
    size: float,
    colour: str,
    ha: str = "left",
    va: str = "baseline",
    *,
    bold: bool = False,
    angle: int = 0,
    box: bool = False,
) -> Label:
    """A :class:`Label` placed by its horizontal (left/center/right) and vertical
    (top/center/bottom/baseline) alignment; rotated text is aligned in its own frame."""
    anchor = {"left": "start", "center": "middle", "right": "end"}[ha]
    shift = BASELINE[va] * size
    if angle == 90:
        x, y = x + shift, y
    else:
        y = y + shift
    return Label(x, y, text, size, colour, anchor, bold, angle, box)  # type: ignore[arg-type]


SHAPES = {
    "s": (((-1, -1), (1, -1), (1, 1), (-1, 1)), 0.9, True),
    "D": (((0, -1), (1, 0), (0, 1), (-1, 0)), 1.2, True),
    "v": (((-1, -0.6), (1, -0.6), (0, 1)), 1.1, True),
    "^": (((-1, 0.6), (1, 0.6), (0, -1)), 1.1, True),
    "x": (((-1, -1), (1, 1), (np.nan, np.nan), (-1, 1), (1, -1)), 0.8, False),
}
"""Marker outlines: vertices in half-sizes about the centre (y down; NaN lifts the pen),
their scale and whether they close."""


@cache
def outline(shape: str, size: float) -> tuple[Points, bool] | None:
    """A marker's outline about its centre (points, y down; read-only) and whether it is
    closed; None for a circle (each writer draws its own). Made once per shape and size."""
    found = SHAPES.get(shape)
    if found is None:
        return None
    corners, scale, closed = found
    offsets = np.array(corners) * (size / 2) * scale
    offsets.flags.writeable = False
    return offsets, closed


def outline_runs(
    centres: Points, offsets: Points, closed: bool
) -> Iterator[tuple[float, float, bool] | None]:
    """Each marker's outline (``offsets`` about each of ``centres``, points) as vertices
    (x, y, whether the pen moves there rather than draws), a NaN offset lifting the pen;
    None after each closed outline (the writer closes the path there)."""
    for x, y in centres:
        moved = True
        for dx, dy in offsets:
            if np.isnan(dx):
                moved = True
                continue
            yield x + dx, y + dy, moved
            moved = False
        if closed:
            yield None

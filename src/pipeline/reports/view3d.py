"""The report's static 3-D view of a well path, projected orthographically onto the page
and drawn as a 2-D chart: the three back faces of the box with their grid, ticks on the
front edges, the path, its shadow on the floor, the wellhead and TD.

Box axes: east, north (one scale) and TVD down (scaled to fit the box's height); the
viewer looks from :data:`ELEVATION` above the horizon and :data:`AZIMUTH` from east.
"""

from __future__ import annotations

import numpy as np

from pipeline.reports.charts import ticks as tk
from pipeline.reports.charts.model import Axis, Chart, Line, Marker, Panel, Polygon, Text, grid
from pipeline.reports.charts.scene import text_width
from pipeline.reports.plots import BLUE, GREY, INK, NAVY, ORANGE, FloatArray, Path3, Size, pieces

ELEVATION, AZIMUTH = 20.0, -55.0
"""degrees"""
HEIGHT = 0.85
"""the box's height over its width"""
PANE, PANE_EDGE, PANE_GRID = "#f3f5f8", "#b8c2cc", "#dde3ea"
TICKS = 5


class _Camera:
    """Box coordinates (each in −½…½, the vertical in ±HEIGHT/2, up positive) → screen."""

    def __init__(self) -> None:
        el, az = np.radians(ELEVATION), np.radians(AZIMUTH)
        self.right = np.array([-np.sin(az), np.cos(az), 0.0])
        self.up = np.array([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)])

    def __call__(self, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        p = np.atleast_2d(p)
        return p @ self.right, p @ self.up


def view_3d(size: Size, path: Path3) -> Chart:
    """Static 3-D view (east, north, TVD down) with the path's shadow on the bottom plane;
    east and north share one scale, the vertical axis is scaled to fit the box."""
    half = max(float(np.ptp(path.east)), float(np.ptp(path.north)), 1.0) / 2 * 1.1
    centre_e = (path.east.max() + path.east.min()) / 2
    centre_n = (path.north.max() + path.north.min()) / 2
    limits = (
        (centre_e - half, centre_e + half),
        (centre_n - half, centre_n + half),
        (min(0.0, float(path.tvd.min())), float(path.tvd.max())),
    )
    floor = limits[2][1]
    depth = max(limits[2][1] - limits[2][0], 1.0)

    def box(east: FloatArray, north: FloatArray, tvd: FloatArray) -> FloatArray:
        return np.column_stack(
            [
                (np.asarray(east) - limits[0][0]) / (2 * half) - 0.5,
                (np.asarray(north) - limits[1][0]) / (2 * half) - 0.5,
                HEIGHT * (0.5 - (np.asarray(tvd) - limits[2][0]) / depth),
            ]
        )

    camera = _Camera()
    (area,) = grid(size, left=0.2, right=0.2, top=0.1, bottom=0.1)
    h = HEIGHT / 2
    corners = np.array([(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-h, h)])
    sx, sy = camera(corners)
    pad_x, pad_y = 0.16 * float(np.ptp(sx)), 0.12 * float(np.ptp(sy))
    panel = Panel(
        area,
        Axis(limits=(float(sx.min()) - pad_x, float(sx.max()) + pad_x)),
        Axis(limits=(float(sy.min()) - pad_y, float(sy.max()) + pad_y)),
        frame=False,
        equal=True,
    )
    faces = (  # the back faces: west (x = −½), north (y = +½) and the floor (z = −h)
        [(-0.5, -0.5, -h), (-0.5, 0.5, -h), (-0.5, 0.5, h), (-0.5, -0.5, h)],
        [(-0.5, 0.5, -h), (0.5, 0.5, -h), (0.5, 0.5, h), (-0.5, 0.5, h)],
        [(-0.5, -0.5, -h), (0.5, -0.5, -h), (0.5, 0.5, -h), (-0.5, 0.5, -h)],
    )
    for face in faces:
        panel.add(Polygon(*camera(np.array(face)), PANE_EDGE, 0.6, fill=PANE))
    _grid_and_ticks(panel, camera, limits, half, depth)
    for n, e, t in zip(
        pieces(path.north, path.offsets),
        pieces(path.east, path.offsets),
        pieces(path.tvd, path.offsets),
        strict=True,
    ):
        panel.add(Line(*camera(box(e, n, np.full_like(t, floor))), GREY, 0.8, dash=(3, 2)))
        panel.add(Line(*camera(box(e, n, t)), BLUE, 1.8))
    start = box(np.zeros(1), np.zeros(1), path.tvd[:1])
    end = box(path.east[-1:], path.north[-1:], path.tvd[-1:])
    panel.add(Line(*camera(start), NAVY, 0, marker=Marker("s", 5)))
    panel.add(Line(*camera(end), ORANGE, 0, marker=Marker("v", 6)))
    return Chart(size, [panel])


def _grid_and_ticks(
    panel: Panel,
    camera: _Camera,
    limits: tuple[tuple[float, float], ...],
    half: float,
    depth: float,
) -> None:
    """Grid lines on the back faces at each axis's ticks, tick labels along the front
    edges (east and north on the floor, TVD up the right-hand edge) and the axis names."""
    h = HEIGHT / 2
    names = ("East (m)", "North (m)", "TVD (m)")
    for axis, (lo, hi) in enumerate(limits):
        values, step = tk.linear_ticks(lo, hi, TICKS)
        reach = 0.0
        span = hi - lo if axis < 2 else depth
        for v in values:
            f = (v - lo) / span - 0.5
            if axis == 0:  # east: on the floor and the north face; labels on the south edge
                lines = [[(f, -0.5, -h), (f, 0.5, -h), (f, 0.5, h)]]
                at, out = (f, -0.5, -h), np.array([0.0, -1.0, 0.0])
            elif axis == 1:  # north: on the floor and the west face; labels on the east edge
                lines = [[(0.5, f, -h), (-0.5, f, -h), (-0.5, f, h)]]
                at, out = (0.5, f, -h), np.array([1.0, 0.0, 0.0])
            else:  # TVD down: on the west and north faces; labels on the north-east edge
                z = HEIGHT * (0.5 - (v - lo) / depth)
                lines = [[(-0.5, -0.5, z), (-0.5, 0.5, z), (0.5, 0.5, z)]]
                at, out = (0.5, 0.5, z), np.array([1.0, 1.0, 0.0])
            for line in lines:
                panel.add(Line(*camera(np.array(line)), PANE_GRID, 0.5))
            reach = max(
                reach, _label(panel, camera, np.array(at), out, tk.label(v, step), 6.5, 5.0)
            )
        middle = {0: (0.0, -0.5, -h), 1: (0.5, 0.0, -h), 2: (0.5, 0.5, 0.0)}[axis]
        _label(panel, camera, np.array(middle), out, names[axis], 7.5, reach + 5.0)


def _label(
    panel: Panel,
    camera: _Camera,
    at: FloatArray,
    out: FloatArray,
    text: str,
    size: float,
    gap: float,
) -> float:
    """``text`` centred beyond box point ``at`` along ``out`` (on screen), its nearest edge
    ``gap`` pt away; returns how far its far edge is, pt."""
    x0, y0 = camera(at)
    x1, y1 = camera(at + 0.1 * out)
    d = np.array([x1[0] - x0[0], y1[0] - y0[0]])
    d = d / (np.hypot(*d) or 1.0)
    half = float(abs(d[0]) * text_width(text, size) / 2 + abs(d[1]) * 0.45 * size)
    distance = gap + half
    panel.add(
        Text(
            float(x0[0]),
            float(y0[0]),
            text,
            size=size,
            colour=INK,
            dx=float(d[0] * distance),
            dy=float(d[1] * distance),
            ha="center",
            va="center",
        )
    )
    return distance + half

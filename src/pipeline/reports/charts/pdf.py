"""A :class:`~.scene.Scene` drawn on a PDF page (:class:`~pipeline.reports.pdf_canvas.Page`)
as path operators and text in the embedded fonts: the same primitives as the SVG, the
scene's y-down points mapped onto the page and scaled."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path as FilePath

import numpy as np

from pipeline.reports.charts.fixed import path_texts, rows
from pipeline.reports.charts.scene import (
    Group,
    Label,
    Marks,
    Path,
    Points,
    Scene,
    outline,
    outline_runs,
    paths,
)
from pipeline.reports.pdf_canvas import PT, Page, fill_colour, stroke_colour, write_pdf

KAPPA = 0.5523
"""Bézier control distance of a quarter circle, in radii."""


def _n(value: float) -> str:
    out = f"{value:.2f}".rstrip("0").rstrip(".")
    return "0" if out in ("-0", "") else out


class _Placed:
    """Scene points → page points: origin (ox, oy) the scene's top-left, scaled by ``s``."""

    def __init__(self, ox: float, oy: float, s: float) -> None:
        self.ox, self.oy, self.s = ox, oy, s
        self._scale, self._origin = np.array([s, -s]), np.array([ox, oy])

    def xy(self, points: Points) -> Points:
        placed: Points = points * self._scale + self._origin  # = (ox + s·x, oy − s·y)
        return placed

    def point(self, x: float, y: float) -> tuple[float, float]:
        """One point placed (the same numbers as :meth:`xy`)."""
        return self.ox + self.s * x, self.oy - self.s * y


POINT = "{} {} l "
"""A path's point in its operators (:func:`~.fixed.path_texts`' template): each a line to
it, the first of a subpath made a move."""


def _subpath(text: str, points: int, closed: bool) -> str:
    """The subpath of ``points`` points written in ``text`` (:data:`POINT` each)."""
    moved = text.replace(" l ", " m ", 1)  # no number holds an "l"
    return (moved[:-1] if points > 1 else moved) + (" h" if closed else "")


STROKES = 256
"""Most strokes (colour, width, dash, scale) whose operators a process keeps (a figure's
grid, frame, ticks and lines share a few, the same in every report)."""


@lru_cache(maxsize=STROKES)
def _stroke(colour: str, width: float, dashes: tuple[float, ...], s: float) -> str:
    """The operators setting a stroke of ``width`` and ``dashes`` (scene points) scaled by
    ``s`` onto the page."""
    dash = " ".join(_n(d * s) for d in dashes)
    return f"{stroke_colour(colour)} {_n(width * s)} w [{dash}] 0 d"


def _body(p: Path, texts: dict[int, list[str]]) -> str:
    """The subpaths of ``p``, their points written in ``texts`` (page points)."""
    parts = (len(part) for part in p.parts if len(part))
    return " ".join(
        _subpath(text, n, p.closed) for text, n in zip(texts[id(p)], parts, strict=True)
    )


def _path(p: Path, at: _Placed, texts: dict[int, list[str]]) -> str:
    body = _body(p, texts)
    if not body:
        return ""
    style = []
    if p.fill:
        style.append(fill_colour(p.fill))
    if p.stroke is not None:
        style.append(_stroke(p.stroke.colour, p.stroke.width, p.stroke.dash, at.s))
    paint = "B" if p.fill and p.stroke else "f" if p.fill else "S"
    return f"{' '.join(style)} {body} {paint}"


CIRCLE = (
    "{0} {1} m {0} {2} {3} {4} {5} {4} c {6} {4} {7} {2} {7} {1} c {7} {8} {6} {9} "
    "{5} {9} c {3} {9} {0} {8} {0} {1} c h "
)
"""A circle of four Bézier quarters from x + r, y + r·κ, x + r·κ, x, y + r, x − r·κ, x − r,
y − r·κ, y − r (columns 0…9: each written where it appears, its digits made once)."""


def _circles(centres: Points, r: float) -> str:
    k = KAPPA * r
    x, y = centres[:, 0], centres[:, 1]
    columns = np.column_stack((x + r, y, y + k, x + k, y + r, x, x - k, x - r, y - k, y - r))
    return rows(CIRCLE, columns, 2)[:-1]


def _marks(m: Marks, at: _Placed) -> str:
    if not len(m.xy):
        return ""
    centres = at.xy(m.xy)
    shape = outline(m.shape, m.size)
    if shape is None:
        r = (m.size / 2 if m.shape != "." else m.size / 4) * at.s
        body = _circles(centres, r)
        closed = True
    else:
        offsets, closed = shape
        runs = outline_runs(centres, offsets * np.array([at.s, -at.s]), closed)
        body = " ".join(
            "h" if v is None else f"{_n(v[0])} {_n(v[1])} {'m' if v[2] else 'l'}" for v in runs
        )
    if m.hollow or not closed:
        return f"{stroke_colour(m.colour)} {_n(m.edge * at.s)} w [] 0 d {body} S"
    return f"{fill_colour(m.colour)} {body} f"


def _label(page: Page, t: Label, at: _Placed) -> None:
    if t.box:
        x0, y0, x1, y1 = t.extent()
        bx, by = at.point(x0 - 1.5, y1 + 1)
        page.raw(
            f"{fill_colour('#ffffff')} {_n(bx)} {_n(by)} {_n((x1 - x0 + 3) * at.s)} "
            f"{_n((y1 - y0 + 2) * at.s)} re f"
        )
    shift = {"start": 0.0, "middle": 0.5, "end": 1.0}[t.anchor] * t.width()
    if t.angle == 90:
        x, y = t.x, t.y + shift
    else:
        x, y = t.x - shift, t.y
    px, py = at.point(x, y)
    page.glyphs(px, py, t.text, t.size * at.s, t.colour, bold=t.bold, angle=t.angle)


def _group(page: Page, g: Group, at: _Placed, texts: dict[int, list[str]]) -> None:
    if g.clip is not None:
        x, y, w, h = g.clip
        cx, cy = at.point(x, y + h)
        page.raw(f"q {_n(cx)} {_n(cy)} {_n(w * at.s)} {_n(h * at.s)} re W n")
    for item in g.items:
        if isinstance(item, Group):
            _group(page, item, at, texts)
        elif isinstance(item, Label):
            _label(page, item, at)
        else:
            ops = _path(item, at, texts) if isinstance(item, Path) else _marks(item, at)
            if ops:
                page.raw(ops)
    if g.clip is not None:
        page.raw("Q")


def draw(page: Page, scene: Scene, left: float, top: float, width: float) -> None:
    """``scene`` on ``page`` with its top-left corner at (left, top) inches from the
    page's bottom-left, scaled to ``width`` inches."""
    page.raw("q 1 j 0 J")
    at = _Placed(left * PT, top * PT, width * PT / scene.width)
    _group(page, scene.root, at, path_texts(paths(scene.root), POINT, 2, at.xy))
    page.raw("Q")


def chart_pdf(scene: Scene, path: FilePath) -> None:
    """``scene`` alone as a one-page PDF of its own size."""
    page = Page(scene.width / PT, scene.height / PT)
    draw(page, scene, 0.0, scene.height / PT, scene.width / PT)
    write_pdf([page], path, path.stem, "gyropipe")

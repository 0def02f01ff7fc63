"""A :class:`~.model.Chart` laid out as a :class:`~.scene.Scene`: limits, the data mapped
to points, grid, frame, ticks and their labels, axis labels, titles and legends (styled
as the reports are: small grey ticks, a light grid, bold navy titles on the left)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pipeline.reports.charts import ticks as tk
from pipeline.reports.charts.legend import legend
from pipeline.reports.charts.model import (
    Axis,
    Band,
    Bars,
    Chart,
    ErrorBars,
    FloatArray,
    Line,
    Panel,
    Polygon,
    Span,
    Text,
)
from pipeline.reports.charts.scene import (
    Group,
    Item,
    Label,
    Marks,
    Path,
    Points,
    Scene,
    Stroke,
    anchored,
    covered,
    faded,
    points,
    text_width,
)

PT = 72.0
INK = "#1f2933"
EDGE = Stroke("#9aa5b1", 0.6)
GRID = Stroke("#e1e6ec", 0.5)
MINOR_GRID = Stroke("#f0f3f6", 0.4)
TICK_COLOUR = "#52606d"
TICK_LENGTH = 2.5
TICK_PAD = 3.5
LABEL_PAD = 4.0
TITLE_RISE = 5.5
"""Points from a panel's top edge up to its title's baseline (and a y axis's ×10ⁿ note's)."""
PAD = 3.0
"""Points a ``clear`` text keeps from the drawn points (a marker's half-width)."""
MARGIN = 0.05
"""Share of the data's range left free at each end of an axis whose limits are not set."""


def lay_out(chart: Chart) -> Scene:
    """Every panel of ``chart`` as primitives in points."""
    root = Group()
    for panel in chart.panels:
        root.add(_panel(panel))
    return Scene(chart.size[0] * PT, chart.size[1] * PT, root)


@dataclass(frozen=True)
class Scale:
    """Data → points along one axis."""

    lo: float
    hi: float
    start: float
    """point of ``lo``"""
    length: float
    """points from ``lo`` to ``hi`` (negative: the axis runs up or is inverted)"""
    log: bool

    def __call__(self, values: FloatArray) -> FloatArray:
        v = np.asarray(values, dtype=float)
        if self.log:
            with np.errstate(divide="ignore", invalid="ignore"):
                v = np.where(v > 0, np.log10(np.where(v > 0, v, 1.0)), np.nan)
            lo, hi = np.log10(self.lo), np.log10(self.hi)
        else:
            lo, hi = self.lo, self.hi
        mapped: FloatArray = self.start + (v - lo) / (hi - lo) * self.length
        return mapped

    def at(self, value: float) -> float:
        """One value mapped (the same number as an array of it)."""
        if self.log or self.hi == self.lo:
            return float(self(np.array([value]))[0])
        return float(self.start + (float(value) - self.lo) / (self.hi - self.lo) * self.length)


def _data(panel: Panel, axis: str) -> FloatArray:
    """Every coordinate the artists of ``panel`` put on ``axis`` ('x' or 'y')."""
    out: list[FloatArray] = []
    for a in panel.artists:
        if isinstance(a, Line | Polygon):
            out.append(a.x if axis == "x" else a.y)
        elif isinstance(a, Band):
            out.extend([a.x] if axis == "x" else [a.low, a.high])
        elif isinstance(a, Bars):
            out.extend([a.left, a.left + a.width] if axis == "x" else [a.height, np.zeros(1)])
        elif isinstance(a, ErrorBars):
            v = a.x if axis == "x" else a.y
            out.extend([v - a.err, v + a.err] if a.axis == axis else [v])
        elif isinstance(a, Span) and a.axis == axis:
            out.append(np.array([a.low, a.high]))
    return np.concatenate(out) if out else np.zeros(0)


def _limits(axis: Axis, values: FloatArray) -> tuple[float, float]:
    if axis.limits is not None:
        return axis.limits
    log = axis.scale == "log"
    v = values[np.isfinite(values) & ((values > 0) if log else True)]
    if not v.size:
        return (1.0, 10.0) if log else (0.0, 1.0)
    lo, hi = float(v.min()), float(v.max())
    if log:
        lo, hi = np.log10(lo), np.log10(hi)
    if hi - lo <= 0:
        half = max(abs(hi) * 0.05, 0.5)
        lo, hi = lo - half, hi + half
    pad = MARGIN * (hi - lo)
    lo, hi = lo - pad, hi + pad
    return (10.0**lo, 10.0**hi) if log else (lo, hi)


def _equal(
    xl: tuple[float, float], yl: tuple[float, float], w: float, h: float
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Limits widened so that a data unit is as long on both axes."""
    per = max((xl[1] - xl[0]) / w, (yl[1] - yl[0]) / h)
    xc, yc = (xl[0] + xl[1]) / 2, (yl[0] + yl[1]) / 2
    return (xc - per * w / 2, xc + per * w / 2), (yc - per * h / 2, yc + per * h / 2)


def scales(panel: Panel) -> tuple[Scale, Scale]:
    """The panel's x and y mappings to points (limits from the data unless set)."""
    b = panel.box
    x0, y0, w, h = b.left * PT, b.top * PT, b.width * PT, b.height * PT
    xl, yl = _limits(panel.x, _data(panel, "x")), _limits(panel.y, _data(panel, "y"))
    if panel.equal:
        xl, yl = _equal(xl, yl, w, h)
    sx = Scale(
        *xl,
        x0 + (w if panel.x.inverted else 0),
        -w if panel.x.inverted else w,
        panel.x.scale == "log",
    )
    sy = Scale(
        *yl,
        y0 + (0 if panel.y.inverted else h),
        h if panel.y.inverted else -h,
        panel.y.scale == "log",
    )
    return sx, sy


def _ticks(
    axis: Axis, scale: Scale, horizontal: bool
) -> tuple[list[float], list[str], list[float], str]:
    """Major ticks, their labels, minor ticks (log axes) within the limits, and the note
    shown once at the axis end ('×10ⁿ +offset' of labels shortened, else '')."""
    lo, hi = sorted((scale.lo, scale.hi))
    if axis.ticks is not None:
        values = list(axis.ticks)
        step = min(np.diff(values)) if len(values) > 1 else 1.0
        if axis.labels is not None:
            return values, list(axis.labels), [], ""
        labels, note = tk.linear_labels(values, step)
        return values, labels, [], note
    if axis.scale == "log":
        major, minor = tk.log_ticks(lo, hi)
        return major, [tk.log_label(v) for v in major], minor, ""
    length, size = abs(scale.length), axis.tick_size
    most = int(min(max(length / (3 * size if horizontal else 2.2 * size), 2), 9))
    while True:  # fewer ticks until the labels of a horizontal axis have room
        values, step = tk.linear_ticks(lo, hi, most)
        labels, note = tk.linear_labels(values, step)
        if not horizontal or most <= 2:
            return values, labels, [], note
        widest = max(text_width(t, size) for t in labels)
        if (widest + 2 * size) * len(values) <= length:
            return values, labels, [], note
        most -= 1


def _runs(xy: Points) -> list[Points]:
    """``xy`` split where a coordinate is not finite."""
    finite = np.isfinite(xy)
    if finite.all():  # as a rule (a reduction along rows of two costs 35 ns a row)
        return [xy] if len(xy) else []
    ok = finite.all(axis=1)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    return [xy[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _finite(xy: Points) -> Points:
    """``xy`` without the points that have a coordinate not finite (``xy`` itself when
    every one is finite)."""
    finite = np.isfinite(xy)
    return xy if finite.all() else xy[finite.all(axis=1)]


def _steps(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Vertices of a line that steps midway between its points."""
    if len(x) < 2:
        return x, y
    mid = (x[1:] + x[:-1]) / 2
    xs = np.concatenate([[x[0]], np.repeat(mid, 2), [x[-1]]])
    ys = np.repeat(y, 2)
    return xs, ys


def _artist(
    a: object, sx: Scale, sy: Scale, box: tuple[float, float, float, float]
) -> list[Item | Group]:
    """The primitives of one data artist."""
    x0, y0, w, h = box
    if isinstance(a, Line):
        xs, ys = _steps(a.x, a.y) if a.step else (a.x, a.y)
        colour = faded(a.colour, a.alpha)
        out: list[Item | Group] = []
        if a.width > 0:
            parts = tuple(p for p in _runs(np.column_stack([sx(xs), sy(ys)])) if len(p) > 1)
            if parts:
                out.append(Path(parts, Stroke(colour, a.width, a.dash)))
        if a.marker is not None:
            xy = _finite(np.column_stack([sx(a.x), sy(a.y)]))
            m = a.marker
            out.append(Marks(xy, m.shape, m.size, colour, m.hollow, m.edge))
        return out
    if isinstance(a, Band):
        xs, lows = _steps(a.x, a.low) if a.step else (a.x, a.low)
        highs = _steps(a.x, a.high)[1] if a.step else a.high
        areas = []
        for lo_run, hi_run in zip(
            _runs(np.column_stack([sx(xs), sy(lows)])),
            _runs(np.column_stack([sx(xs), sy(highs)])),
            strict=False,
        ):
            areas.append(np.concatenate([hi_run, lo_run[::-1]]))
        return [Path(tuple(areas), fill=a.colour, closed=True)] if areas else []
    if isinstance(a, Span):
        scale = sy if a.axis == "y" else sx
        lo, hi = sorted((scale.at(a.low), scale.at(a.high)))
        if a.low == a.high:
            seg = [[x0, lo], [x0 + w, lo]] if a.axis == "y" else [[lo, y0], [lo, y0 + h]]
            return [Path((np.array(seg),), Stroke(a.colour, a.width))]
        rect = (
            [[x0, lo], [x0 + w, lo], [x0 + w, hi], [x0, hi]]
            if a.axis == "y"
            else [[lo, y0], [hi, y0], [hi, y0 + h], [lo, y0 + h]]
        )
        return [Path((np.array(rect),), fill=a.colour, closed=True)]
    if isinstance(a, Polygon):
        xy = np.column_stack([sx(a.x), sy(a.y)])
        stroke = Stroke(a.colour, a.width) if a.width > 0 else None
        return [Path(tuple(_runs(xy)), stroke, a.fill, closed=True)]
    if isinstance(a, Bars):
        left, right = sx(a.left), sx(a.left + a.width)
        base, top = sy(np.zeros_like(a.height)), sy(a.height)
        corners = np.empty((len(left), 4, 2))  # bottom left, bottom right, top right, top left
        corners[:, :, 0] = np.column_stack([left, right, right, left])
        corners[:, :, 1] = np.column_stack([base, base, top, top])
        rects = tuple(corners[np.isfinite(corners).all(axis=(1, 2))])
        return [Path(rects, Stroke(a.colour, a.line), a.fill, closed=True)] if rects else []
    if isinstance(a, ErrorBars):
        return _error_bars(a, sx, sy)
    raise TypeError(f"not a chart artist: {a!r}")


def _error_bars(a: ErrorBars, sx: Scale, sy: Scale) -> list[Item | Group]:
    vertical = a.axis == "y"
    out: list[Item | Group] = []
    stroke = Stroke(a.colour, a.width)
    lo_x, hi_x = (sx(a.x), sx(a.x)) if vertical else (sx(a.x - a.err), sx(a.x + a.err))
    lo_y, hi_y = (sy(a.y - a.err), sy(a.y + a.err)) if vertical else (sy(a.y), sy(a.y))
    c = a.cap
    for k, (x1, y1, x2, y2) in enumerate(zip(lo_x, lo_y, hi_x, hi_y, strict=True)):
        if not np.isfinite([x1, y1, x2, y2]).all():
            continue
        bar = Path((np.array([[x1, y1], [x2, y2]]),), stroke)
        if vertical:
            caps = (np.array([[x1 - c, y1], [x1 + c, y1]]), np.array([[x2 - c, y2], [x2 + c, y2]]))
        else:
            caps = (np.array([[x1, y1 - c], [x1, y1 + c]]), np.array([[x2, y2 - c], [x2, y2 + c]]))
        if a.id:
            out.append(Group([bar], f"{a.id}-bar-{k}"))
            out.append(Group([Path(caps, stroke)], f"{a.id}-cap-{k}"))
        else:
            out.extend([bar, Path(caps, stroke)])
    xy = _finite(np.column_stack([sx(a.x), sy(a.y)]))
    m = a.marker
    out.append(Marks(xy, m.shape, m.size, a.colour, m.hollow, m.edge))
    return out


def _text(a: Text, sx: Scale, sy: Scale) -> Group | Label:
    label = anchored(
        sx.at(a.x) + a.dx,
        sy.at(a.y) - a.dy,
        a.text,
        a.size,
        a.colour,
        a.ha,
        a.va,
        bold=a.bold,
        box=a.box,
    )
    lines = a.text.split("\n")
    if len(lines) == 1:
        return Group([label], a.id) if a.id else label
    pitch = a.size * 1.2
    first = label.y - (
        0
        if a.va in ("top", "baseline")
        else pitch * (len(lines) - 1) / (2 if a.va == "center" else 1)
    )
    rows: list[Item | Group] = [
        Label(label.x, first + k * pitch, line, a.size, a.colour, label.anchor, a.bold, 0, a.box)
        for k, line in enumerate(lines)
    ]
    return Group(rows, a.id)


CORNERS = ((1, -1), (1, 1), (-1, -1), (-1, 1), (1, 0), (-1, 0), (0, 1), (0, -1))
"""Where a ``clear`` text may go, in this order: right below, right above, left below, left
above, right, left, above, below."""
SIDES = {1: ("left", "bottom"), 0: ("center", "center"), -1: ("right", "top")}
"""Alignment of a text on each side of its point (horizontal for x, vertical for y)."""


def _extent(item: Item | Group) -> tuple[float, float, float, float]:
    """Box (x0, y0, x1, y1) of a text's lines, points."""
    labels = item.items if isinstance(item, Group) else [item]
    x0, y0, x1, y1 = zip(*(t.extent() for t in labels if isinstance(t, Label)), strict=True)
    return min(x0), min(y0), max(x1), max(y1)


def _clear(
    a: Text, sx: Scale, sy: Scale, drawn: Points, box: tuple[float, float, float, float]
) -> Item | Group:
    """``a`` in the place around its point that covers the fewest of the ``drawn`` points,
    each place first moved into the panel if it sticks out (the first place on a tie)."""
    x0, y0, w, h = box

    def placed(right: int, up: int) -> Item | Group:
        text = dataclasses.replace(
            a,
            dx=right * abs(a.dx),
            dy=up * abs(a.dy),
            ha=SIDES[right][0],  # type: ignore[arg-type]
            va=SIDES[up][1],  # type: ignore[arg-type]
        )
        e = _extent(_text(text, sx, sy))
        shift_x = max(0.0, x0 - e[0]) - max(0.0, e[2] - x0 - w)
        shift_y = max(0.0, y0 - e[1]) - max(0.0, e[3] - y0 - h)
        return _text(dataclasses.replace(text, dx=text.dx + shift_x, dy=text.dy - shift_y), sx, sy)

    places = [placed(right, up) for right, up in CORNERS]
    boxes = [(e[0] - PAD, e[1] - PAD, e[2] + PAD, e[3] + PAD) for e in map(_extent, places)]
    return places[int(np.argmin(covered(drawn, boxes)))]


def _placed(values: list[float], s: Scale) -> list[float | None]:
    """Each of ``values`` mapped to points by ``s``, None where it lies outside the limits
    (to rounding)."""
    lo, hi = sorted((s.lo, s.hi))
    slack = 1e-9 * (hi - lo)
    return [s.at(v) if lo - slack <= v <= hi + slack else None for v in values]


def _segments(at: list[float], span: tuple[float, float], *, vertical: bool) -> tuple[Points, ...]:
    """A line across ``span`` (points) at each of ``at``: vertical (x = a, y over the span)
    or horizontal; each a 2 × 2 view into one array made for them all."""
    lines = np.empty((len(at), 2, 2))
    lines[:, :, 0 if vertical else 1] = np.asarray(at)[:, None]
    lines[:, :, 1 if vertical else 0] = span
    return tuple(lines)


def _axes(
    panel: Panel, sx: Scale, sy: Scale, box: tuple[float, float, float, float]
) -> tuple[Group, Group]:
    """The grid (under the data) and the frame, ticks and labels (over it)."""
    x0, y0, w, h = box
    under, over = Group(), Group()
    xt, xl, xminor, x_note = _ticks(panel.x, sx, True)
    yt, yl, yminor, y_note = _ticks(panel.y, sy, False)
    xs, ys = _placed(xt, sx), _placed(yt, sy)  # the major ticks' points (None: outside)
    for at, stroke in ((_placed(xminor, sx), MINOR_GRID), (xs, GRID)):
        parts = _segments([v for v in at if v is not None], (y0, y0 + h), vertical=True)
        if parts and panel.x.grid:
            under.add(Path(parts, stroke))
    for at, stroke in ((_placed(yminor, sy), MINOR_GRID), (ys, GRID)):
        parts = _segments([v for v in at if v is not None], (x0, x0 + w), vertical=False)
        if parts and panel.y.grid:
            under.add(Path(parts, stroke))
    over.add(
        Path(
            (np.array([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]),), EDGE, closed=True
        )
    )
    tick = Stroke(EDGE.colour, 0.6)
    bottom = y0 + h + TICK_LENGTH + TICK_PAD
    x_ticks = [(x, t) for x, t in zip(xs, xl, strict=True) if x is not None]
    x_marks = _segments([x for x, _ in x_ticks], (y0 + h, y0 + h + TICK_LENGTH), vertical=True)
    for (x, text), mark in zip(x_ticks, x_marks, strict=True):
        items: list[Item | Group] = [Path((mark,), tick)]
        if panel.x.tick_labels:
            items.append(anchored(x, bottom, text, panel.x.tick_size, TICK_COLOUR, "center", "top"))
        over.add(Group(items, kind="xtick"))
    widest = 0.0
    y_ticks = [(y, t) for y, t in zip(ys, yl, strict=True) if y is not None]
    y_marks = _segments([y for y, _ in y_ticks], (x0 - TICK_LENGTH, x0), vertical=False)
    for (y, text), mark in zip(y_ticks, y_marks, strict=True):
        items = [Path((mark,), tick)]
        if panel.y.tick_labels:
            lab = anchored(
                x0 - TICK_LENGTH - TICK_PAD,
                y,
                text,
                panel.y.tick_size,
                TICK_COLOUR,
                "right",
                "center",
            )
            widest = max(widest, lab.width())
            items.append(lab)
        over.add(Group(items, kind="ytick"))
    below = bottom + (panel.x.tick_size if panel.x.tick_labels else 0) + LABEL_PAD
    centre = x0 + w / 2
    if x_note and panel.x.tick_labels:  # under the right end of the axis, the label left of it
        note = anchored(x0 + w, below, x_note, panel.x.tick_size, TICK_COLOUR, "right", "top")
        over.add(Group([note], kind="xnote"))
        room = x0 + w - note.width() - LABEL_PAD
        centre = max(min(centre, room - text_width(panel.x.label, panel.x.label_size) / 2), x0)
    if panel.x.label:
        size = panel.x.label_size
        over.add(anchored(centre, below, panel.x.label, size, INK, "center", "top"))
    if y_note and panel.y.tick_labels:  # over the tick labels, level with a title
        right = x0 - TICK_LENGTH - TICK_PAD
        note = anchored(right, y0 - TITLE_RISE, y_note, panel.y.tick_size, TICK_COLOUR, "right")
        over.add(Group([note], kind="ynote"))
    if panel.y.label:
        left = x0 - TICK_LENGTH - TICK_PAD - widest - LABEL_PAD
        over.add(
            anchored(
                left,
                y0 + h / 2,
                panel.y.label,
                panel.y.label_size,
                INK,
                "center",
                "bottom",
                angle=90,
            )
        )
    return under, over


def _panel(panel: Panel) -> Group:
    b = panel.box
    box = (b.left * PT, b.top * PT, b.width * PT, b.height * PT)
    sx, sy = scales(panel)
    group = Group(id=panel.id)
    over = Group()
    if panel.frame:
        under, over = _axes(panel, sx, sy, box)
        group.add(under)
    data = Group(clip=box if panel.frame else None)
    for a in panel.artists:
        if not isinstance(a, Text):
            data.add(*_artist(a, sx, sy, box))
    drawn = points(data)
    texts = [
        (_clear(a, sx, sy, drawn, box) if a.clear else _text(a, sx, sy))
        for a in panel.artists
        if isinstance(a, Text)
    ]
    group.add(data, over, *texts)
    if panel.title:
        group.add(
            anchored(box[0], box[1] - TITLE_RISE, panel.title, 8.5, panel.title_colour, bold=True)
        )
    if panel.legend is not None:
        found = legend(panel, data, box, [_extent(t) for t in texts])
        if found is not None:
            group.add(found)
    return group

"""Report figures, described as charts (:mod:`.charts.model`) that the HTML and the PDF
both draw (vector): each function takes the figure's size (width, height, inches) and its
data and returns the :class:`~.charts.model.Chart`; margins and gaps are in inches.

Positions are NED relative to the wellhead (north, east, TVD down, metres); angles in
degrees; azimuths clockwise from the north reference named in the labels.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.reports.charts.model import (
    Axis,
    Band,
    Bars,
    Chart,
    ErrorBars,
    LegendLoc,
    Line,
    Marker,
    Panel,
    Polygon,
    Shape,
    Span,
    Text,
    grid,
)
from pipeline.reports.envelope import FullRate
from pipeline.reports.numbers import fmt_azimuth, fmt_measured, fmt_sig

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Size = tuple[float, float]
"""A figure's width and height, inches"""

INK = "#1f2933"
NAVY = "#1b365d"
BLUE = "#2f6fb0"
ORANGE = "#d9731a"
TEAL = "#23867a"
RED = "#c0392b"
GREY = "#8a94a6"
BAND = "#dcefe3"
SERIES_COLOURS = ("#4477aa", "#ee6677", "#228833", "#ccbb44", "#66ccee", "#aa3377", "#000000")
"""Colours of a chart's series (offset wells, ellipses, axes): Paul Tol's colour-blind-safe
"bright" scheme and black, distinct also to deuteranopes, protanopes and tritanopes."""
DOT = Marker("o", 2.6)
"""The marker of a station"""


def series_colour(k: int) -> str:
    """Colour of the ``k``-th series of a chart."""
    return SERIES_COLOURS[k % len(SERIES_COLOURS)]


def pieces(values: FloatArray, offsets: Sequence[int]) -> list[FloatArray]:
    """``values`` split into the contiguous surveys delimited by ``offsets``."""
    return [values[lo:hi] for lo, hi in itertools.pairwise(offsets)]


MAX_DRAWN = 2_000
"""Most stations a trajectory chart draws (a 300,000-station survey drawn whole spent most
of its run in the report; its listing is never thinned)."""


def drawn_rows(md: FloatArray, offsets: Sequence[int], peaks: FloatArray) -> NDArray[np.intp]:
    """The stations a chart draws: all when there are at most :data:`MAX_DRAWN`; else
    :data:`MAX_DRAWN` evenly spaced ones plus every survey's first and last station and, in
    each stretch between two drawn stations, the one of highest ``peaks`` (DLS: a dogleg is
    never thinned away). Sorted row indices."""
    n = len(md)
    if n <= MAX_DRAWN:
        return np.arange(n)
    even = np.linspace(0, n - 1, MAX_DRAWN).astype(np.intp)
    ends = np.array([*offsets[:-1], *(o - 1 for o in offsets[1:])], dtype=np.intp)
    values = np.where(np.isfinite(peaks), peaks, -np.inf)
    highest = np.array(
        [lo + int(np.argmax(values[lo:hi])) for lo, hi in itertools.pairwise([*even, n])],
        dtype=np.intp,
    )
    rows: NDArray[np.intp] = np.unique(np.concatenate([even, ends, highest]))
    return rows


def _span(values: FloatArray) -> tuple[float, float]:
    """Limits of an axis showing ``values`` with a 5 % margin (shared by stacked panels)."""
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    pad = 0.05 * (hi - lo) if hi > lo else 1.0
    return lo - pad, hi + pad


@dataclass(frozen=True)
class Path3:
    """Station positions of one or more surveys (``offsets`` delimit them)."""

    md: FloatArray
    north: FloatArray
    east: FloatArray
    tvd: FloatArray
    offsets: tuple[int, ...]
    north_label: str
    """e.g. 'true north'"""

    def taken(self, rows: NDArray[np.intp]) -> Path3:
        """The path through stations ``rows`` only (sorted; each survey's ends among them)."""
        offsets = tuple(int(o) for o in np.searchsorted(rows, self.offsets))
        return Path3(
            self.md[rows],
            self.north[rows],
            self.east[rows],
            self.tvd[rows],
            offsets,
            self.north_label,
        )

    def surveys(self) -> list[tuple[int, Path3]]:
        """Each survey's first row and its own path."""
        found = []
        for lo, hi in itertools.pairwise(self.offsets):
            rows = slice(lo, hi)
            one = Path3(
                self.md[rows],
                self.north[rows],
                self.east[rows],
                self.tvd[rows],
                (0, hi - lo),
                self.north_label,
            )
            found.append((lo, one))
        return found


def plan_view(size: Size, path: Path3) -> Chart:
    """Horizontal projection with the closure from the wellhead to the last station."""
    (box,) = grid(size, left=0.85)
    panel = Panel(box, Axis("East (m)"), Axis(f"North (m, {path.north_label})"), equal=True)
    surveys = zip(pieces(path.north, path.offsets), pieces(path.east, path.offsets), strict=True)
    for n, e in surveys:
        panel.add(Line(e, n, BLUE, marker=DOT))
    n_end, e_end = float(path.north[-1]), float(path.east[-1])
    distance = float(np.hypot(n_end, e_end))
    direction = float(np.degrees(np.arctan2(e_end, n_end)))
    panel.add(
        Line(np.zeros(1), np.zeros(1), NAVY, 0, marker=Marker("s", 5), label="wellhead"),
        Line(np.array([0.0, e_end]), np.array([0.0, n_end]), GREY, 0.8, dash=(3, 2)),
        Line(np.array([e_end]), np.array([n_end]), ORANGE, 0, marker=Marker("v", 6), label="TD"),
        Text(  # beside TD, clear of the path
            e_end,
            n_end,
            f"TD  MD {path.md[-1]:.1f} m\nclosure {distance:.1f} m @ {fmt_azimuth(direction)}°",
            dx=8,
            dy=6,
            clear=True,
        ),
    )
    panel.legend = "best"
    return Chart(size, [panel])


def vertical_section(size: Size, vs: FloatArray, path: Path3, azimuth: float | None) -> Chart:
    """Vertical section (horizontal displacement along the section azimuth) against TVD."""
    (box,) = grid(size, left=0.85)
    plane = f" @ {fmt_azimuth(azimuth)}° {path.north_label}" if azimuth is not None else ""
    panel = Panel(
        box, Axis(f"Vertical section (m){plane}"), Axis("TVD (m)", inverted=True), equal=True
    )
    for v, t in zip(pieces(vs, path.offsets), pieces(path.tvd, path.offsets), strict=True):
        panel.add(Line(v, t, BLUE, marker=DOT))
    panel.add(Line(vs[-1:], path.tvd[-1:], ORANGE, 0, marker=Marker("v", 6)))
    return Chart(size, [panel])


def profiles(
    size: Size,
    path: Path3,
    inc: FloatArray,
    azi: FloatArray,
    dls: FloatArray,
    dls_unit: str,
    low_inclination: float = 3.0,
    short: BoolArray | None = None,
    short_label: str = "short courses",
) -> Chart:
    """Inclination, azimuth and dogleg severity against MD; azimuths of stations below
    ``low_inclination`` (ill-defined) drawn hollow, DLS over ``short`` courses grey."""
    boxes = grid(size, 3, 1, hspace=0.12, top=0.15)
    md = _span(path.md)
    hidden = Axis(limits=md, tick_labels=False)
    p_inc = Panel(boxes[0], hidden, Axis("Inclination (°)"))
    for m, i in zip(pieces(path.md, path.offsets), pieces(inc, path.offsets), strict=True):
        p_inc.add(Line(m, i, BLUE, marker=Marker("o", 2.2)))
    low = inc < low_inclination
    p_azi = Panel(
        boxes[1],
        hidden,
        Axis(f"Azimuth (°, {path.north_label})", limits=(-5, 365), ticks=(0, 90, 180, 270, 360)),
    )
    p_azi.add(Line(path.md[~low], azi[~low], TEAL, 0, marker=Marker("o", 2.6)))
    if low.any():
        label = f"inclination < {low_inclination:g}° (azimuth ill-defined)"
        _set_apart(p_azi, path.md[low], azi[low], 2.6, label, "upper right")
    course = np.diff(path.md, prepend=path.md[0])
    grey = np.zeros(len(dls), bool) if short is None else short
    p_dls = Panel(boxes[2], Axis("MD (m)", limits=md), Axis(f"DLS ({dls_unit})"))
    p_dls.add(Bars((path.md - course)[~grey], course[~grey], dls[~grey], "#f0b27a", ORANGE))
    if grey.any():  # a short course's bar would be a hairline: a hollow marker instead
        label = f"{short_label} (not in the maximum)"
        _set_apart(p_dls, path.md[grey], dls[grey], 3.5, label, "upper left")
    return Chart(size, [p_inc, p_azi, p_dls])


def _set_apart(
    panel: Panel, md: FloatArray, values: FloatArray, size: float, label: str, legend: LegendLoc
) -> None:
    """Stations set apart on a profile (``md`` in m): hollow grey markers ``size`` pt
    across, named in the panel's legend at ``legend``."""
    panel.add(Line(md, values, GREY, 0, marker=Marker("o", size, hollow=True), label=label))
    panel.legend = legend


@dataclass(frozen=True)
class Ellipses:
    """Horizontal error ellipses (semi-axes m, major-axis azimuth deg) and vertical
    half-intervals at one confidence level."""

    md: FloatArray
    major: FloatArray
    minor: FloatArray
    azimuth: FloatArray
    vertical: FloatArray
    confidence: str
    """e.g. '95 %' or '1σ'"""


def ellipse(
    major: float, minor: float, azimuth: float, n: int = 73
) -> tuple[FloatArray, FloatArray]:
    """East and north of an ellipse about the origin: semi-axes ``major`` along
    ``azimuth`` (deg clockwise from north) and ``minor`` across it."""
    t = np.linspace(0.0, 2 * np.pi, n)
    a = np.radians(azimuth)
    along, across = major * np.cos(t), minor * np.sin(t)
    return along * np.sin(a) + across * np.cos(a), along * np.cos(a) - across * np.sin(a)


def error_ellipses(size: Size, ell: Ellipses, north_label: str, shown: int = 6) -> Chart:
    """Semi-axes against MD, and the ellipses of ``shown`` stations spread over the MD
    range drawn about a common centre."""
    b_md, b_shape = grid(size, 1, 2, wspace=0.8)
    p_md = Panel(
        b_md, Axis("MD (m)"), Axis(f"Half-axis at {ell.confidence} (m)"), id="ellipse-axes"
    )
    p_md.add(
        Line(ell.md, ell.major, BLUE, label="semi-major"),
        Line(ell.md, ell.minor, TEAL, label="semi-minor"),
        Line(ell.md, ell.vertical, ORANGE, dash=(4, 2), label="vertical"),
    )
    p_md.legend = "upper left"
    picks = np.unique(np.linspace(0, len(ell.md) - 1, shown).round().astype(int))
    picks = picks[ell.major[picks] > 0] if (ell.major[picks] > 0).any() else picks
    reach = 1.15 * (float(ell.major[picks].max()) or 1.0)
    p_shape = Panel(
        b_shape,
        Axis("East (m)", limits=(-reach, reach)),
        Axis(f"North (m, {north_label})", limits=(-reach, reach)),
        equal=True,
        legend="best",
        legend_size=6.5,
        id="ellipse-shapes",
    )
    for k, i in enumerate(picks):
        east, north = ellipse(float(ell.major[i]), float(ell.minor[i]), float(ell.azimuth[i]))
        p_shape.add(
            Polygon(east, north, series_colour(k), label=f"MD {round(float(ell.md[i])) + 0} m")
        )
    return Chart(size, [p_md, p_shape])


@dataclass(frozen=True)
class QcSeries:
    """One QC check along depth: the tested quantity, its allowed band and the verdicts.
    Rows that were not evaluated are left out (``skipped`` counts them)."""

    name: str
    """the check's name (the chart panel's id)"""
    unit: str
    """as printed (°/h, m/s²)"""
    x: FloatArray
    value: FloatArray
    low: FloatArray
    high: FloatArray
    passed: NDArray[np.bool_]
    quantity: str
    """what ``value`` is, e.g. 'measured − reference'"""
    skipped: int = 0
    title: str = ""
    """what a client reads as the chart's title (empty: ``name``)"""


BAND_WIDER = 5.0
"""A QC chart's axis shows its values only (the legend gives the band) when the tolerance
band is this many times wider than the values' range."""


def _band_text(s: QcSeries) -> str:
    """The tolerance band in words: '±100 °/h', '0 to 100 °/h' or 'up to ±0.7 °/h'."""
    low, high = float(np.nanmin(s.low)), float(np.nanmax(s.high))
    unit = f" {s.unit}" if s.unit else ""
    constant = np.ptp(s.low) == 0 and np.ptp(s.high) == 0
    if np.isclose(low, -high):
        return f"{'' if constant else 'up to '}±{fmt_sig(high)}{unit}"
    return f"{fmt_sig(low)} to {fmt_sig(high)}{unit}"


def qc_view(s: QcSeries) -> tuple[float, float] | None:
    """Y limits of a QC chart when its band is far wider than its values: the values and
    the reference 0 with a margin (None: show band and values alike)."""
    values = s.value[np.isfinite(s.value)]
    bands = np.concatenate([s.low, s.high])
    bands = bands[np.isfinite(bands)]
    if not len(values) or not len(bands):
        return None
    lo, hi = min(float(values.min()), 0.0), max(float(values.max()), 0.0)
    if hi - lo <= 0 or float(np.ptp(np.append(bands, [lo, hi]))) <= BAND_WIDER * (hi - lo):
        return None
    margin = 0.12 * (hi - lo)
    return lo - margin, hi + margin


def qc_charts(size: Size, series: Sequence[QcSeries], x_label: str = "MD (m)") -> Chart:
    """One panel per check: values with the tolerance band shaded, failures in red; where
    the band is far wider than the values (:func:`qc_view`) the axis is scaled to the
    values and the legend says what the band is."""
    ncols = 1 if len(series) == 1 else 2
    nrows = -(-len(series) // ncols)
    boxes = grid(size, nrows, ncols, hspace=0.55, top=0.3, wspace=0.75)
    panels = []
    for box, s in zip(boxes, series, strict=False):
        order = np.argsort(s.x, kind="stable")
        view = qc_view(s)
        ok = s.passed
        failed = int((~ok).sum())
        tail = f" — {failed} failed" if failed else ""
        band = f"tolerance {_band_text(s)} (beyond the axis)" if view is not None else ""
        panel = Panel(
            box,
            Axis(x_label, label_size=7),
            Axis(f"{s.quantity} ({s.unit})" if s.unit else s.quantity, limits=view, label_size=7),
            title=f"{s.title or s.name}{tail}",
            title_colour=RED if failed else NAVY,
            legend="best" if view is not None else None,
            id=f"qc-{s.name}".replace(" ", "-").replace("/", "-"),  # the panel in an SVG
        )
        x = s.x[order]
        panel.add(
            Band(x, s.low[order], s.high[order], BAND, step=True, label=band),
            Line(x, s.high[order], TEAL, 0.7, step=True),
            Line(x, s.low[order], TEAL, 0.7, step=True),
            Line(s.x[ok], s.value[ok], BLUE, 0, marker=Marker("o", 2.6)),
        )
        if failed:
            panel.add(Line(s.x[~ok], s.value[~ok], RED, 0, marker=Marker("x", 4.5, edge=1.0)))
        panels.append(panel)
    return Chart(size, panels)


def drift_correction(
    size: Size,
    time_h: FloatArray,
    correction: FloatArray,
    md: FloatArray,
    azi_raw: FloatArray,
    azi: FloatArray,
    outbound: NDArray[np.bool_],
    north_label: str,
) -> Chart:
    """The drift correction removed from each reading against time, and the azimuth as
    read and as corrected against MD (in-run filled, out-run hollow)."""
    b_t, b_md = grid(size, 1, 2, wspace=0.8)
    p_t = Panel(b_t, Axis("Time (h)"), Axis("Drift correction (°)"), legend="upper left")
    p_md = Panel(b_md, Axis("MD (m)"), Axis(f"Azimuth (°, {north_label})"), legend="best")
    raw = Marker(".", 4.0)
    for mask, label, hollow in ((~outbound, "in-run", False), (outbound, "out-run", True)):
        dot = Marker("o", 2.8, hollow=hollow)
        p_t.add(Line(time_h[mask], correction[mask], BLUE, 0, marker=dot, label=label))
        p_md.add(Line(md[mask], azi_raw[mask], GREY, 0, marker=raw))
        p_md.add(Line(md[mask], azi[mask], TEAL, 0, marker=dot, label=f"corrected, {label}"))
    p_md.add(Line(np.zeros(0), np.zeros(0), GREY, 0, marker=raw, label="as read"))
    return Chart(size, [p_t, p_md])


def allan_deviation(
    size: Size, tau: FloatArray, curves: dict[str, FloatArray], units: dict[str, str]
) -> Chart:
    """Allan deviation against averaging time, log–log, one panel per sensor kind."""
    kinds = [k for k in ("gyro", "acc") if any(a.startswith(k) for a in curves)]
    panels = []
    for box, kind in zip(grid(size, 1, len(kinds), wspace=0.85, left=0.85), kinds, strict=True):
        unit = next(units[a] for a in curves if a.startswith(kind))
        name = "Gyro" if kind == "gyro" else "Accelerometer"
        panel = Panel(
            box,
            Axis("Averaging time τ (s)", scale="log"),
            Axis(f"{name} Allan deviation ({unit})", scale="log"),
            legend="upper right",
        )
        for k, (axis, adev) in enumerate(a for a in curves.items() if a[0].startswith(kind)):
            panel.add(Line(tau, adev, series_colour(k), marker=Marker("o", 2.6), label=axis))
        panels.append(panel)
    return Chart(size, panels)


SERIES_CAP = 3.5
"""Half-width of the caps of the series-mean error bars, points."""


@dataclass(frozen=True)
class SeriesPoints:
    """Calibration data of one instrument: readings (optional), series means and the
    drift estimates (rates and σ in °/h)."""

    reading_time_min: FloatArray | None
    reading_error: FloatArray | None
    reading_series: NDArray[np.int64] | None
    series: NDArray[np.int64]
    mid_time_min: FloatArray
    mean_error: FloatArray
    sigma_mean: FloatArray
    fit_rate_h: float | None
    fit_sigma_h: float | None
    estimates: tuple[tuple[str, float, float, bool], ...]
    """(label, drift °/h, σ °/h, selected)"""


def calibration_series(size: Size, data: SeriesPoints) -> Chart:
    """Azimuth error against time with the series means (±2σ) and the fitted drift line;
    beside it every drift estimate with its ±σ."""
    b_t, b_est = grid(size, 1, 2, wspace=1.05, left=0.75, right=0.15, width_ratios=(1.55, 1.0))
    p_t = Panel(b_t, Axis("Time (min)"), Axis("Azimuth error (°)"), legend="best")
    ids = list(data.series)
    if data.reading_time_min is not None and data.reading_error is not None:
        assert data.reading_series is not None
        for k, sid in enumerate(ids):
            rows = data.reading_series == sid
            p_t.add(
                Line(
                    data.reading_time_min[rows],
                    data.reading_error[rows],
                    series_colour(k),
                    0,
                    marker=Marker("o", 2.6),
                    alpha=0.55,
                )
            )
    p_t.add(
        ErrorBars(
            data.mid_time_min,
            data.mean_error,
            2 * data.sigma_mean,
            NAVY,
            Marker("s", 5.0),
            cap=SERIES_CAP,
            width=1.2,
            label="series mean ± 2σ",
            id="series",  # ids in an SVG: what the labels must keep clear of
        )
    )
    for k, sid in enumerate(ids):  # right of the bar, clear of its caps
        p_t.add(
            Text(
                float(data.mid_time_min[k]),
                float(data.mean_error[k]),
                f"S{sid}",
                size=7.5,
                colour=NAVY,
                dx=SERIES_CAP + 4,
                va="center",
                bold=True,
                box=True,
                id=f"series-label-{sid}",
            )
        )
    if data.fit_rate_h is not None:
        weights = 1.0 / np.maximum(data.sigma_mean, 1e-12) ** 2
        t0 = float(np.average(data.mid_time_min, weights=weights))
        m0 = float(np.average(data.mean_error, weights=weights))
        span = np.array([data.mid_time_min.min(), data.mid_time_min.max()])
        pad = 0.08 * float(np.ptp(span) or 1.0)
        t_line = np.array([span[0] - pad, span[1] + pad])
        p_t.add(
            Line(
                t_line,
                m0 + data.fit_rate_h / 60.0 * (t_line - t0),
                ORANGE,
                label=f"fitted drift {fmt_measured(data.fit_rate_h, data.fit_sigma_h)} °/h",
            )
        )
    labels = [f"{e[0]} (used)" if e[3] else e[0] for e in data.estimates]
    y = np.arange(len(labels), dtype=float)[::-1]
    rate = np.array([e[1] for e in data.estimates])
    sigma = np.array([e[2] for e in data.estimates])
    used = np.array([e[3] for e in data.estimates])
    p_est = Panel(
        b_est,
        Axis("Drift rate ± σ (°/h)"),
        Axis(
            limits=(-0.6, len(labels) - 0.4),
            ticks=y.tolist(),
            labels=labels,
            grid=False,
            tick_size=6.5,
        ),
    )
    if data.fit_rate_h is not None:
        p_est.add(Span(data.fit_rate_h, data.fit_rate_h, ORANGE, axis="x"))
    shapes: tuple[tuple[BoolArray, Shape, str], ...] = ((~used, "o", BLUE), (used, "D", ORANGE))
    for mask, shape, colour in shapes:
        p_est.add(ErrorBars(rate[mask], y[mask], sigma[mask], colour, Marker(shape, 4.0), "x", 2.5))
    return Chart(size, [p_t, p_est])


def full_rate(size: Size, series: FullRate, path: Path3, inc: FloatArray, azi: FloatArray) -> Chart:
    """Inclination and azimuth of every sample against MD (their per-column envelope,
    :mod:`.envelope`), the stations on top as dots (on the azimuth panel only when both
    have one north reference)."""
    b_inc, b_azi = grid(size, 2, 1, hspace=0.12, top=0.15)
    same_north = series.north == path.north_label
    md = _span(np.concatenate([series.inc[0], series.azi[0], path.md]))
    p_inc = Panel(b_inc, Axis(limits=md, tick_labels=False), Axis("Inclination (°)"))
    p_inc.legend = "upper left"
    p_azi = Panel(b_azi, Axis("MD (m)", limits=md), Axis(f"Azimuth (°, {series.north})"))
    for panel, (x, y), at, colour in (
        (p_inc, series.inc, inc, BLUE),
        (p_azi, series.azi, azi if same_north else None, TEAL),
    ):
        panel.add(Line(x, y, GREY, 0.6, label=f"samples ({series.samples:,})"))
        if at is not None:
            panel.add(Line(path.md, at, colour, 0, marker=Marker("o", 2.6), label="stations"))
    return Chart(size, [p_inc, p_azi])

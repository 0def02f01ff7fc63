"""Report figures. Each function draws into a matplotlib figure or subfigure it is given
(so the same drawing lands in the HTML page and on a PDF page) with margins in inches.

Positions are NED relative to the wellhead (north, east, TVD down, metres); angles in
degrees; azimuths clockwise from the north reference named in the labels.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure
from matplotlib.patches import Ellipse
from matplotlib.ticker import MaxNLocator
from matplotlib.typing import RcKeyType
from numpy.typing import NDArray

from pipeline.reports.envelope import FullRate
from pipeline.reports.numbers import fmt_azimuth, fmt_sig

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
Canvas = Figure | SubFigure
"""What a plot function draws into: a whole figure (HTML) or a region of a page (PDF)."""

INK = "#1f2933"
NAVY = "#1b365d"
BLUE = "#2f6fb0"
ORANGE = "#d9731a"
TEAL = "#23867a"
RED = "#c0392b"
GREY = "#8a94a6"
BAND = "#dcefe3"
SERIES_COLOURS = (BLUE, ORANGE, TEAL, "#8e44ad", "#b5651d", "#34495e", "#d35400", "#16a085")

STYLE: dict[RcKeyType, Any] = {
    "font.family": "DejaVu Sans",
    "font.size": 8,
    "axes.titlesize": 8.5,
    "axes.titleweight": "bold",
    "axes.titlecolor": NAVY,
    "axes.titlelocation": "left",
    "axes.labelsize": 8,
    "axes.labelcolor": INK,
    "axes.edgecolor": "#9aa5b1",
    "axes.linewidth": 0.6,
    "axes.grid": True,
    "axes.axisbelow": True,
    "grid.color": "#e1e6ec",
    "grid.linewidth": 0.5,
    "xtick.labelsize": 7.5,
    "ytick.labelsize": 7.5,
    "xtick.color": "#52606d",
    "ytick.color": "#52606d",
    "xtick.major.size": 2.5,
    "ytick.major.size": 2.5,
    "legend.fontsize": 7,
    "legend.frameon": False,
    "lines.linewidth": 1.3,
    "lines.markersize": 3.5,
    "savefig.facecolor": "white",
    "svg.fonttype": "none",
    "svg.hashsalt": "gyropipe",
    "pdf.fonttype": 42,
}
"""rcParams of every report figure (applied with ``matplotlib.rc_context``)."""


def axes_grid(
    fig: Canvas,
    nrows: int = 1,
    ncols: int = 1,
    *,
    left: float = 0.75,
    right: float = 0.2,
    bottom: float = 0.5,
    top: float = 0.3,
    hspace: float = 0.35,
    wspace: float = 0.6,
    sharex: bool = False,
    width_ratios: Sequence[float] | None = None,
) -> list[Axes]:
    """A grid of axes with margins and gaps given in inches (so text never collides,
    whatever the figure size); returned row by row."""
    width = fig.bbox.width / fig.dpi
    height = fig.bbox.height / fig.dpi
    grid = fig.add_gridspec(
        nrows,
        ncols,
        left=left / width,
        right=1 - right / width,
        bottom=bottom / height,
        top=1 - top / height,
        hspace=hspace * nrows / max(height - top - bottom - hspace * (nrows - 1), 0.1),
        wspace=wspace * ncols / max(width - left - right - wspace * (ncols - 1), 0.1),
        width_ratios=width_ratios,
    )
    axes: list[Axes] = []
    for i in range(nrows):
        for j in range(ncols):
            share = axes[j] if sharex and i > 0 else None
            axes.append(fig.add_subplot(grid[i, j], sharex=share))
    return axes


def _pieces(values: FloatArray, offsets: Sequence[int]) -> list[FloatArray]:
    """``values`` split into the contiguous surveys delimited by ``offsets``."""
    return [values[lo:hi] for lo, hi in itertools.pairwise(offsets)]


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


def _plan_axes(ax: Axes, path: Path3) -> None:
    pieces = zip(_pieces(path.north, path.offsets), _pieces(path.east, path.offsets), strict=True)
    for n, e in pieces:
        ax.plot(e, n, color=BLUE, marker="o", markersize=2.2, markeredgewidth=0)
    ax.plot(0.0, 0.0, marker="s", color=NAVY, markersize=5, linestyle="none", label="wellhead")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("East (m)")
    ax.set_ylabel(f"North (m, {path.north_label})")


def plan_view(fig: Canvas, path: Path3) -> None:
    """Horizontal projection with the closure from the wellhead to the last station."""
    (ax,) = axes_grid(fig, left=0.85)
    _plan_axes(ax, path)
    n_end, e_end = path.north[-1], path.east[-1]
    distance = float(np.hypot(n_end, e_end))
    direction = float(np.degrees(np.arctan2(e_end, n_end)))
    ax.plot([0.0, e_end], [0.0, n_end], color=GREY, linestyle="--", linewidth=0.8)
    ax.plot(e_end, n_end, marker="v", color=ORANGE, markersize=6, linestyle="none", label="TD")
    ax.annotate(
        f"TD  MD {path.md[-1]:.1f} m\nclosure {distance:.1f} m @ {fmt_azimuth(direction)}°",
        (e_end, n_end),
        xytext=(8, -4),
        textcoords="offset points",
        fontsize=7,
        color=INK,
        va="top",
    )
    ax.legend(loc="upper left")


def vertical_section(fig: Canvas, vs: FloatArray, path: Path3, azimuth: float | None) -> None:
    """Vertical section (horizontal displacement along the section azimuth) against TVD."""
    (ax,) = axes_grid(fig, left=0.85)
    for v, t in zip(_pieces(vs, path.offsets), _pieces(path.tvd, path.offsets), strict=True):
        ax.plot(v, t, color=BLUE, marker="o", markersize=2.2, markeredgewidth=0)
    ax.plot(vs[-1], path.tvd[-1], marker="v", color=ORANGE, markersize=6, linestyle="none")
    ax.set_aspect("equal", adjustable="datalim")
    ax.invert_yaxis()
    plane = f" @ {fmt_azimuth(azimuth)}° {path.north_label}" if azimuth is not None else ""
    ax.set_xlabel(f"Vertical section (m){plane}")
    ax.set_ylabel("TVD (m)")


def view_3d(fig: Canvas, path: Path3) -> None:
    """Static 3-D view (east, north, TVD down) with the path's shadow on the bottom plane;
    east and north share one scale, the vertical axis is scaled to fit the box."""
    ax: Any = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d")
    floor = float(path.tvd.max())
    for n, e, t in zip(
        _pieces(path.north, path.offsets),
        _pieces(path.east, path.offsets),
        _pieces(path.tvd, path.offsets),
        strict=True,
    ):
        ax.plot(e, n, np.full_like(t, floor), color=GREY, linewidth=0.8, linestyle="--")
        ax.plot(e, n, t, color=BLUE, linewidth=1.8)
    ax.scatter([0.0], [0.0], [path.tvd[0]], color=NAVY, marker="s", s=18)
    ax.scatter([path.east[-1]], [path.north[-1]], [path.tvd[-1]], color=ORANGE, marker="v", s=24)
    half = max(float(np.ptp(path.east)), float(np.ptp(path.north)), 1.0) / 2 * 1.1
    for centre, setter in (
        ((path.east.max() + path.east.min()) / 2, ax.set_xlim),
        ((path.north.max() + path.north.min()) / 2, ax.set_ylim),
    ):
        setter(centre - half, centre + half)
    ax.set_zlim(floor, min(0.0, float(path.tvd.min())))
    ax.set_xlabel("East (m)", labelpad=3)
    ax.set_ylabel("North (m)", labelpad=3)
    ax.set_zlabel("TVD (m)", labelpad=5)
    ax.tick_params(labelsize=6.5, pad=1)
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(5))
    ax.view_init(elev=20, azim=-55)
    ax.set_box_aspect((1.0, 1.0, 0.85), zoom=0.82)


def profiles(
    fig: Canvas,
    path: Path3,
    inc: FloatArray,
    azi: FloatArray,
    dls: FloatArray,
    dls_unit: str,
    low_inclination: float = 3.0,
    short: BoolArray | None = None,
    short_label: str = "short courses",
) -> None:
    """Inclination, azimuth and dogleg severity against MD; azimuths of stations below
    ``low_inclination`` (ill-defined) drawn hollow, DLS over ``short`` courses grey."""
    ax_inc, ax_azi, ax_dls = axes_grid(fig, 3, 1, hspace=0.12, sharex=True, top=0.15)
    for md, i in zip(_pieces(path.md, path.offsets), _pieces(inc, path.offsets), strict=True):
        ax_inc.plot(md, i, color=BLUE, marker="o", markersize=2, markeredgewidth=0)
    ax_inc.set_ylabel("Inclination (°)")
    low = inc < low_inclination
    ax_azi.plot(path.md[~low], azi[~low], color=TEAL, marker="o", markersize=2.4, linestyle="none")
    if low.any():
        ax_azi.plot(
            path.md[low],
            azi[low],
            marker="o",
            markersize=2.4,
            linestyle="none",
            markerfacecolor="none",
            markeredgecolor=GREY,
            markeredgewidth=0.6,
            label=f"inclination < {low_inclination:g}° (azimuth ill-defined)",
        )
        ax_azi.legend(loc="upper right")
    ax_azi.set_ylim(-5, 365)
    ax_azi.set_yticks([0, 90, 180, 270, 360])
    ax_azi.set_ylabel(f"Azimuth (°, {path.north_label})")
    course = np.diff(path.md, prepend=path.md[0])
    grey = np.zeros(len(dls), bool) if short is None else short
    ax_dls.bar(
        (path.md - course)[~grey],
        dls[~grey],
        width=course[~grey],
        align="edge",
        color="#f0b27a",
        edgecolor=ORANGE,
        linewidth=0.5,
    )
    if grey.any():  # a short course's bar would be a hairline: a hollow marker instead
        ax_dls.plot(
            path.md[grey],
            dls[grey],
            marker="o",
            markersize=3.5,
            linestyle="none",
            markerfacecolor="none",
            markeredgecolor=GREY,
            label=f"{short_label} (not in the maximum)",
        )
        ax_dls.legend(loc="upper left")
    ax_dls.set_ylabel(f"DLS ({dls_unit})")
    ax_dls.set_xlabel("MD (m)")
    for ax in (ax_inc, ax_azi):
        ax.tick_params(labelbottom=False)


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


def error_ellipses(fig: Canvas, ell: Ellipses, north_label: str, shown: int = 6) -> None:
    """Semi-axes against MD, and the ellipses of ``shown`` stations spread over the MD
    range drawn about a common centre."""
    ax_md, ax_shape = axes_grid(fig, 1, 2, wspace=0.8)
    ax_md.plot(ell.md, ell.major, color=BLUE, label="semi-major")
    ax_md.plot(ell.md, ell.minor, color=TEAL, label="semi-minor")
    ax_md.plot(ell.md, ell.vertical, color=ORANGE, linestyle="--", label="vertical")
    ax_md.set_xlabel("MD (m)")
    ax_md.set_ylabel(f"Half-axis at {ell.confidence} (m)")
    ax_md.legend(loc="upper left")
    picks = np.unique(np.linspace(0, len(ell.md) - 1, shown).round().astype(int))
    picks = picks[ell.major[picks] > 0] if (ell.major[picks] > 0).any() else picks
    reach = float(ell.major[picks].max()) or 1.0
    for k, i in enumerate(picks):
        colour = SERIES_COLOURS[k % len(SERIES_COLOURS)]
        ax_shape.add_patch(
            Ellipse(
                (0.0, 0.0),
                2 * ell.minor[i],
                2 * ell.major[i],
                angle=-float(ell.azimuth[i]),
                fill=False,
                edgecolor=colour,
                linewidth=1.2,
                label=f"MD {ell.md[i]:.0f} m",
            )
        )
    ax_shape.set_xlim(-1.15 * reach, 1.15 * reach)
    ax_shape.set_ylim(-1.15 * reach, 1.15 * reach)
    ax_shape.set_aspect("equal")
    ax_shape.set_xlabel("East (m)")
    ax_shape.set_ylabel(f"North (m, {north_label})")
    ax_shape.legend(loc="best", fontsize=6.5)


@dataclass(frozen=True)
class QcSeries:
    """One QC check along depth: the tested quantity, its allowed band and the verdicts.
    Rows that were not evaluated are left out (``skipped`` counts them)."""

    name: str
    unit: str
    x: FloatArray
    value: FloatArray
    low: FloatArray
    high: FloatArray
    passed: NDArray[np.bool_]
    quantity: str
    """what ``value`` is, e.g. 'measured − reference'"""
    skipped: int = 0


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


def qc_charts(fig: Canvas, series: Sequence[QcSeries], x_label: str = "MD (m)") -> None:
    """One panel per check: values with the tolerance band shaded, failures in red; where
    the band is far wider than the values (:func:`qc_view`) the axis is scaled to the
    values and the legend says what the band is."""
    ncols = 1 if len(series) == 1 else 2
    nrows = -(-len(series) // ncols)
    axes = axes_grid(fig, nrows, ncols, hspace=0.55, top=0.3, wspace=0.75)
    for ax, s in zip(axes, series, strict=False):
        ax.set_gid(f"qc-{s.name}".replace(" ", "-").replace("/", "-"))  # the panel in an SVG
        order = np.argsort(s.x, kind="stable")
        band = ax.fill_between(
            s.x[order], s.low[order], s.high[order], color=BAND, step="mid", linewidth=0
        )
        ax.plot(s.x[order], s.high[order], color=TEAL, linewidth=0.7, drawstyle="steps-mid")
        ax.plot(s.x[order], s.low[order], color=TEAL, linewidth=0.7, drawstyle="steps-mid")
        ok = s.passed
        ax.plot(s.x[ok], s.value[ok], marker="o", markersize=2.4, linestyle="none", color=BLUE)
        if (~ok).any():
            ax.plot(s.x[~ok], s.value[~ok], marker="x", markersize=4.5, linestyle="none", color=RED)
        view = qc_view(s)
        if view is not None:
            ax.set_ylim(*view)
            band.set_label(f"tolerance {_band_text(s)} (beyond the axis)")
            ax.legend(handles=[band], loc="best")
        failed = int((~ok).sum())
        tail = f" — {failed} failed" if failed else ""
        ax.set_title(f"{s.name}{tail}", color=RED if failed else NAVY)
        ax.set_ylabel(f"{s.quantity} ({s.unit})" if s.unit else s.quantity, fontsize=7)
        ax.set_xlabel(x_label, fontsize=7)
    for ax in axes[len(series) :]:
        ax.set_visible(False)


def drift_correction(
    fig: Canvas,
    time_h: FloatArray,
    correction: FloatArray,
    md: FloatArray,
    azi_raw: FloatArray,
    azi: FloatArray,
    outbound: NDArray[np.bool_],
    north_label: str,
) -> None:
    """The drift correction removed from each reading against time, and the azimuth as
    read and as corrected against MD (in-run filled, out-run hollow)."""
    ax_t, ax_md = axes_grid(fig, 1, 2, wspace=0.8)
    for mask, label, face in ((~outbound, "in-run", None), (outbound, "out-run", "none")):
        dots: dict[str, Any] = {
            "marker": "o",
            "markersize": 2.6,
            "linestyle": "none",
            "markerfacecolor": face,
        }
        ax_t.plot(time_h[mask], correction[mask], color=BLUE, label=label, **dots)
        ax_md.plot(md[mask], azi_raw[mask], marker=".", markersize=2, linestyle="none", color=GREY)
        ax_md.plot(md[mask], azi[mask], color=TEAL, label=f"corrected, {label}", **dots)
    ax_md.plot([], [], marker=".", linestyle="none", color=GREY, label="as read")
    ax_t.set_xlabel("Time (h)")
    ax_t.set_ylabel("Drift correction (°)")
    ax_t.legend(loc="upper left")
    ax_md.set_xlabel("MD (m)")
    ax_md.set_ylabel(f"Azimuth (°, {north_label})")
    ax_md.legend(loc="best")


def allan_deviation(
    fig: Canvas, tau: FloatArray, curves: dict[str, FloatArray], units: dict[str, str]
) -> None:
    """Allan deviation against averaging time, log–log, one panel per sensor kind."""
    kinds = [k for k in ("gyro", "acc") if any(a.startswith(k) for a in curves)]
    axes = axes_grid(fig, 1, len(kinds), wspace=0.85, left=0.85)
    for ax, kind in zip(axes, kinds, strict=True):
        for k, (axis, adev) in enumerate(a for a in curves.items() if a[0].startswith(kind)):
            ax.loglog(tau, adev, marker="o", markersize=2.4, color=SERIES_COLOURS[k], label=axis)
        ax.set_xlabel("Averaging time τ (s)")
        unit = next(units[a] for a in curves if a.startswith(kind))
        name = "Gyro" if kind == "gyro" else "Accelerometer"
        ax.set_ylabel(f"{name} Allan deviation ({unit})")
        ax.grid(True, which="minor", color="#f0f3f6", linewidth=0.4)
        ax.legend(loc="upper right")


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
    estimates: tuple[tuple[str, float, float, bool], ...]
    """(label, drift °/h, σ °/h, selected)"""


def calibration_series(fig: Canvas, data: SeriesPoints) -> None:
    """Azimuth error against time with the series means (±2σ) and the fitted drift line;
    beside it every drift estimate with its ±σ."""
    ax_t, ax_est = axes_grid(
        fig, 1, 2, wspace=1.05, left=0.75, right=0.15, width_ratios=(1.55, 1.0)
    )
    ids = list(data.series)
    if data.reading_time_min is not None and data.reading_error is not None:
        assert data.reading_series is not None
        for k, sid in enumerate(ids):
            rows = data.reading_series == sid
            ax_t.plot(
                data.reading_time_min[rows],
                data.reading_error[rows],
                marker="o",
                markersize=2.2,
                linestyle="none",
                alpha=0.55,
                color=SERIES_COLOURS[k % len(SERIES_COLOURS)],
            )
    means = ax_t.errorbar(
        data.mid_time_min,
        data.mean_error,
        yerr=2 * data.sigma_mean,
        fmt="s",
        color=NAVY,
        markersize=5,
        capsize=SERIES_CAP,
        label="series mean ± 2σ",
        zorder=3,
    )
    _, caps, bars = means.lines  # ids in an SVG: what the labels must keep clear of
    for k, artist in enumerate((*caps, *bars)):
        artist.set_gid(f"series-bar-{k}")
    for k, sid in enumerate(ids):  # right of the bar, clear of its caps
        ax_t.annotate(
            f"S{sid}",
            (data.mid_time_min[k], data.mean_error[k]),
            xytext=(SERIES_CAP + 4, 0),
            textcoords="offset points",
            ha="left",
            va="center",
            fontsize=7.5,
            fontweight="bold",
            color=NAVY,
            bbox={"boxstyle": "round,pad=0.15", "facecolor": "white", "edgecolor": "none"},
            zorder=4,
            gid=f"series-label-{sid}",
        )
    if data.fit_rate_h is not None:
        weights = 1.0 / np.maximum(data.sigma_mean, 1e-12) ** 2
        t0 = float(np.average(data.mid_time_min, weights=weights))
        m0 = float(np.average(data.mean_error, weights=weights))
        span = np.array([data.mid_time_min.min(), data.mid_time_min.max()])
        pad = 0.08 * float(np.ptp(span) or 1.0)
        t_line = np.array([span[0] - pad, span[1] + pad])
        ax_t.plot(
            t_line,
            m0 + data.fit_rate_h / 60.0 * (t_line - t0),
            color=ORANGE,
            label=f"fitted drift {data.fit_rate_h:.2f} °/h",
        )
    ax_t.set_xlabel("Time (min)")
    ax_t.set_ylabel("Azimuth error (°)")
    ax_t.legend(loc="best")

    labels = [f"{e[0]} (used)" if e[3] else e[0] for e in data.estimates]
    y = np.arange(len(labels))[::-1]
    rate = np.array([e[1] for e in data.estimates])
    sigma = np.array([e[2] for e in data.estimates])
    used = np.array([e[3] for e in data.estimates])
    if data.fit_rate_h is not None:
        ax_est.axvline(data.fit_rate_h, color=ORANGE, linewidth=0.8)
    for mask, marker, colour in ((~used, "o", BLUE), (used, "D", ORANGE)):
        ax_est.errorbar(
            rate[mask],
            y[mask],
            xerr=sigma[mask],
            fmt=marker,
            color=colour,
            markersize=4,
            capsize=2.5,
        )
    ax_est.set_yticks(y, labels, fontsize=6.5)
    ax_est.set_xlabel("Drift rate ± σ (°/h)")
    ax_est.grid(False, axis="y")


def full_rate(fig: Canvas, series: FullRate, path: Path3, inc: FloatArray, azi: FloatArray) -> None:
    """Inclination and azimuth of every sample against MD (their per-column envelope,
    :mod:`.envelope`), the stations on top as dots (on the azimuth panel only when both
    have one north reference)."""
    ax_inc, ax_azi = axes_grid(fig, 2, 1, hspace=0.12, sharex=True, top=0.15)
    same_north = series.north == path.north_label
    for ax, (x, y), at, colour in (
        (ax_inc, series.inc, inc, BLUE),
        (ax_azi, series.azi, azi if same_north else None, TEAL),
    ):
        ax.plot(x, y, color=GREY, linewidth=0.6, label=f"samples ({series.samples:,})")
        if at is not None:
            ax.plot(
                path.md, at, "o", color=colour, markersize=2.4, linestyle="none", label="stations"
            )
    ax_inc.set_ylabel("Inclination (°)")
    ax_inc.legend(loc="upper left")
    ax_inc.tick_params(labelbottom=False)
    ax_azi.set_ylabel(f"Azimuth (°, {series.north})")
    ax_azi.set_xlabel("MD (m)")

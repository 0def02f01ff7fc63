"""Full-rate series in report figures: reduced batch by batch to a per-pixel-column envelope
that is bounded in points whatever the survey's length and draws what the raw line draws."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pytest
from PIL import Image, ImageDraw

from pipeline.reports import plots
from pipeline.reports.charts.layout import lay_out
from pipeline.reports.charts.model import Chart, Line
from pipeline.reports.charts.scene import Group, Path
from pipeline.reports.envelope import COLUMNS, Envelope, full_rate


def survey(samples: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MD (m) creeping forward with pauses, a smooth inclination and a noisy azimuth, deg."""
    rng = np.random.default_rng(seed)
    md = 300.0 + np.cumsum(rng.uniform(0.0, 2400.0 / samples, samples))
    inc = 45.0 * np.clip((md - 500.0) / 700.0, 0.0, 1.0) + rng.normal(0.0, 0.05, samples)
    azi = 40.0 + 2.0 * np.sin(md / 90.0) + rng.normal(0.0, 0.3, samples)
    return md, inc, azi


def batches(md: np.ndarray, inc: np.ndarray, azi: np.ndarray, rows: int) -> list[pa.RecordBatch]:
    return [
        pa.RecordBatch.from_pydict(
            {"md": md[k : k + rows], "inc": inc[k : k + rows], "azi": azi[k : k + rows]}
        )
        for k in range(0, len(md), rows)
    ]


def drawn(series: plots.FullRate, md: np.ndarray, inc: np.ndarray, azi: np.ndarray) -> Chart:
    path = plots.Path3(md, md * 0, md * 0, md, (0, len(md)), "true north")
    return plots.full_rate((6.9, 4.0), series, path, inc, azi)


def line_points(chart: Chart) -> list[int]:
    return [len(a.x) for p in chart.panels for a in p.artists if isinstance(a, Line)]


def sample_paths(group: Group) -> list[Path]:
    """The laid-out lines of the samples (grey) in ``group``."""
    found: list[Path] = []
    for item in group.items:
        if isinstance(item, Group):
            found += sample_paths(item)
        elif isinstance(item, Path) and item.stroke and item.stroke.colour == plots.GREY:
            found.append(item)
    return found


def rasterised(chart: Chart, dpi: int = 100) -> np.ndarray:
    """The chart's sample lines drawn one pixel wide at ``dpi`` (grey levels)."""
    scene = lay_out(chart)
    scale = dpi / 72.0
    image = Image.new("L", (round(scene.width * scale), round(scene.height * scale)), 255)
    pen = ImageDraw.Draw(image)
    for path in sample_paths(scene.root):
        for part in path.parts:
            pen.line([(float(x), float(y)) for x, y in part * scale], fill=0, width=1)
    return np.asarray(image).astype(int)


@pytest.mark.parametrize("samples", [30_000, 3_000_000])
def test_figure_series_is_bounded_whatever_the_survey_length(samples: int):
    md, inc, azi = survey(samples)
    stations = np.arange(0, samples, samples // 150)
    series = full_rate(batches(md, inc, azi, 65_536), "true north")
    assert series.samples == samples
    counts = line_points(drawn(series, md[stations], inc[stations], azi[stations]))
    assert max(counts) <= 2 * COLUMNS  # the sample lines; stations keep their 151 points
    assert sorted(counts)[:2] == [len(stations)] * 2


def test_envelope_keeps_every_bins_extremes_in_any_order():
    """Batches of uneven sizes, x out of order and reaching back before the first batch,
    NaNs: each bin's lowest and highest value and where they are equal the raw data's."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-50.0, 1000.0, 400_000)
    x[:1000] = rng.uniform(400.0, 410.0, 1000)  # the first batch is narrow
    y = np.sin(x / 7.0) + rng.normal(0.0, 0.2, len(x))
    y[rng.integers(0, len(x), 500)] = np.nan
    env = Envelope()
    start = 0
    for size in (1000, 7, 50_000, 123_457, 300_000):
        env.add(x[start : start + size], y[start : start + size])
        start += size
    px, py = env.points()
    assert len(px) <= 2 * COLUMNS and np.all(np.diff(px) >= 0)
    ok = np.isfinite(y)
    assert env.samples == ok.sum()
    edges = env.origin + env.width * np.arange(COLUMNS + 1)
    raw_bin = np.searchsorted(edges, x[ok], side="right") - 1
    env_bin = np.searchsorted(edges, px, side="right") - 1
    for reduce in (np.fmin, np.fmax):
        fill = np.inf if reduce is np.fmin else -np.inf
        raw, ours = np.full(COLUMNS, fill), np.full(COLUMNS, fill)
        reduce.at(raw, raw_bin, y[ok])
        reduce.at(ours, env_bin, py)
        assert np.array_equal(raw, ours)
    assert edges[0] <= x[ok].min() and x[ok].max() < edges[-1]
    assert (x[ok].max() - x[ok].min()) > 0.25 * (edges[-1] - edges[0])  # bins not too wide


def test_envelope_draws_what_the_raw_line_draws():
    md, inc, azi = survey(400_000, seed=5)
    stations = np.arange(0, len(md), 4000)
    reduced = full_rate(batches(md, inc, azi, 65_536), "true north")
    whole = plots.FullRate((md, inc), (md, azi), len(md), "true north")
    images = [
        rasterised(drawn(series, md[stations], inc[stations], azi[stations]))
        for series in (reduced, whole)
    ]
    assert (images[1] < 128).mean() > 0.01  # the raw lines do draw
    differs = np.abs(images[0] - images[1]) > 64
    assert differs.mean() < 0.002


def test_a_series_columns_envelope_as_each_alone_whatever_they_leave_out():
    """full_rate's inclination and azimuth share one binning per batch where they keep the
    same samples: the same envelopes as each column folded alone, also where one column's
    NaNs leave it other samples (and other bins) than the other's, or none in a batch."""
    md, inc, azi = survey(200_000, seed=8)
    md[::997] = md[::997] - 30.0  # back steps: not in order
    inc[50_000:50_040] = np.nan
    azi[150_000:] = np.nan  # the azimuth's last batches empty, its range shorter
    series = full_rate(batches(md, inc, azi, 65_536), "grid north")
    for got, y in ((series.inc, inc), (series.azi, azi)):
        alone = Envelope()
        for k in range(0, len(md), 65_536):
            alone.add(md[k : k + 65_536], y[k : k + 65_536])
        want = alone.points()
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert series.samples == np.isfinite(inc).sum()

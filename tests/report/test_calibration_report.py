"""The drift calibration report through `gyropipe run pipelines/calibration.yaml`: on the
bundled sample (linear drift) and on a simulated instrument whose drift is not linear."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
from report_support import (
    assert_self_contained,
    assert_signoff_before_appendix,
    figure_regions,
    figure_svg,
    ink,
    inspect,
    overlap,
    pdf_pages,
    svg_boxes,
)

from pipeline.sim.calibration import CalibrationPlan, simulate_calibration
from pipeline.sim.spec import Drift
from tests_support import gyropipe_cli


def number(cell: str) -> float:
    return float(cell.replace("−", "-"))


def calibrate(readings: str, out: Path, *options: str) -> Path:
    gyropipe_cli(
        "run",
        "pipelines/calibration.yaml",
        "--input",
        readings,
        "--out",
        str(out),
        *options,
        check=True,
    )
    return out


def test_bundled_calibration_report(browser: Any, tmp_path: Path):
    out = calibrate("examples/calibration-ig50.csv", tmp_path / "out")
    html = out / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    assert page.figures == ["fig-series"]
    assert "Linear drift" in page.text and "IG50-0417" in page.text

    series = pq.read_table(out / "drift.series.parquet").to_pylist()
    shown = page.tables["series"]
    assert [int(r[0]) for r in shown] == [s["series"] for s in series]
    assert [number(r[3]) for r in shown] == pytest.approx(
        [s["mean_error"] for s in series], abs=5e-4
    )
    result = pq.read_table(out / "drift.result.parquet").to_pylist()
    estimates = page.tables["estimates"]
    assert [r[0] for r in estimates] == [r["method"] for r in result]
    assert [number(r[2]) for r in estimates] == pytest.approx(
        [r["drift_deg_h"] for r in result], abs=5e-4
    )
    # σ with two significant digits: within 5 %
    assert [number(r[3]) for r in estimates] == pytest.approx(
        [r["sigma_deg_h"] for r in result], rel=0.05
    )
    assert [number(r[5]) for r in estimates] == pytest.approx(
        [r["sigma_deg_min"] for r in result], rel=0.05
    )
    used = [r[0] for r in estimates if r[-1] == "selected"]
    assert used == ["fit"]
    traditional = next(r for r in result if r["method"] == "traditional")
    shown = re.search(r"Traditional estimate\s+(−?[\d.]+) ± ([\d.]+) °/h", page.text)
    assert shown is not None, page.text
    drift, sigma = shown.group(1), shown.group(2)
    assert len(drift.partition(".")[2]) >= 3  # at least the table's 3 decimals
    assert number(drift) == pytest.approx(traditional["drift_deg_h"], abs=5e-4)
    assert number(sigma) == pytest.approx(traditional["sigma_deg_h"], rel=0.05)

    pages = pdf_pages(out / "report.pdf", tmp_path)
    regions = figure_regions(pages)
    assert list(regions) == [1] and ink(regions[1]) > 0.02
    words = " ".join(w[0] for p in pages for w in p.words)
    assert "Linear drift" in words and "traditional" in words


def test_calibration_report_has_a_signoff_block(browser: Any, tmp_path: Path):
    """A calibration certificate is signed like a survey report (#28 item 9)."""
    assert_signoff_before_appendix(browser, calibrate("examples/calibration-ig50.csv", tmp_path))


def test_non_linear_drift_is_a_failed_verdict(browser: Any, tmp_path: Path):
    plan = CalibrationPlan(
        series=6, reading_noise=1.0, drift=Drift(rate=4.0, curvature=40.0), seed=5
    )
    pq.write_table(simulate_calibration(plan), tmp_path / "cal.parquet")
    out = calibrate(str(tmp_path / "cal.parquet"), tmp_path / "out")
    result = pq.read_table(out / "drift.result.parquet")
    assert result.column("verdict")[0].as_py().startswith("non-linear")
    page = inspect(browser, out / "report.html")
    assert "NOT linear: instrument unfit or needs a non-linear drift model" in page.text
    verdict = (out / "report.html").read_text(encoding="utf-8")
    assert '<p class="verdict fail">NOT linear' in verdict
    words = " ".join(w[0] for p in pdf_pages(out / "report.pdf", tmp_path) for w in p.words)
    assert "NOT linear" in words


PAPER = "Usovershenstvovannaya metodika opredeleniya kursovogo ukhoda giroskopicheskikh"


def test_calibration_report_cites_the_method_by_its_paper(browser: Any, tmp_path: Path):
    """A client document: the method is cited by its published paper in a reference list,
    results are stated plainly, no internal names (issue #18, item 6)."""
    out = calibrate("examples/calibration-ig50.csv", tmp_path / "out")
    page = inspect(browser, out / "report.html")
    words = " ".join(w[0] for p in pdf_pages(out / "report.pdf", tmp_path) for w in p.words)
    for text in (page.text, words):
        assert "seed" not in text.lower()
        assert "drift from the means of the calibration series [1]" in text
        assert "[1]" in text and PAPER in text
        assert "An improved method of determining the azimuth drift of gyroscopic" in text
    selected = next(
        r for r in pq.read_table(out / "drift.result.parquet").to_pylist() if r["selected"]
    )
    assert (
        f"{selected['gain']:.1f}× smaller σ than the traditional estimate (the method's paper "
        f"[1] predicts √(n(n−1)/2) = {selected['gain_claimed']:.1f}× for n = 13 readings per "
        "series)"
    ) in page.text


def test_calibration_series_labels_clear_the_error_bars(browser: Any, tmp_path: Path):
    """The S1…S4 labels of the series means sit beside their error bars: no label box
    touches a bar or a cap, or another label (laid out by Chromium from the report's
    SVG figure); the figure is larger than it was (6.9 × 3.6 in)."""
    out = calibrate("examples/calibration-ig50.csv", tmp_path / "out")
    svg = figure_svg(out / "report.html", "series")
    labels, bars, caps = svg_boxes(
        browser,
        svg,
        [
            '[id^="series-label-"]',
            '[id^="series-bar-"] path',
            '[id^="series-cap-"] path',
        ],
    )
    assert len(labels) == 4 and len(caps) == 4 and len(bars) == 4  # a path: both caps
    for k, label in enumerate(labels):
        assert label["x1"] - label["x0"] > 5 and label["y1"] - label["y0"] > 5
        for other in labels[k + 1 :]:
            assert not overlap(label, other)
        for bar in bars + caps:  # a line's box widened by its stroke
            wide = {
                "x0": bar["x0"] - 1,
                "y0": bar["y0"] - 1,
                "x1": bar["x1"] + 1,
                "y1": bar["y1"] + 1,
            }
            assert not overlap(label, wide), (k, label, bar)
        # beside its own bar: to the right of it, at the height of the mean
        bar = bars[k]
        assert label["x0"] > bar["x1"] and label["y0"] < (bar["y0"] + bar["y1"]) / 2 < label["y1"]
    height = re.search(r'<svg[^>]* height="([\d.]+)pt"', svg)
    assert height and float(height[1]) >= 4.5 * 72

"""The drift calibration report through `gyropipe run pipelines/calibration.yaml`: on the
bundled sample (linear drift) and on a simulated instrument whose drift is not linear."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pyarrow.parquet as pq
import pytest
from report_support import (
    assert_self_contained,
    figure_regions,
    ink,
    inspect,
    pdf_pages,
    run_ok,
)

from pipeline.sim.calibration import CalibrationPlan, simulate_calibration
from pipeline.sim.spec import Drift


def number(cell: str) -> float:
    return float(cell.replace("−", "-"))


def calibrate(readings: str, out: Path) -> Path:
    run_ok("run", "pipelines/calibration.yaml", "--input", readings, "--out", str(out))
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
    assert [number(r[3]) for r in estimates] == pytest.approx(
        [r["sigma_deg_h"] for r in result], abs=5e-4
    )
    used = [r[0] for r in estimates if r[-1] == "selected"]
    assert used == ["fit"]
    traditional = next(r for r in result if r["method"] == "traditional")
    assert f"{traditional['drift_deg_h']:.3f} ± {traditional['sigma_deg_h']:.3f} °/h" in page.text

    pages = pdf_pages(out / "report.pdf", tmp_path)
    regions = figure_regions(pages)
    assert list(regions) == [1] and ink(regions[1]) > 0.02
    words = " ".join(w[0] for p in pages for w in p.words)
    assert "Linear drift" in words and "traditional" in words


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

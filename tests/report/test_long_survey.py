"""A very long survey (issue 32 item 16): its charts are thinned for drawing — evenly
spaced stations, every survey's ends, the highest dogleg of each stretch — and its listing
keeps every station. 30,000 stations took 92 s of CPU and 2.4 GB; now 17.5 s and 265 MB."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from report_support import figure_svg

from pipeline.reports import plots
from pipeline.reports.plots import MAX_DRAWN, drawn_rows
from tests_support import gyropipe_cli


def test_drawn_rows_keep_the_ends_of_every_survey_and_each_stretch_s_highest_dogleg():
    n = 10 * MAX_DRAWN
    md = np.arange(n, dtype=float)
    dls = np.zeros(n)
    dls[[12_352, 12_353]] = [4.0, 9.0]  # a dogleg between the drawn 12,345 and 12,355
    rows = drawn_rows(md, (0, 7_001, n), dls)
    assert MAX_DRAWN < len(rows) <= 2 * MAX_DRAWN + 4
    assert {0, 7_000, 7_001, n - 1, 12_345, 12_353, 12_355} <= set(rows.tolist())
    assert 12_352 not in rows and (np.diff(rows) > 0).all()
    assert drawn_rows(md[:MAX_DRAWN], (0, MAX_DRAWN), dls[:MAX_DRAWN]).tolist() == list(
        range(MAX_DRAWN)
    )


def test_a_long_survey_s_charts_are_thinned_and_its_listing_is_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.setattr(plots, "MAX_DRAWN", 50)  # a long survey, made short for the test
    n = 300
    md = np.arange(n) * 2.0
    stations = tmp_path / "long.csv"
    lines = [f"{m:.1f},{min(m / 50.0, 60.0):.3f},{45 + m / 1000.0:.3f}" for m in md]
    stations.write_text("md [m],inc [deg],azi true [deg]\n" + "\n".join(lines) + "\n")
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", "pipelines/survey.yaml", "--input", str(stations), "--out", str(out)
    )
    assert result.returncode == 0, result.stderr
    html = out / "report.html"
    text = html.read_text(encoding="utf-8")
    drawn = re.search(rf"Drawn at ([\d,]+) of the {n:,} stations", text)
    assert drawn, "the captions say the charts are thinned"
    shown = int(drawn[1].replace(",", ""))
    assert 50 <= shown < n
    plan = figure_svg(html, "plan")
    assert plan.count("<circle") <= shown + 5  # one dot per drawn station (and the legend)
    assert f"{md[-1]:.2f}" in text and text.count("<tr") > n  # the listing: every station

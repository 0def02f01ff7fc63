"""summary.json's maximum DLS is counted by the run's survey report's rule: a survey report
given ``min_course_length: 20`` leaves a 12 m course out of both the report's "Maximum DLS"
and summary.json's ``max_dls`` (before, the summary counted courses ≥ 10 m whatever the
report said, so the two deliverables stated different maxima).

The stations hold one azimuth, so each course's dogleg is its change of inclination and its
DLS that change × 30 m / course length: the 12 m course at 72 m 2° (5.00 °/30 m), the 30 m
course at 130 m 2.5° (2.50 °/30 m), every other ≤ 2 °/30 m."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from agreement_support import report_fields

from tests_support import ROOT, gyropipe_cli

STATIONS = """Well: COURSES-1
Latitude: 61.25
Longitude: 73.4
Survey Date: 2026-11-21

MD (m),Inc (deg),Azimuth True (deg)
0.00,0.00,40.00
30.00,2.00,40.00
60.00,4.00,40.00
72.00,6.00,40.00
100.00,7.00,40.00
130.00,9.50,40.00
160.00,10.50,40.00
"""
SHORT = (5.0, 72.0)
"""°/30 m and MD (m) of the largest DLS, the 12 m course's"""
LONG = (2.5, 130.0)
"""°/30 m and MD (m) of the largest DLS over courses ≥ 20 m"""


def _run(tmp_path: Path, min_course: float | None) -> tuple[dict[str, object], str]:
    """survey.yaml on the stations, its report given ``min_course`` (None: as shipped);
    summary.json's max_dls and the report's "Maximum DLS"."""
    text = (ROOT / "pipelines" / "survey.yaml").read_text(encoding="utf-8")
    if min_course is not None:
        old = "      checks: dls_check.results\n"
        assert text.endswith(old), "the report stage is the last and ends with its inputs"
        text += f"    with: {{min_course_length: {min_course}}}\n"
    (tmp_path / "survey.yaml").write_text(text, encoding="utf-8")
    (tmp_path / "stations.csv").write_text(STATIONS, encoding="utf-8")
    out = tmp_path / "out"
    gyropipe_cli(
        "run", tmp_path / "survey.yaml", "--input", tmp_path / "stations.csv", "--out", out,
        check=True,
    )  # fmt: skip
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    (survey,) = summary["surveys"]
    return survey["max_dls"], report_fields(out / "report.html")["Maximum DLS"]


@pytest.mark.parametrize(
    ("min_course", "expected", "left_out"), [(None, SHORT, 0), (20.0, LONG, 1)]
)
def test_summary_and_report_state_one_maximum_dls(
    tmp_path: Path, min_course: float | None, expected: tuple[float, float], left_out: int
) -> None:
    max_dls, said = _run(tmp_path, min_course)
    dls, md = expected
    assert max_dls["dls"] == pytest.approx(dls, abs=1e-3)
    assert max_dls["md"] == pytest.approx(md, abs=1e-6)
    assert max_dls["min_course_length"] == (10.0 if min_course is None else min_course)
    assert max_dls["courses_not_counted"] == left_out
    assert said.startswith(f"{dls:.2f} °/30 m at {md:.2f} m MD"), said

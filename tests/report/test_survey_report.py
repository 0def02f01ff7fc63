"""The survey report of the bundled sample, end to end through `gyropipe run`: the HTML in
headless Chromium (listing, decoded plots, no console errors, nothing fetched), the PDF
rasterised (pages, figures drawn), and the copy in examples/report/ current."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from report_support import (
    assert_self_contained,
    colour,
    figure_regions,
    ink,
    inspect,
    marks,
    pdf_pages,
)

from pipeline.errors import GyropipeError, StageError
from pipeline.graph import build_plan
from pipeline.registry import Registry, StageDef
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from pipeline.tables import Trajectory
from tests_support import ROOT, gyropipe_cli, tables_of

SAMPLE = "examples/stations-j-well.csv"
EXAMPLES = ROOT / "examples" / "report"
EXAMPLE_RUNS = {
    "survey-j-12": ("pipelines/survey.yaml", "examples/stations-j-well.csv"),
    "point-gyro-readings-j-well": (
        "pipelines/point-gyro-readings.yaml",
        "examples/readings-j-well.csv",
    ),
    "calibration-ig50": ("pipelines/calibration.yaml", "examples/calibration-ig50.csv"),
}


def sample_rows() -> list[list[float]]:
    """MD, INC, AZI rows of the bundled sample, parsed here independently of the reader."""
    lines = (ROOT / SAMPLE).read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("MD (m)")) + 1
    return [[float(v) for v in line.split(",")] for line in lines[start:] if line.strip()]


@pytest.fixture(scope="module")
def example_run(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Path]:
    """Output directory of a ready pipeline run on a bundled sample (each run once)."""
    done: dict[str, Path] = {}

    def get(name: str) -> Path:
        if name not in done:
            pipeline, sample = EXAMPLE_RUNS[name]
            done[name] = tmp_path_factory.mktemp(name)
            gyropipe_cli("run", pipeline, "--input", sample, "--out", str(done[name]), check=True)
        return done[name]

    return get


@pytest.fixture(scope="module")
def survey_run(example_run: Callable[[str], Path]) -> Path:
    return example_run("survey-j-12")


def test_html_report_in_chromium(survey_run: Path, browser: Any):
    html = survey_run / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    assert page.figures == ["fig-plan", "fig-section", "fig-view3d", "fig-profiles", "fig-qc-0"]
    assert [s["figure"] for s in page.svgs] == page.figures

    rows = sample_rows()
    listing = page.tables["listing"]
    assert len(listing) == len(rows)
    assert page.headers["listing"][:3] == ["MD", "INC", "AZI"]
    assert page.units["listing"][:3] == ["m", "°", "° true"]
    assert page.headers["listing"][-1] == "QC"
    for shown, (md, inc, azi) in zip(listing, rows, strict=True):
        assert [float(c.replace("−", "-")) for c in shown[:3]] == pytest.approx(
            [md, inc, azi], abs=0.005
        )
    trajectory = pq.read_table(survey_run / "trajectory.trajectory.parquet")
    tvd = trajectory.column("tvd").to_numpy()
    assert [float(r[3]) for r in listing] == pytest.approx(tvd, abs=0.005)
    assert all(r[-1] == "ok" for r in listing)  # dls_limit passes on the sample
    assert "QC: all 85 stations passed." in page.text
    for words in ("J-12", "Samotlor", "61.250000° N", "minimum curvature", "true north"):
        assert words in page.text
    manifest = json.loads((survey_run / "run.json").read_text())
    assert manifest["pipeline"]["sha256"] in page.text
    assert manifest["inputs"]["stations"]["sha256"] in page.text


def test_pdf_report_pages_and_plots(survey_run: Path, tmp_path: Path):
    pages = pdf_pages(survey_run / "report.pdf", tmp_path)
    assert 4 <= len(pages) <= 12
    assert all(p.pixels.shape[:2] == (585, 414) for p in pages)  # A4 at 50 dpi
    for page in pages:
        assert ink(page.pixels) > 0.005
    text = " ".join(w[0] for p in pages for w in p.words)
    for words in (
        "Gyro survey report",
        "Survey listing",
        "Appendix: provenance",
        "2520.00",
        "2058.87",
    ):
        assert all(w in text for w in words.split())
    regions = figure_regions(pages)
    assert sorted(regions) == [1, 2, 3, 4, 5]
    for number, region in regions.items():
        assert ink(region) > 0.02, number
        assert colour(region) > 0.001, number
    last = [
        int(m) for p in pages for m in re.findall(r"Page (\d+) of", " ".join(w[0] for w in p.words))
    ]
    assert last == list(range(1, len(pages) + 1))


def test_failed_check_highlights_the_row_and_is_explained(tmp_path: Path, browser: Any):
    """A station that fails a QC check (DLS above a 2 °/30 m limit) has its whole listing row
    highlighted, is named in the summary and its check is explained in the QC section; the
    stations that pass are not highlighted at all (#18 item 7)."""
    out = tmp_path / "out"
    gyropipe_cli(
        "run",
        "pipelines/survey.yaml",
        "--input",
        SAMPLE,
        "--out",
        str(out),
        "--set",
        "dls_check.params={limit: 2.0}",
        "--set",
        "report.formats=[html]",
        check=True,
    )
    checks = pq.read_table(out / "dls_check.results.parquet").to_pylist()
    failed = [not r["passed"] for r in checks]
    assert 0 < sum(failed) < len(failed)
    page = inspect(browser, out / "report.html")
    rows = marks(browser, out / "report.html")["listing"]
    assert [r.row for r in rows] == failed
    assert not any(any(r.cells) for r in rows)
    assert [r[-1] for r in page.tables["listing"]] == [
        "dls_limit failed" if f else "ok" for f in failed
    ]
    assert page.tables["flags"] == [
        [
            "dls_limit failed",
            "failed check",
            str(sum(failed)),
            "The dogleg severity exceeds the limit set for the survey.",
        ]
    ]
    assert f"QC: {sum(failed)} of {len(failed)} stations failed a check (MD " in page.text


@pytest.mark.parametrize("name", sorted(EXAMPLE_RUNS))
def test_bundled_example_reports_are_current(name: str, example_run: Callable[[str], Path]):
    """examples/report/ holds what the ready pipelines make of the bundled samples: the
    tables (listing, QC, estimates, provenance) regenerate identically."""
    committed = EXAMPLES / f"{name}.html"
    assert committed.is_file() and (EXAMPLES / f"{name}.pdf").is_file()
    assert tables_of(example_run(name) / "report.html") == tables_of(committed), (
        f"{committed} is stale: regenerate it as examples/report/README.md says"
    )


def test_examples_are_small():
    sizes = [p.stat().st_size for p in EXAMPLES.glob("*.*")]
    assert len(sizes) >= 6 and sum(sizes) < 1.5e6


def empty_trajectory(inputs: Any, params: Any, ctx: Any) -> dict[str, pa.Table]:
    columns = {c.name: [] for c in Trajectory.compiled().columns if c.required}
    return {"trajectory": Trajectory.compiled().make_table(columns, north_reference="true")}


def test_empty_trajectory_fails_the_run_naming_the_stage(
    tmp_path: Path, registry: Registry, add_stage: Callable[[StageDef], None], write_yaml: Any
):
    add_stage(
        StageDef("tests.empty", empty_trajectory, "empty", outputs={"trajectory": Trajectory})
    )
    path = write_yaml(
        """
        name: empty
        version: "1"
        stages:
          - {id: make, uses: tests.empty}
          - {id: report, uses: report, inputs: {trajectory: make.trajectory}}
        """
    )
    with pytest.raises(StageError, match=r"stage 'report'.*no stations") as caught:
        run_plan(build_plan(load_spec(path), registry), registry, inputs={}, out_dir=tmp_path / "o")
    assert isinstance(caught.value.__cause__, GyropipeError)
    assert not (tmp_path / "o").exists()  # a failed run publishes nothing


def test_bad_report_filename_is_rejected_before_running(tmp_path: Path):
    result = gyropipe_cli("validate", "pipelines/survey.yaml", "--set", "report.filename=../escape")
    assert result.returncode == 2
    assert "--set report.filename=../escape: stage 'report'" in result.stderr

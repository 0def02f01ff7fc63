"""Reports of several runs, through the command line: the acceptance gates of an in-run
against an out-run (pipelines/inout-gyro.yaml, an out-run with an azimuth error) and the
definitive survey of a gyro and an MWD run (pipelines/definitive.yaml), rendered in
Chromium; the gates also in run.json and on the command line."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from report_support import assert_self_contained, inspect, pdf_pages

import pipeline as gp
from inout_support import simulated_runs
from tests_support import ROOT, gyropipe_cli


@pytest.fixture(scope="module")
def inout(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    work = tmp_path_factory.mktemp("inout")
    runs = simulated_runs()
    for name in ("in", "bad"):
        gp.write(runs[name], work / f"{name}.csv")
    done = gyropipe_cli(
        "run",
        "pipelines/inout-gyro.yaml",
        "--input",
        f"inrun={work / 'in.csv'}",
        "--input",
        f"outrun={work / 'bad.csv'}",
        "--out",
        str(work / "out"),
    )
    assert done.returncode == 3, done.stderr  # the run worked; the survey failed acceptance
    return work / "out", done.stdout


def test_command_line_prints_and_records_the_gates(inout: tuple[Path, str]) -> None:
    out, stdout = inout
    lines = stdout.splitlines()
    assert "acceptance: FAIL" in lines
    assert any(line.split()[:2] == ["gates.azimuth", "fail"] for line in lines), stdout
    assert any(line.split()[:2] == ["gates.inclination", "pass"] for line in lines), stdout
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["acceptance"]["status"] == "fail"
    recorded = {g["gate"]: g for g in manifest["acceptance"]["gates"]}
    gates = pd.read_parquet(out / "gates.gates.parquet").set_index("gate")
    for gate, row in gates.iterrows():
        assert recorded[gate]["status"] == row["status"]
        assert recorded[gate]["value"] == pytest.approx(row["value"])
        assert recorded[gate]["limit"] == row["limit"] and recorded[gate]["unit"] == row["unit"]


def test_gates_report_in_chromium(inout: tuple[Path, str], browser: Any, tmp_path: Path) -> None:
    out, _ = inout
    html = out / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    gates = pd.read_parquet(out / "gates.gates.parquet").set_index("gate")

    table = page.tables["gates"]
    assert page.headers["gates"] == ["Gate", "Criterion", "Worst value", "Limit", "Unit", "Result"]
    assert [row[-1] for row in table] == [s.upper() for s in gates["status"]]
    azimuth = next(row for row in table if row[0] == "Azimuth, in-run − out-run")
    assert azimuth[-1] == "FAIL" and float(azimuth[2]) == pytest.approx(
        gates.loc["azimuth", "value"], rel=5e-3
    )
    assert float(azimuth[3]) == 1.0 and azimuth[4] == "deg"
    # the verdict, in the summary and atop the QC section, names the failed gate
    assert page.text.count("Acceptance: FAILED — Azimuth, in-run − out-run.") == 2
    # the out-run's stations compared station by station, charted with their tolerance
    assert any(f.startswith("fig-qc") for f in page.figures)
    qc = {row[0]: row for row in page.tables["qc"]}
    comparison = pd.read_parquet(out / "gates.comparison.parquet")
    assert qc["In-run − out-run azimuth"][4] == str(int((~comparison["passed"]).sum()))
    assert qc["In-run − out-run azimuth"][5] == str(
        int(comparison["azi_diff"].isna().sum())
    )  # vertical
    # the definitive survey's program: the in-run throughout
    program = page.tables["program"]
    assert [row[1] for row in program] == ["in-run"]
    assert program[0][-1] == "in.csv"
    assert "correlated within the run" in page.text  # the method line of the definitive survey
    # a failed in/out station is the in-run's (the program above), not "the mean of the two"
    assert "not corrected for the difference" in page.text
    assert "mean of the two" not in page.text

    pages = pdf_pages(out / "report.pdf", tmp_path)
    text = " ".join(w[0] for p in pages for w in p.words)
    assert "Acceptance gates" in text and "FAIL" in text


def test_definitive_survey_report_in_chromium(browser: Any, tmp_path: Path) -> None:
    examples = ROOT / "examples" / "definitive"
    done = gyropipe_cli(
        "run",
        "pipelines/definitive.yaml",
        "--input",
        f"gyro={examples / 'gyro-run.csv'}",
        "--input",
        f"mwd={examples / 'mwd-run.csv'}",
        "--out",
        str(tmp_path / "out"),
        "--set",
        "report.formats=[html]",
    )
    assert done.returncode == 0, done.stderr
    assert "acceptance" not in done.stdout  # no gates in this pipeline
    out = tmp_path / "out"
    assert "acceptance" not in json.loads((out / "run.json").read_text())
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    survey = pd.read_parquet(out / "definitive.survey.parquet")
    program = page.tables["program"]
    assert [row[1] for row in program] == ["GYRO-1", "MWD-1"]
    assert [row[2] for row in program] == ["GYRO-NS", "ISCWSA-MWD-REV5"]
    assert [row[-1] for row in program] == ["gyro-run.csv", "mwd-run.csv"]
    counts = survey.groupby("run", sort=False).size()
    assert [int(row[4]) for row in program] == counts.tolist()
    assert len(page.tables["listing"]) == len(survey)
    assert [row[0] for row in page.tables["listing"]] == survey["run"].tolist()  # Run column
    html = (out / "report.html").read_text()
    # each run's tool, not the last file header's (issue 28 item 8)
    assert (
        "<dt>Tool type</dt><dd>GYRO-1: north-seeking gyro (example); MWD-1: MWD (example)</dd>"
    ) in html
    assert '<th class="l">Run<span class="unit">&nbsp;</span></th><th class="r">MD<' in html
    subtitle = re.search(r'<p class="subtitle">([^<]*)</p>', html)
    assert subtitle is None or "MWD" not in subtitle[1]  # not the last file header's tool
    # the GYRO-1 run's model cites the gyro error model's paper beside the MWD one's
    assert "propagated as in [1] (the gyro terms as in [2])" in page.text
    assert "Prediction of wellbore position accuracy when surveyed with gyroscopic" in page.text
    csv = pd.read_csv(out / "definitive.csv", comment="#")
    assert len(csv) == len(survey)

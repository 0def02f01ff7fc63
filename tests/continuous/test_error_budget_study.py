"""The error-budget study (benchmarks/study_error_budget.py) runs end to end on a short plan,
and its paper error set gives the errors the analytic drift of a constant bias predicts."""

from __future__ import annotations

import dataclasses
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import yaml

from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.sim.spec import load_simulation
from tests_support import ROOT

STUDY = ROOT / "benchmarks" / "study_error_budget.py"
PLAN = ROOT / "examples" / "plans" / "west-siberia-700m.yaml"
PAPER_PLAN = ROOT / "examples" / "plans" / "bystrinskoye-690m.yaml"
FIGURES = ("azimuth", "horizontal", "td-scatter", "breakdown")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def short_plan(tmp_path: Path) -> Path:
    """The study's plan, logged from its start stop (135 m) to 215 m with short stops."""
    plan = yaml.safe_load(PLAN.read_text(encoding="utf-8"))
    plan["survey"]["end_md"] = 215.0
    plan["survey"]["stop"] = {"dwell": 8.0, "move_time": 1.0}
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(plan), encoding="utf-8")
    return path


def table_row(doc: str, title: str, label: str) -> list[str]:
    """Cells of the row starting with ``label`` in the table after the bold ``title``."""
    section = doc[doc.index(f"**{title}**") :]
    for line in section.splitlines():
        if line.startswith(f"| {label}"):
            return [cell.strip() for cell in line.strip("|").split("|")]
    raise AssertionError(f"no row {label!r} under {title!r}")


def test_study_runs_the_public_pipeline_and_writes_figures_and_numbers(tmp_path: Path) -> None:
    out = tmp_path / "docs"
    doc = out / "error-budget.md"
    out.mkdir()
    doc.write_text(
        "# Kept\n\nprose\n\n<!-- BEGIN numbers: written by benchmarks/study_error_budget.py -->\nold\n<!-- END numbers -->\n\ntail\n",
        encoding="utf-8",
    )
    plan = short_plan(tmp_path)
    args = ["--runs", "1", "--breakdown-runs", "1", "--sets", "realistic", "--plan", str(plan)]
    args += ["--out", str(out)]
    assert study_module().main([*args, "--work", str(tmp_path / "work")]) == 0
    for name in FIGURES:
        data = (out / "figures" / f"error-budget-{name}.png").read_bytes()
        assert data.startswith(PNG_SIGNATURE) and 5_000 < len(data) < 300_000
    text = doc.read_text(encoding="utf-8")
    assert text.startswith("# Kept\n\nprose\n") and text.endswith("\n\ntail\n")
    assert "\nold\n" not in text and "Runs: 1 (seed 1)" in text
    # 80 m of logging: the TD stop's azimuth error is within a few of its predicted σ (≈ 3° for
    # this MEMS tool at 8 s per position); the position error from the tie-in is decimetres
    azi = table_row(text, "Azimuth error", "TD")
    assert 0.0 < float(azi[4]) < 10.0 and abs(float(azi[1])) < 4.0 * float(azi[4])
    horizontal = table_row(text, "Horizontal position error", "TD")
    assert 0.0 < float(horizontal[1]) < 4.0 * float(horizontal[4]) < 4.0
    assert table_row(text, "Azimuth error", "200")[0] == "200"
    assert "| 300 " not in text  # depths past the short plan's TD are not reported
    breakdown = table_row(text, "Breakdown", "gyro bias")
    assert float(breakdown[2]) < 0.1  # a constant gyro bias is removed by the 5-position stops


def study_module() -> ModuleType:
    spec = importlib.util.spec_from_file_location("study_error_budget", STUDY)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses of the module resolve their annotations here
    spec.loader.exec_module(module)
    return module


def short_paper_plan(tmp_path: Path) -> Path:
    """The paper's case logged from 135 m (I = 5°) to 215 m (I ≈ 18.5°) with short stops and
    no accelerometer noise (the constant errors alone)."""
    plan = yaml.safe_load(PAPER_PLAN.read_text(encoding="utf-8"))
    plan["survey"]["end_md"] = 215.0
    plan["survey"]["stop"] = {"dwell": 8.0, "move_time": 1.0}
    plan["tool"]["overrides"] = {"accelerometer": {"noise_density": 0.0}}
    path = tmp_path / "paper-short.yaml"
    path.write_text(yaml.safe_dump(plan), encoding="utf-8")
    return path


def test_paper_error_set_drifts_as_a_constant_gyro_and_accelerometer_bias_predict(
    tmp_path: Path,
) -> None:
    """No closure: between two depths of the steady run (150 and 200 m, I ≈ 7° and 15°) the
    azimuth error grows by the drift of the constant errors, each checked alone:
    ΔA = −b_gx ∫dt/sin I (gyro along frame x, held at the high side; 1 m/s) and
    ΔA = (b_ay/g)(cot I₁ − cot I₂) (right-side accelerometer: toolface error b/(g sin I) times
    İ, Binder & Khazov 2023 Eq. 20); the inclination along the run is off by
    −(b_ax cos I + b_az sin I)/g (frame x at the high side)."""
    study = study_module()
    plan = short_paper_plan(tmp_path)
    spec = load_simulation(plan)
    survey = spec.survey
    grid = np.append(np.arange(survey.start_md, survey.end_md, 5.0), survey.end_md)
    i1, i2 = (int(np.argmin(np.abs(grid - md))) for md in (150.0, 200.0))
    md = np.linspace(grid[i1], grid[i2], 2001)
    inc = spec.path().evaluate(md).inc
    f = 1.0 / np.sin(inc)
    hours = np.sum(np.diff(md) * (f[1:] + f[:-1]) / 2) / survey.speed / 3600.0
    cot = 1.0 / np.tan(inc[0]) - 1.0 / np.tan(inc[-1])
    paper = dataclasses.replace(study.ERROR_SETS["paper"], plan=plan)
    runs = 2
    for gyro in (True, False):
        errors = dataclasses.replace(
            paper,
            gyro_bias_3sigma=3.0 if gyro else 0.0,  # deg/h: 30 × the paper's, to measure it
            acc_bias_3sigma=0.0 if gyro else paper.acc_bias_3sigma,
        )
        ens = study.simulate_ensemble(
            "all terms", "all terms", runs, 1, errors, study.PIPELINE, grid, tmp_path
        )
        a = ens.arrays()
        for k in range(runs):
            draw = study.Draw.of(1, k, errors)
            expected = (
                -draw.gyro_bias[0] * hours
                if gyro
                else np.degrees(draw.acc_bias[1] / STANDARD_GRAVITY * cot)
            )
            assert abs(expected) > 0.01  # deg: a measurable drift
            drift = a["azi"][k, i2] - a["azi"][k, i1]
            np.testing.assert_allclose(drift, expected, rtol=0.1, atol=0.002)
            if not gyro:
                i_mid = spec.path().evaluate(np.array([grid[i2]])).inc[0]
                bx, _, bz = draw.acc_bias
                tilt = -(bx * np.cos(i_mid) + bz * np.sin(i_mid)) / STANDARD_GRAVITY
                np.testing.assert_allclose(a["inc"][k, i2], np.degrees(tilt), atol=0.002)

"""Runs of different wells are never combined: the definitive survey and the in-run/out-run
acceptance gates refuse tables whose headers name different wells (well name, UWI/API),
naming both wells and their ports; tables that name no well, or one well written two ways,
pass."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from test_run_headers import RUNS, with_header

import pipeline as gp
from inout_support import simulated_runs
from tests_support import ROOT, gyropipe_cli


def _with_well(frame: pd.DataFrame, **well: str | None) -> pd.DataFrame:
    """``frame`` (the simulator's header: well ``inout``) with the header fields ``well``
    (None: left out)."""
    frame = frame.copy()
    header = {**frame.attrs["well"], **well}
    frame.attrs["well"] = {k: v for k, v in header.items() if v is not None}
    return frame


def test_the_definitive_survey_refuses_runs_of_two_wells(tmp_path: Path) -> None:
    (tmp_path / "mwd").mkdir()
    mwd = with_header(RUNS / "mwd-run.csv", tmp_path / "mwd", Well="J-13")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "definitive.yaml", "--input", f"gyro={RUNS / 'gyro-run.csv'}",
        "--input", f"mwd={mwd}", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode == 1, result.output
    assert "Traceback" not in result.output
    assert "different wells" in result.stderr
    assert "run1 (GYRO-1): well 'J-12'" in result.stderr
    assert "run2 (MWD-1): well 'J-13'" in result.stderr
    assert not (tmp_path / "out").exists()


def test_one_well_written_two_ways_is_one_well(tmp_path: Path) -> None:
    """``J-12`` and ``j 12`` are one name; an API number's first ten digits name the well
    (the sidetrack and event codes after them its wellbore)."""
    (tmp_path / "gyro").mkdir()
    (tmp_path / "mwd").mkdir()
    gyro = with_header(RUNS / "gyro-run.csv", tmp_path / "gyro", UWI="42-501-20130-00")
    mwd = with_header(RUNS / "mwd-run.csv", tmp_path / "mwd", Well="j 12", UWI="4250120130-01-00")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "definitive.yaml", "--input", f"gyro={gyro}",
        "--input", f"mwd={mwd}", "--out", tmp_path / "out", "--set", "report.formats=[html]",
    )  # fmt: skip
    assert result.returncode == 0, result.output


def test_the_gates_refuse_an_out_run_of_another_well() -> None:
    runs = simulated_runs()
    inrun = _with_well(runs["in"], well="J-12", uwi="42-501-20130")
    outrun = _with_well(runs["out"], well="J-12", uwi="42-501-20131")
    with pytest.raises(gp.GyropipeError) as caught:
        gp.acceptance_gates(inrun, outrun)
    text = str(caught.value)
    assert "different wells" in text
    assert "inrun: well 'J-12', UWI '42-501-20130'" in text
    assert "outrun: well 'J-12', UWI '42-501-20131'" in text


def test_the_inout_pipeline_refuses_an_out_run_of_another_well() -> None:
    runs = simulated_runs()
    inrun = _with_well(runs["in"], well="J-12")
    outrun = _with_well(runs["out"], well="K-7")
    with pytest.raises(gp.GyropipeError, match=r"different wells.*inrun: well 'J-12'.*K-7"):
        gp.run(ROOT / "pipelines" / "inout-gyro.yaml", {"inrun": inrun, "outrun": outrun})


def test_runs_naming_no_well_or_one_pass() -> None:
    """Both runs of well ``inout``, or one naming none (its well unknown, not another)."""
    runs = simulated_runs()
    unnamed = _with_well(runs["out"], well=None)
    for outrun in (runs["out"], unnamed):
        gates = gp.acceptance_gates(runs["in"], outrun).gates
        assert set(gates["status"]) == {"pass"}

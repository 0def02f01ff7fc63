"""Acceptance gates of a gyro survey, in-run against out-run, on simulated runs
(:func:`inout_support.simulated_runs`: an agreeing pair, and an out-run with a g-sensitive
gyro whose azimuths err beyond the 1° gate)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

import pipeline as gp
from inout_support import simulated_runs
from pipeline.qc.gates import pair_stations
from tests_support import ROOT, gyropipe_cli


@pytest.fixture(scope="module")
def runs() -> dict[str, pd.DataFrame]:
    return simulated_runs()


def _status(gates: Any) -> dict[str, str]:
    return dict(zip(gates["gate"], gates["status"], strict=True))


def test_agreeing_runs_pass_every_gate(runs: dict[str, pd.DataFrame]) -> None:
    result = gp.acceptance_gates(runs["in"], runs["out"])
    assert _status(result.gates) == dict.fromkeys(
        ("stations", "inclination", "azimuth", "azimuth_low", "depth", "coverage"), "pass"
    )
    comparison = result.comparison
    assert len(comparison) == len(runs["in"]) == 16  # every station paired
    assert comparison["passed"].all()
    assert comparison.attrs["units"]["azi_diff"] == "deg"


def test_an_out_run_with_an_azimuth_error_fails_the_azimuth_gate(
    runs: dict[str, pd.DataFrame],
) -> None:
    result = gp.acceptance_gates(runs["in"], runs["bad"])
    status = _status(result.gates)
    assert status["azimuth"] == "fail"
    assert {k: v for k, v in status.items() if k != "azimuth"} == dict.fromkeys(
        ("stations", "inclination", "azimuth_low", "depth", "coverage"), "pass"
    )
    comparison = result.comparison
    failed = comparison[~comparison["passed"]]
    assert len(failed) and (failed[["inc_in", "inc_out"]].mean(axis=1) >= 10.0).all()
    assert (failed["azi_diff"].abs() > 1.0).all()
    # the error follows the g-sensitive bias: it grows with the inclination (sin I)
    inclined = comparison[comparison["inc_in"] > 5.0]
    rho = np.corrcoef(np.sin(np.radians(inclined["inc_in"])), inclined["azi_diff"].abs())[0, 1]
    assert rho > 0.5, rho
    row = result.gates.set_index("gate").loc["azimuth"]
    assert row["value"] == pytest.approx(failed["azi_diff"].abs().max())
    assert row["limit"] == 1.0 and row["unit"] == "deg"


def test_client_criteria_are_parameters(runs: dict[str, pd.DataFrame]) -> None:
    lenient = gp.acceptance_gates(runs["in"], runs["bad"], azi_tolerance=3.0)
    assert _status(lenient.gates)["azimuth"] == "pass"
    few = gp.acceptance_gates(runs["in"].iloc[:8], runs["out"].iloc[:8])
    assert _status(few.gates)["stations"] == "fail"
    assert few.gates.set_index("gate").loc["stations", "value"] == 8
    deeper = runs["out"].assign(md=runs["out"]["md"] + 0.8)  # out-run depths 0.8 m deeper
    assert _status(gp.acceptance_gates(runs["in"], deeper).gates)["depth"] == "fail"
    tolerant = gp.acceptance_gates(runs["in"], deeper, depth_tolerance=1.0)
    assert _status(tolerant.gates)["depth"] == "pass"
    with pytest.raises(gp.GyropipeError, match="inc_tolerance"):
        gp.acceptance_gates(runs["in"], runs["out"], inc_tolerance=-1.0)


def test_pairing_takes_the_nearest_station_once_within_the_window() -> None:
    pairs = pair_stations(
        np.array([0.0, 30.0, 60.0, 90.0]), np.array([29.0, 31.5, 61.0, 200.0]), 5.0
    )
    assert pairs.tolist() == [[1, 0], [2, 2]]  # 31.5 loses 30 to 29; 200 is too far
    assert pair_stations(np.array([1.0]), np.array([]), 5.0).shape == (0, 2)


def test_pairing_equals_the_greedy_over_every_pair() -> None:
    """The windowed search pairs as a greedy over the whole distance matrix does."""

    def every_pair(a: np.ndarray, b: np.ndarray, window: float) -> list[list[int]]:
        dist = np.abs(a[:, None] - b[None, :])
        i, o = np.nonzero(dist <= window)
        used_a: set[int] = set()
        used_b: set[int] = set()
        pairs = []
        for k in np.argsort(dist[i, o], kind="stable"):
            if i[k] not in used_a and o[k] not in used_b:
                used_a.add(int(i[k]))
                used_b.add(int(o[k]))
                pairs.append([int(i[k]), int(o[k])])
        return sorted(pairs)

    rng = np.random.default_rng(5)
    for _ in range(100):
        a = np.sort(rng.uniform(0, 100, rng.integers(0, 25)))
        b = np.sort(rng.uniform(0, 100, rng.integers(0, 25)))
        assert pair_stations(a, b, 5.0).tolist() == every_pair(a, b, 5.0)


def test_pipeline_gates_and_definitive_survey(runs: dict[str, pd.DataFrame]) -> None:
    """pipelines/inout-gyro.yaml from Python (the command line and run.json on disk:
    tests/report/test_definitive_reports.py): the gates, their record for run.json, and the
    definitive survey keeping the in-run with the out-run's stations beside it."""
    pipeline = ROOT / "pipelines" / "inout-gyro.yaml"
    result = gp.run(pipeline, {"inrun": runs["in"], "outrun": runs["bad"]})
    acceptance = result.manifest["acceptance"]
    assert acceptance["status"] == "fail"
    by_gate = {g["gate"]: g for g in acceptance["gates"]}
    assert set(by_gate) == {
        "stations",
        "inclination",
        "azimuth",
        "azimuth_low",
        "depth",
        "coverage",
    }
    assert by_gate["azimuth"]["status"] == "fail" and by_gate["azimuth"]["limit"] == 1.0
    assert by_gate["inclination"]["status"] == "pass" and by_gate["azimuth"]["stage"] == "gates"
    gates = result.frame("gates.gates").set_index("gate")
    assert gates.loc["azimuth", "value"] == pytest.approx(by_gate["azimuth"]["value"])
    survey = result.frame("definitive.survey")
    overlap = result.frame("definitive.overlap")
    assert (survey["run"] == "in-run").all() and len(survey) == len(runs["in"])
    assert (overlap["run"] == "out-run").all() and (overlap["role"] == "overlap").all()
    # the out-run beside the definitive (in-run) survey: the same azimuth disagreement
    assert overlap["azi_diff"].abs().max() == pytest.approx(by_gate["azimuth"]["value"], abs=0.05)

    lenient = gp.run(
        pipeline, {"inrun": runs["in"], "outrun": runs["bad"]}, set={"gates.azi_tolerance": 3.0}
    )
    assert lenient.manifest["acceptance"]["status"] == "pass"
    agreeing = gp.run(pipeline, {"inrun": runs["in"], "outrun": runs["out"]})
    assert agreeing.manifest["acceptance"]["status"] == "pass"


FREE_GYRO_PIPELINE = """
name: free-gyro-gates
version: "1.0"
inputs:
  readings: {description: free-gyro readings}
well: {north_reference: "true"}
stages:
  - {id: read, uses: read_free_gyro}
  - id: drift
    uses: correct_drift
    inputs: {readings: read.free_gyro}
  - id: gates
    uses: free_gyro_gates
    inputs: {inout: drift.qc}
"""


def test_free_gyro_in_out_qc_is_gated(tmp_path: Path) -> None:
    """A free gyro's drift-corrected in/out QC through the same gates (its readings carry
    no separate out-run depths: the depth gate is not evaluated)."""
    readings = gp.simulate(ROOT / "examples" / "plans" / "j-well-free-gyro.yaml").readings
    (tmp_path / "p.yaml").write_text(FREE_GYRO_PIPELINE)
    result = gp.run(tmp_path / "p.yaml", {"readings": readings})
    gates = result.frame("gates.gates").set_index("gate")
    assert gates.loc["depth", "status"] == "not evaluated" and np.isnan(gates.loc["depth", "value"])
    qc = result.frame("drift.qc")
    assert gates.loc["stations", "value"] == len(qc)
    assert gates.loc["inclination", "value"] == pytest.approx(qc["inc_diff"].abs().max())
    by_gate = {g["gate"]: g for g in result.manifest["acceptance"]["gates"]}
    assert by_gate["depth"]["value"] is None  # NaN → null in JSON


def test_a_gap_in_the_stations_compared_fails_the_coverage_gate(
    runs: dict[str, pd.DataFrame],
) -> None:
    """Two in-run stations left out open a gap of three station intervals (180 m > 100 m);
    a gap of the out-run alone is a gap of the stations compared too."""
    assert _status(gp.acceptance_gates(runs["in"], runs["out"]).gates)["coverage"] == "pass"
    holed = runs["in"].drop(index=[6, 7])
    above, below = runs["in"]["md"][5], runs["in"]["md"][8]
    gates = gp.acceptance_gates(holed, runs["out"]).gates.set_index("gate")
    assert gates.loc["coverage", "status"] == "fail"
    assert gates.loc["coverage", "value"] == pytest.approx(below - above, abs=1e-9)
    assert (gates.loc["coverage", "limit"], gates.loc["coverage", "unit"]) == (100.0, "m")
    assert f"{above:.1f} to {below:.1f} m MD" in gates.loc["coverage", "description"]
    assert (gates.drop(index="coverage")["status"] != "fail").all()
    out_holed = gp.acceptance_gates(runs["in"], runs["out"].drop(index=[6, 7])).gates
    assert _status(out_holed)["coverage"] == "fail"
    wide = gp.acceptance_gates(holed, runs["out"], max_gap=200.0).gates
    assert _status(wide)["coverage"] == "pass"


def test_a_stated_td_must_be_reached(runs: dict[str, pd.DataFrame]) -> None:
    """``td`` (m): the deepest station compared within ``td_tolerance`` (0.5 m) of it; no
    ``td``, no TD gate."""
    deepest = runs["in"]["md"].max()
    assert "td" not in _status(gp.acceptance_gates(runs["in"], runs["out"]).gates)
    reached = gp.acceptance_gates(runs["in"], runs["out"], td=deepest + 0.3).gates
    assert _status(reached)["td"] == "pass"
    short = gp.acceptance_gates(runs["in"], runs["out"], td=deepest + 40.0).gates
    row = short.set_index("gate").loc["td"]
    assert row["status"] == "fail" and row["value"] == pytest.approx(40.0, abs=1e-9)
    assert (row["limit"], row["unit"]) == (0.5, "m")
    assert f"{deepest:.1f} m MD" in row["description"] and "TD" in row["description"]
    cut = gp.acceptance_gates(runs["in"], runs["out"].iloc[:-1], td=deepest + 0.3).gates
    assert _status(cut)["td"] == "fail"  # the bottom station of the in-run alone: not compared


def _feet_file(path: Path, keep: list[int]) -> Path:
    """The example J-well stations (every 30 m) at the rows ``keep``, MD written in feet."""
    lines = (ROOT / "examples" / "stations-j-well.csv").read_text().splitlines()
    head = lines.index("MD (m),Inc (deg),Azimuth True (deg)")
    rows = [lines[head + 1 + k].split(",") for k in keep]
    body = [f"{float(md) / 0.3048:.4f},{inc},{azi}" for md, inc, azi in rows]
    path.write_text("\n".join([*lines[:head], "MD (ft),Inc (deg),Azimuth True (deg)", *body]))
    return path


@pytest.mark.parametrize(("dropped", "gap", "status"), [(2, 90.0, "pass"), (3, 120.0, "fail")])
def test_coverage_of_feet_files_is_judged_in_metres(
    tmp_path: Path, dropped: int, gap: float, status: str
) -> None:
    """In-run and out-run files in feet (stations every 98.4 ft): a gap of 295.3 ft is
    90 m, within the 100 m limit; 393.7 ft is 120 m, beyond it."""
    keep = [k for k in range(85) if not 40 < k <= 40 + dropped]
    inrun = _feet_file(tmp_path / "in.csv", keep)
    outrun = _feet_file(tmp_path / "out.csv", keep)
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "inout-gyro.yaml", "--input", f"inrun={inrun}",
        "--input", f"outrun={outrun}", "--out", tmp_path / "out",
        "--set", "report.formats=[html]", "--set", "gates.td=2520",
    )  # fmt: skip
    assert result.returncode == {"pass": 0, "fail": 3}[status], result.output  # 3: rejected
    manifest = json.loads((tmp_path / "out" / "run.json").read_text())
    by_gate = {g["gate"]: g for g in manifest["acceptance"]["gates"]}
    assert by_gate["coverage"]["value"] == pytest.approx(gap, abs=1e-3)
    assert (by_gate["coverage"]["status"], by_gate["coverage"]["unit"]) == (status, "m")
    assert by_gate["td"]["status"] == "pass"
    assert f"gates.coverage     {status}" in result.stdout


def test_a_table_of_two_surveys_is_refused(tmp_path: Path) -> None:
    """An in-run file listing the main bore and its sidetrack (a SURVEY column, as an
    operator's export of a wellbore lists both): paired by MD alone, the sidetrack's
    stations were compared with the out-run's main-bore stations at the same depths; now
    refused, naming the port and the surveys, no traceback."""
    lines = (ROOT / "examples" / "stations-j-well.csv").read_text().splitlines()
    head = lines.index("MD (m),Inc (deg),Azimuth True (deg)")
    rows = lines[head + 1 : head + 41]
    sidetrack = [f"{float(md) + 600:.2f},{float(inc) + 2:.2f},{azi}" for md, inc, azi in
                 (r.split(",") for r in rows[20:30])]  # fmt: skip
    inrun = tmp_path / "in.csv"
    inrun.write_text(
        "\n".join(
            [*lines[:head], "Survey,MD (m),Inc (deg),Azimuth True (deg)"]
            + [f"MAIN,{r}" for r in rows]
            + [f"ST1,{r}" for r in sidetrack]
        )
    )
    outrun = tmp_path / "out.csv"
    outrun.write_text("\n".join([*lines[: head + 1], *rows]))
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "inout-gyro.yaml", "--input", f"inrun={inrun}",
        "--input", f"outrun={outrun}", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode != 0
    assert "inrun: the table holds 2 surveys ('MAIN', 'ST1')" in result.stderr
    assert "Traceback" not in result.output and not (tmp_path / "out").exists()
    with pytest.raises(gp.GyropipeError, match="outrun: the table holds 2 surveys"):
        gp.run(ROOT / "pipelines" / "inout-gyro.yaml", {"inrun": outrun, "outrun": inrun})
    both = gp.read(inrun)  # the gates alone (no definitive stage after them to refuse)
    with pytest.raises(gp.GyropipeError, match="inrun: the table holds 2 surveys"):
        gp.acceptance_gates(both, gp.read(outrun))


def test_a_bad_free_gyro_tie_in_fails_its_check(tmp_path: Path) -> None:
    """The drift rate from the tie-in misclosure makes the tie-in's two corrected readings
    equal: its pair is checked against the drift the other stations read twice show. The
    out-run's closing reading at the tie-in 3° off (the tool knocked at the wellhead) fails
    it — against the 1° azimuth limit, though the tie-in is vertical (its error shifts every
    azimuth of the survey); the clean survey's tie-in passes, its difference within 4 σ."""
    readings = gp.simulate(ROOT / "examples" / "plans" / "j-well-free-gyro.yaml").readings
    closing = readings.index[(readings["run"] == "out") & (readings["station"] == 0)][-1]
    bad = readings.copy()
    bad.loc[closing, "azi"] = (bad.loc[closing, "azi"] + 3.0) % 360
    (tmp_path / "p.yaml").write_text(FREE_GYRO_PIPELINE)
    for data, offset, status in ((readings, 0.0, "pass"), (bad, -3.0, "fail")):
        result = gp.run(tmp_path / "p.yaml", {"readings": data})
        qc = result.frame("drift.qc")
        tie = qc[qc["station"] == 0].iloc[0]
        assert bool(tie["tie_in"]) and qc["tie_in"].sum() == 1
        assert 0.2 < tie["sigma_azi_diff"] < 0.5  # two readings and the other pairs' rate
        assert abs(tie["azi_diff"] - offset) < 4 * tie["sigma_azi_diff"]
        assert (tie["azi_tolerance"], bool(tie["passed"])) == (1.0, status == "pass")
        gates = result.frame("gates.gates").set_index("gate")
        assert gates.loc["tie_in", "status"] == status
        assert gates.loc["tie_in", "value"] == pytest.approx(abs(tie["azi_diff"]))
        assert gates.loc["tie_in", "limit"] == 1.0

"""Simulation plans through the public interfaces: `gyropipe simulate`, the simulate stages
in a pipeline, free-gyro readings, bad plans, and the error budget."""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from pipeline.errors import SpecError
from pipeline.gyrocompass.azimuth import cramer_rao
from pipeline.gyrocompass.precision import hr_covariance, position_design
from pipeline.sim.budget import error_budget
from pipeline.sim.freegyro import simulate_free_gyro
from pipeline.sim.spec import load_simulation
from pipeline.tables import FreeGyroReadings, RawSamples, SimTruth, Stations
from tests_support import ROOT, gyropipe_cli, read_stations

PLANS = ROOT / "examples" / "plans"
SMALL = """
name: small
seed: 7
site:
  latitude: 61.25
  date: 2026-11-21
well:
  sections:
    - {kind: vertical, length: 30}
    - {kind: build, dls: 6.0, inc: 20, azi: 37}
tool: {preset: mems-vrg}
survey: {mode: point, every: 30, dwell: 5, move_time: 1}
"""


def write(tmp_path: Path, text: str, name: str = "plan.yaml") -> Path:
    path = tmp_path / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    return path


def test_every_example_plan_is_valid():
    names = sorted(p.stem for p in PLANS.glob("*.yaml"))
    assert {"vertical", "j-well", "s-well", "horizontal", "sidetrack-kickoff"} <= set(names)
    for path in PLANS.glob("*.yaml"):
        load_simulation(path)


def test_simulate_command_writes_contracted_tables(tmp_path: Path):
    plan = write(tmp_path, SMALL)
    out = tmp_path / "out"
    result = gyropipe_cli("simulate", str(plan), "--out", str(out))
    assert result.returncode == 0, result.stderr
    samples = pq.read_table(out / "samples.parquet")
    RawSamples.validate_table(samples)
    SimTruth.validate_table(pq.read_table(out / "truth.parquet"))
    stations = pq.read_table(out / "stations.parquet")
    Stations.validate_table(stations)
    # stations every 30 m within the plan (vertical 30 m + 100 m build to 20°)
    np.testing.assert_allclose(stations.column("md").to_numpy(), [0.0, 30.0, 60.0, 90.0, 120.0])
    manifest = json.loads((out / "simulation.json").read_text())
    assert manifest["seed"] == 7
    assert manifest["outputs"]["samples"]["rows"] == samples.num_rows
    again = tmp_path / "again"
    gyropipe_cli("simulate", str(plan), "--out", str(again), check=True)
    assert pq.read_table(again / "samples.parquet").equals(samples)  # reproducible
    csv = gyropipe_cli(
        "simulate", str(plan), "--out", str(tmp_path / "c"), "--format", "csv", "--seed", "8"
    )
    assert csv.returncode == 0, csv.stderr
    assert (tmp_path / "c" / "stations.csv").read_text().startswith("# gyropipe small")


def test_pipeline_starts_from_a_simulation(tmp_path: Path):
    plan = write(tmp_path, SMALL)
    pipeline = write(
        tmp_path,
        """
        name: simulated-survey
        version: 1
        inputs: {plan: {}}
        stages:
          - id: sim
            uses: simulate
            persist: [samples]
          - id: trajectory
            uses: minimum_curvature
            inputs: {stations: sim.stations}
            persist: [trajectory]
    """,
        "pipeline.yaml",
    )
    out = tmp_path / "out"
    result = gyropipe_cli("run", str(pipeline), "--input", str(plan), "--out", str(out))
    assert result.returncode == 0, result.stderr
    trajectory = pq.read_table(out / "trajectory.trajectory.parquet")
    truth = pq.read_table(out / "sim.samples.parquet")
    assert truth.num_rows > 1000
    # last station at 120 m, 90 m into the build from 30 m at 6°/30 m: I = 18° on an arc
    # of radius R, so the closed-form horizontal displacement is R(1 − cos I)
    r = 30 / np.radians(6.0)
    end = trajectory.slice(trajectory.num_rows - 1)
    assert end.column("inc")[0].as_py() == pytest.approx(18.0)
    horizontal = r * (1 - np.cos(np.radians(18)))
    assert end.column("closure_distance")[0].as_py() == pytest.approx(horizontal, abs=1e-9)
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["well"]["latitude"] == 61.25 and manifest["well"]["north_reference"] == "true"


@pytest.mark.parametrize(
    ("edit", "fragment"),
    [
        ("survey: {mode: point, every: 30, dwell: -5}", "survey.dwell"),
        ("tool: {preset: no-such-tool}", "unknown tool preset 'no-such-tool'"),
        ("tool: {preset: mems-vrg, overrides: {gyro: {bais: [1, 2, 3]}}}", "bais"),
        ("survey: {mode: sideways}", "survey"),
    ],
)
def test_bad_plan_parameters_name_the_field(tmp_path: Path, edit: str, fragment: str):
    key = edit.split(":")[0]
    lines = [line for line in textwrap.dedent(SMALL).splitlines() if not line.startswith(key)]
    plan = write(tmp_path, "\n".join([*lines, edit]) + "\n")
    with pytest.raises(SpecError) as info:
        load_simulation(plan)
    text = str(info.value)
    assert fragment in text
    assert f"{plan}:" in text


def test_impossible_dls_for_the_section_length(tmp_path: Path):
    plan = write(
        tmp_path,
        SMALL.replace(
            "{kind: build, dls: 6.0, inc: 20, azi: 37}",
            "{kind: build, dls: 1.0, inc: 20, azi: 37, length: 100}",
        ),
    )
    with pytest.raises(SpecError) as info:
        load_simulation(plan)
    assert "sections[1]" in str(info.value) and "100" in str(info.value)
    result = gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "o"))
    assert result.returncode == 2
    assert "Traceback" not in result.stderr and not (tmp_path / "o").exists()


def test_free_gyro_readings_drift_as_configured():
    spec = load_simulation(PLANS / "j-well-free-gyro.yaml")
    readings = simulate_free_gyro(spec)
    FreeGyroReadings.validate_table(readings)
    t = readings.column("time").to_numpy() / 3600
    error = (
        readings.column("azi").to_numpy() - readings.column("true_azi").to_numpy() + 180
    ) % 360 - 180
    inclined = readings.column("true_inc").to_numpy() > 1  # azimuth is defined there
    slope, offset = np.polyfit(t[inclined], error[inclined], 1)
    assert slope == pytest.approx(3.0, abs=0.1)  # deg/h, configured
    assert offset == pytest.approx(0.5, abs=0.1)
    resid = error[inclined] - (offset + slope * t[inclined])
    assert resid.std() == pytest.approx(0.2, rel=0.25)  # configured reading noise
    runs = readings.column("run").to_pylist()
    assert runs[0] == "in" and runs[-1] == "out"


def test_lsq_covariance_matches_monte_carlo():
    rng = np.random.default_rng(4)
    psi = np.radians([10.0, 100.0, 190.0, 280.0, 10.0])
    t = np.array([20.0, 63.0, 106.0, 149.0, 192.0])
    design = position_design(psi, t)
    truth = np.array([7.0, -3.0, 5.0, 0.01])
    fits = []
    for _ in range(4000):
        y = design @ truth + rng.normal(0, 0.8, len(psi))
        fits.append(np.linalg.lstsq(design, y, rcond=None)[0][:2])
    np.testing.assert_allclose(np.cov(np.array(fits).T), hr_covariance(psi, t, 0.8), rtol=0.08)


def test_azimuth_sigma_limits():
    cov = np.diag([0.4, 0.4]) ** 2
    lat = np.radians(61.25)
    k = 15.041067 * np.cos(lat)

    # vertical hole: both channels carry the azimuth equally → σ/k
    def azimuth_sigma(c, a, i, lat):
        return float(cramer_rao(np.array(a), np.array(i), lat, c))

    assert azimuth_sigma(cov, 0.7, 0.0, lat) == pytest.approx(0.4 / k, rel=1e-4)
    # east-west horizontal hole: h carries nothing, r nothing about A → undefined
    assert azimuth_sigma(cov, np.pi / 2, np.pi / 2, lat) > 1e6
    # never worse than the sine form σ_r / (k |cos A|)
    assert azimuth_sigma(cov, 0.3, 1.2, lat) <= 0.4 / (k * np.cos(0.3))


def test_error_budget_of_the_j_well():
    spec = load_simulation(PLANS / "j-well.yaml")
    budget = error_budget(spec)
    assert budget.num_rows == len(np.arange(0, 2500.1, 90))
    inc = budget.column("inc").to_numpy()
    gyro = budget.column("sigma_azi_gyro").to_numpy()
    # ~0.2 °/h per position at 61.25° N (k = 7.2 °/h): of order one degree, as ENGINEERING
    # quotes 0.79° for a 0.1 °/h bias
    assert np.all((gyro[inc > 10] > 0.3) & (gyro[inc > 10] < 3.0))
    assert np.all(budget.column("sigma_inc").to_numpy() < 0.05)
    # white noise only: σ_A ∝ 1/√dwell
    white = {"preset": "mems-vrg", "overrides": {"gyro": {"bias_instability": 0.0}}}
    base = spec.model_copy(update={"tool": spec.tool.model_validate(white)})
    longer = base.model_copy(update={"survey": base.survey.model_copy(update={"dwell": 160.0})})
    ratio = (
        error_budget(longer).column("sigma_azi_gyro").to_numpy()
        / error_budget(base).column("sigma_azi_gyro").to_numpy()
    )
    defined = inc > 0.0  # the vertical top hole has no azimuth (NaN in both)
    assert np.all(np.isnan(ratio[~defined]))
    np.testing.assert_allclose(ratio[defined], 0.5, rtol=1e-9)


def test_error_budget_declares_the_azimuth_undefined_at_vertical(tmp_path: Path):
    """At 0° the compass stage gives no azimuth (horizontal gravity within its σ): the budget
    predicts none either — NaN in the table, said in words on the command line."""
    budget = error_budget(load_simulation(PLANS / "j-well.yaml"))
    inc = budget.column("inc").to_numpy()
    for name in ("sigma_azi", "sigma_azi_gyro", "sigma_azi_g", "sigma_azi_accel"):
        sigma = budget.column(name).to_numpy()
        assert np.all(np.isnan(sigma[inc == 0.0])), name
        assert np.all(np.isfinite(sigma[inc > 1.0])), name
    done = gyropipe_cli("budget", str(PLANS / "vertical.yaml"))
    assert done.returncode == 0, done.stderr
    rows = done.stdout.splitlines()[2:]
    assert rows and all("azimuth undefined" in row for row in rows)
    assert "nan" not in done.stdout


def test_well_from_a_stations_file(tmp_path: Path):
    (tmp_path / "st.csv").write_text(
        "MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n30,2,40\n60,5,45\n90,9,47\n"
    )
    plan = write(
        tmp_path,
        SMALL.replace(
            "  sections:\n    - {kind: vertical, length: 30}\n"
            "    - {kind: build, dls: 6.0, inc: 20, azi: 37}\n",
            "  stations: st.csv\n",
        ),
    )
    spec = load_simulation(plan, read_stations=read_stations)
    from pipeline.sim.simulate import simulate

    stations = simulate(spec).stations
    np.testing.assert_allclose(stations.column("md").to_numpy(), [0, 30, 60, 90])
    np.testing.assert_allclose(stations.column("inc").to_numpy(), [0, 2, 5, 9], atol=1e-12)
    np.testing.assert_allclose(stations.column("azi").to_numpy()[1:], [40, 45, 47], atol=1e-9)
    (tmp_path / "grid.csv").write_text("MD (m),Inc (deg),Azimuth Grid (deg)\n0,0,0\n30,2,40\n")
    grid = write(tmp_path, plan.read_text().replace("st.csv", "grid.csv"), "grid.yaml")
    with pytest.raises(SpecError) as info:  # at the plan's stations: line
        load_simulation(grid, read_stations=read_stations)
    assert str(info.value.problems[0]) == (
        f"{grid}:7:13: well.stations: {tmp_path / 'grid.csv'}: the simulator needs "
        "true-north azimuths"
    )


def test_a_denormal_dls_is_refused_at_its_line(tmp_path: Path):
    """Fuzz finding: dls 5e-324 made the arc infinite (NumPy warned of a division by zero)
    and was reported against the well as a whole, with the other kind of well's fields."""
    plan = write(tmp_path, SMALL.replace("dls: 6.0", "dls: 5.0e-324"))
    result = gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "o"))
    assert result.returncode == 2 and "Warning" not in result.stderr, result.stderr
    assert result.stderr.splitlines()[1:] == [
        f"  {plan}:9:26: well.sections.1.dls: Input should be greater than or equal to 0.001 "
        "(got 5e-324)"
    ]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("row", "problem"),
    [
        ("60,abc,45", "st.csv:4 (column 'Inc (deg)'): expected a number, got 'abc'"),
        (
            "60,179.99,225",
            "st.csv:4: station 2 turns 179.990 deg from the previous station: a reversal "
            "has no unique circular arc",
        ),
    ],
    ids=["cell", "reversal"],
)
def test_stations_file_problems_name_the_plan_line_and_the_file_line(
    tmp_path: Path, row: str, problem: str
):
    """A stations file's problem was reported at the stations file alone (or, for a
    reversal, by station index through ``path()``); now at the plan's ``stations:`` line
    too, through ``gyropipe simulate``."""
    (tmp_path / "st.csv").write_text(
        f"MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n30,0,0\n{row}\n90,1,45\n"
    )
    plan = write(
        tmp_path,
        SMALL.replace(
            "  sections:\n    - {kind: vertical, length: 30}\n"
            "    - {kind: build, dls: 6.0, inc: 20, azi: 37}\n",
            "  stations: st.csv\n",
        ),
    )
    result = gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "o"))
    assert result.returncode == 2, result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 2 and lines[1].startswith(f"  {plan}:7:13: well.stations: "), lines
    assert f"well.stations: {tmp_path}/{problem}" in lines[1], lines

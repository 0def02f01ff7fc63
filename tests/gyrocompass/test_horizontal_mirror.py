"""Near horizontal a transverse gyro cannot tell the azimuth A from its mirror 180° − A: the
high-side component h = k cos A cos I + Ω sin φ sin I carries cos A only through cos I. At
88° a single-axis MEMS gyro's stations on a north-going lateral compassed to ≈ 178° with
σ 1.9° and no flag (93 σ off), which the trajectory turned into a 258°/30 m dogleg. A station
whose mirror fits its readings about as well is rejected, saying why; the axial gyro, where
it joins the fit, resolves it. Driven through ``gyropipe simulate`` and ``gyropipe run`` and
the Python API on simulated wells; tolerances: 4 σ of the station's own predicted σ."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import yaml

import pipeline as gp
from pipeline.gyrocompass.azimuth import OMEGA_DEG_H, mirror_probability
from tests_support import EXAMPLE_SITE, gyropipe_cli, simulate_and_run

FIVE = [0, 90, 180, 270, 0]


def plan(azi: float, tool: dict[str, Any], seed: int) -> dict[str, Any]:
    """Build at 30°/30 m from 20 m to 88°, then hold: stations from 50° to 88°."""
    return {
        "name": "mirror",
        "seed": seed,
        "site": EXAMPLE_SITE,
        "well": {
            "sections": [
                {"kind": "vertical", "length": 20},
                {"kind": "build", "dls": 30.0, "inc": 88, "azi": azi},
                {"kind": "hold", "length": 100},
            ]
        },
        "tool": tool,
        "survey": {"mode": "point", "stations": [70, 90, 110, 130, 150, 170], "dwell": 20},
    }


def wrapped(a: np.ndarray) -> np.ndarray:
    return (a + 180.0) % 360.0 - 180.0


def test_a_north_lateral_at_88_degrees_is_not_compassed_to_its_mirror(tmp_path: Path):
    text = yaml.safe_dump(plan(0.0, {"preset": "mems-vrg"}, seed=1))
    out = simulate_and_run(tmp_path, text)
    truth = pd.read_parquet(tmp_path / "sim" / "stations.parquet").set_index("station")
    stations = pd.read_parquet(out / "compass.stations.parquet").set_index("station")
    rejects = pd.read_parquet(out / "compass.rejects.parquet").set_index("station")
    error = wrapped(stations.azi - truth.azi[stations.index])
    assert (error.abs() <= 4 * stations.sigma_azi).all(), pd.concat([error, stations], axis=1)
    assert set(stations.index) >= {0, 1}  # 50° and 70°: solved
    # the two stations that went to ≈ 178° (seed 1) are rejected, naming the mirror
    assert {4, 5} <= set(rejects.index)
    assert rejects.reason.str.contains("cannot be told from its mirror").all()
    trajectory = pd.read_parquet(out / "uncertainty.trajectory.parquet")
    assert trajectory.dls.max() < 40.0  # the plan's 30°/30 m, not a reversal


def test_the_budget_says_the_lateral_is_ambiguous_before_the_job(tmp_path: Path):
    """``gyropipe budget`` predicted σ 1.96° at the 88° stations the compass stage rejects."""
    plan_file = tmp_path / "plan.yaml"
    plan_file.write_text(yaml.safe_dump(plan(0.0, {"preset": "mems-vrg"}, seed=1)))
    out = tmp_path / "budget.csv"
    done = gyropipe_cli("budget", str(plan_file), "--out", str(out))
    assert done.returncode == 0, done.stderr
    budget = pd.read_csv(out, comment="#")
    budget.columns = [c.split("[")[0] for c in budget.columns]
    horizontal = budget.inc > 87.0
    assert horizontal.sum() == 4 and budget.sigma_azi[horizontal].isna().all()
    assert (budget.mirror[horizontal] > 0.01).all()
    assert budget.sigma_azi[~horizontal].between(1.0, 3.0).all()
    assert (budget.mirror[~horizontal] < 1e-6).all()
    rows = done.stdout.splitlines()[2 : 2 + len(budget)]  # after the title and header
    assert [("azimuth ambiguous" in row) for row in rows] == list(horizontal)


@pytest.mark.parametrize("azi", [90.0, 270.0])
def test_an_east_west_lateral_has_no_mirror_to_reject(azi: float):
    """At A = 90° the mirror is A itself: the σ, not a rejection, states the doubt."""
    sim = gp.simulate(plan(azi, {"preset": "mems-vrg"}, seed=2))
    readings = gp.position_readings(sim["samples"], trim_start=1.0)
    solved = gp.compass(readings, latitude=EXAMPLE_SITE["latitude"])
    assert len(solved["rejects"]) == 0
    stations = solved["stations"].set_index("station")
    error = wrapped(stations.azi - sim["stations"].set_index("station").azi[stations.index])
    assert (error.abs() <= 4 * stations.sigma_azi).all()


def test_the_axial_gyro_in_the_fit_resolves_the_mirror():
    sim = gp.simulate(plan(0.0, {"preset": "nav-grade"}, seed=1))
    readings = gp.position_readings(sim["samples"], trim_start=1.0)
    solved = gp.compass(readings, latitude=EXAMPLE_SITE["latitude"], z_bias_sigma=0.05)
    assert len(solved["rejects"]) == 0
    stations = solved["stations"].set_index("station")
    error = wrapped(stations.azi - sim["stations"].set_index("station").azi[stations.index])
    assert (error.abs() <= 4 * stations.sigma_azi).all()


def test_mirror_probability_of_noise_free_components():
    """Exactly horizontal, (h, r) fit A and 180° − A alike: 1/2. At 60° with 0.05 °/h noise
    h tells them apart by 2 k cos A cos I ≈ 130 σ: 0."""
    lat = np.radians(61.25)
    k, s = OMEGA_DEG_H * np.cos(lat), OMEGA_DEG_H * np.sin(lat)
    a, sigma = np.radians([30.0, 30.0]), np.radians([1.0, 1.0])
    inc = np.radians([90.0, 60.0])
    obs = np.stack([k * np.cos(a) * np.cos(inc) + s * np.sin(inc), -k * np.sin(a)], axis=1)
    cov = np.broadcast_to(np.eye(2) * 0.05**2, (2, 2, 2))
    np.testing.assert_allclose(mirror_probability(obs, cov, a, sigma, inc, lat, 1e-3), [0.5, 0.0])


def test_the_screen_drops_no_station_that_reaches_the_floor():
    """The triangle-inequality screen leaves out only stations whose mirror odds are below
    the floor: against no screen (a floor of 1e-300) on noisy components, 60°–95°."""
    rng = np.random.default_rng(3)
    lat, n = np.radians(61.25), 2000
    k, s = OMEGA_DEG_H * np.cos(lat), OMEGA_DEG_H * np.sin(lat)
    a, inc = rng.uniform(0, 2 * np.pi, n), np.radians(rng.uniform(60, 95, n))
    obs = np.stack([k * np.cos(a) * np.cos(inc) + s * np.sin(inc), -k * np.sin(a)], axis=1)
    obs += rng.normal(scale=0.25, size=obs.shape)
    cov = np.broadcast_to(np.eye(2) * 0.25**2, (n, 2, 2))
    sigma = np.full(n, np.radians(2.0))
    every = mirror_probability(obs, cov, a, sigma, inc, lat, 1e-300)
    screened = mirror_probability(obs, cov, a, sigma, inc, lat, 1e-3)
    reached = every > 1e-3
    assert 50 < reached.sum() < n - 50
    np.testing.assert_array_equal(screened[reached], every[reached])
    assert (screened[~reached] <= every[~reached]).all()

"""``gyropipe budget`` for the two- and three-axis tools the simulator and the compass stage
support: the least squares has a bias and trend per transverse gyro, so the bundled
horizontal plan's 0/180/0 positions of a two-axis DTG are solvable; the predicted gyro share
of σ_azi matches the scatter of the compassed azimuths over seeds."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

import pipeline as gp
from pipeline.sim.budget import error_budget
from pipeline.sim.spec import load_simulation
from tests_support import EXAMPLE_SITE, gyropipe_cli

PLANS = Path(__file__).parents[2] / "examples" / "plans"

PLAN: dict[str, Any] = {
    "name": "xy-hold",
    "site": EXAMPLE_SITE,
    "well": {
        "sections": [
            {"kind": "vertical", "length": 20},
            {"kind": "build", "dls": 15.0, "inc": 60, "azi": 37},
            {"kind": "hold", "to_md": 320},
        ]
    },
    # 10 s per position (the presets' default is 40 s): the same budget check on 40 % of the
    # samples
    "survey": {"mode": "point", "every": 20, "positions": [0, 180, 0], "dwell": 10.0},
}


def test_the_horizontal_example_plan_has_a_budget():
    done = gyropipe_cli("budget", str(PLANS / "horizontal.yaml"))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    tangent = [line for line in lines if line.split()[:2] == ["1500.0", "60.00"]]
    assert len(tangent) == 1 and "azimuth" not in tangent[0]
    # due west at 90°: the transverse gyros carry no azimuth (∂h/∂A = ∂r/∂A = 0)
    lateral = [line for line in lines if line.split()[:2] == ["2500.0", "90.00"]]
    assert len(lateral) == 1 and "azimuth unobservable" in lateral[0]


def test_three_positions_of_a_single_axis_gyro_are_refused_in_words(tmp_path: Path):
    plan = tmp_path / "plan.yaml"
    plan.write_text(yaml.safe_dump({**PLAN, "seed": 0, "tool": {"preset": "mems-vrg"}}))
    done = gyropipe_cli("budget", str(plan))
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert "3 positions of 1 gyro axis(es) cannot resolve" in done.stderr


@pytest.mark.parametrize("preset", ["dtg-xy", "nav-grade"])
def test_the_gyro_share_matches_the_scatter_over_seeds(tmp_path: Path, preset: str):
    plan = {**PLAN, "tool": {"preset": preset}}
    errors = []
    for seed in range(6):
        sim = gp.simulate({**plan, "seed": seed})
        st = gp.compass(gp.position_readings(sim.samples)).stations
        hold = st[st["inc"] > 59.5]
        truth = sim.stations.set_index("md")
        nearest = np.abs(truth.index.values[:, None] - hold["md"].values).argmin(axis=0)
        true = truth.iloc[nearest]["azi"].to_numpy()
        errors.append((hold["azi"].to_numpy() - true + 180.0) % 360.0 - 180.0)
    err = np.array(errors)  # seeds × stations
    # the preset's g-sensitivity and accelerometer errors are the same at every seed: the
    # scatter about each station's mean is the random (gyro noise and drift) share
    dof = err.size - err.shape[1]
    scatter = np.sqrt(((err - err.mean(axis=0)) ** 2).sum() / dof)
    file = tmp_path / "plan.yaml"
    file.write_text(yaml.safe_dump({**plan, "seed": 0}))
    budget = error_budget(load_simulation(file)).to_pandas()
    predicted = budget.loc[budget["inc"] > 59.5, "sigma_azi_gyro"].to_numpy()
    assert len(predicted) == err.shape[1] >= 10
    # 10 seeds measured: nav-grade 0.340° against 0.328°; dtg-xy 1.11° against 1.37° (its
    # 0.15 °/h bias instability is taken per position, the trend absorbs part). Never
    # optimistic beyond the scatter's sampling error (~10 % at 50 dof), at most 2.5×
    # conservative.
    assert 0.4 < scatter / predicted.max() < 1.25, (scatter, predicted)

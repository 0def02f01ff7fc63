"""Biases compassing cannot see are in σ (issue 18, item 5a): the gyro's g-dependent bias
turns with the frame like the Earth rate, and the accelerometers' bias, misalignment and
scale factor are common to the positions. Against the simulator, the normalised errors
(error / σ) of the shipped presets are of order one; a station whose σ passes the limit is
flagged; ``gyropipe budget`` predicts the same share."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
import yaml

import pipeline as gp
from pipeline.errors import StageError
from tests_support import EXAMPLE_SITE, gyropipe_cli

PLAN: dict[str, Any] = {
    "name": "short-hold",
    "site": EXAMPLE_SITE,
    "well": {
        "sections": [
            {"kind": "vertical", "length": 20},
            {"kind": "build", "dls": 15.0, "inc": 50, "azi": 37},
            {"kind": "hold", "to_md": 260},
        ]
    },
    "survey": {"mode": "point", "every": 20, "dwell": 8, "move_time": 1.0, "speed": 10.0},
}


def normalised(preset: str, seeds: range, **params: Any) -> tuple[np.ndarray, ...]:
    """(azimuth z, inclination z, flags, σ_azi) of the inclined stations over ``seeds``."""
    za, zi, flags, sigma = [], [], [], []
    for seed in seeds:
        sim = gp.simulate({**PLAN, "seed": seed, "tool": {"preset": preset}})
        st = gp.compass(gp.position_readings(sim.samples), **params).stations
        truth = sim.stations.set_index("md")
        inclined = st[st["mode"] == "inclined"]
        nearest = np.abs(truth.index.values[:, None] - inclined["md"].values).argmin(axis=0)
        true = truth.iloc[nearest]
        err_azi = (inclined["azi"].values - true["azi"].values + 180.0) % 360.0 - 180.0
        za.append(err_azi / inclined["sigma_azi"].values)
        zi.append((inclined["inc"].values - true["inc"].values) / inclined["sigma_inc"].values)
        flags += list(inclined["flags"])
        sigma.append(inclined["sigma_azi"].to_numpy())
    return np.concatenate(za), np.concatenate(zi), np.array(flags), np.concatenate(sigma)


@pytest.mark.parametrize("preset", ["dtg-xy", "mems-vrg", "nav-grade"])
def test_normalised_errors_of_the_presets_are_of_order_one(preset: str):
    za, zi, _, _ = normalised(preset, range(2))
    assert len(za) >= 20
    for z in (za, zi):
        assert abs(z.mean()) < 2.0 and np.sqrt(np.mean(z**2)) < 2.0, (preset, z)


def test_the_g_sensitivity_of_a_two_axis_gyro_is_in_sigma_and_flagged():
    za, _, flags, sigma = normalised("dtg-xy", range(1))
    # without the tool's g-sensitivity the σ claims a precision the azimuth does not have
    blind = normalised("dtg-xy", range(1), g_sensitivity=0.0)[0]
    assert np.sqrt(np.mean(blind**2)) > 3.0 > np.sqrt(np.mean(za**2))
    # 1 (°/h)/g at 50°: σ ≈ 0.77/(Ω cos φ) ≈ 7° > the 5° limit, flagged; below it, not
    poor = np.array(["poor_azimuth" in f for f in flags])
    assert poor.any() and np.array_equal(poor, sigma > 5.0)
    assert not any("poor_azimuth" in f for f in normalised("dtg-xy", range(1), max_sigma_azi=8)[2])


def test_budget_predicts_the_g_dependent_share(tmp_path: Path):
    plan = tmp_path / "plan.yaml"
    plan.write_text(yaml.safe_dump({**PLAN, "seed": 1, "tool": {"preset": "dtg-xy"}}))
    out = tmp_path / "budget.csv"
    done = gyropipe_cli("budget", str(plan), "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert "g-sens" in done.stdout
    table = pd.read_csv(out, comment="#")
    table.columns = [c.split("[")[0] for c in table.columns]
    hold = table[table["inc"] > 49.9]
    # h = k cos A cos I + …, r = −k sin A (k = Ω cos φ), each with σ = K sin I, K the
    # transverse row norm of the preset's g-sensitivity matrix: σ_A = K sin I /
    # (k √(sin²A cos²I + cos²A))
    k = 15.041 * np.cos(np.radians(61.25))
    a, i = np.radians(37.0), np.radians(50.0)
    gain = np.hypot(1.0, 0.2)
    expected = np.degrees(gain * np.sin(i) / (k * np.hypot(np.sin(a) * np.cos(i), np.cos(a))))
    assert hold["sigma_azi_g"].to_numpy() == pytest.approx(expected, rel=0.01)
    assert np.all(hold["sigma_azi"] >= hold["sigma_azi_g"])


def test_a_simulated_well_compasses_with_its_presets_tool_errors():
    sim = gp.simulate({**PLAN, "seed": 0, "tool": {"preset": "dtg-xy"}})
    assert sim.samples.attrs["well"]["tool_preset"] == "dtg-xy"
    readings = gp.position_readings(sim.samples)
    sigma = gp.compass(readings).stations["sigma_azi"].to_numpy()
    # dtg-xy's transverse g-sensitivity rows (0.2, 1.0), (−1.0, 0.2) (°/h)/g; accelerometer
    # bias (1.0, −0.8, 0.6)·1e-3 m/s², misalignment ±0.3/±0.2 mrad, scale factor 100 ppm
    by_hand = gp.compass(
        readings,
        g_sensitivity=np.sqrt(1.04),
        acc_bias=np.sqrt((1.0**2 + 0.8**2 + 0.6**2) / 3) * 1e-3,
        acc_misalignment=np.sqrt((2 * 0.3**2 + 4 * 0.2**2) / 6),
        acc_scale_factor=100.0,
    )
    np.testing.assert_allclose(sigma, by_hand.stations["sigma_azi"].to_numpy(), rtol=1e-12)
    # a tool the catalogue does not name: the ISCWSA GYRO-NS magnitudes
    undeclared = gp.compass(readings, well={"tool_preset": None}).stations["sigma_azi"]
    gyro_ns = gp.compass(
        readings,
        g_sensitivity=0.2,
        acc_bias=0.0017,
        acc_misalignment=np.radians(0.0095) * 1e3,
        acc_scale_factor=111.0,
    ).stations["sigma_azi"]
    np.testing.assert_allclose(undeclared.to_numpy(), gyro_ns.to_numpy(), rtol=1e-12)
    assert not np.allclose(undeclared.to_numpy(), sigma, equal_nan=True)
    with pytest.raises(StageError, match=r"tool_preset: unknown tool preset 'no-such'.*dtg-xy"):
        gp.compass(readings, well={"tool_preset": "no-such"})

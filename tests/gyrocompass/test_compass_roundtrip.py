"""Gyrocompassing against the simulator: noise-free recovery over a grid of attitudes and
latitudes for single-axis, XY and three-axis tools; bias and trend removed exactly; with
noise, errors consistent with the predicted σ; the closed form; near-vertical toolface."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from scipy.spatial.transform import Rotation

from pipeline.gyrocompass.fit import Fit, design, fit_all
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.gyrocompass.solve import compass, five_position_closed_form
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from tests_support import read_stations

INCS = [5, 10, 20, 30, 45, 60, 75, 85, 95, 105, 120]
AZIS = list(range(0, 360, 30))
TRIM = ReadingOptions(trim_start=0.5, min_dwell=1.0)


def grid_well(tmp_path: Path, incs, azis, *, start_md: float = 0.0) -> Path:
    """A stations file visiting every (inclination, azimuth) pair, 30 m apart."""
    rows = [(0.0, 0.0, 0.0)]
    md = start_md
    for inc in incs:
        for azi in azis:
            md += 30.0
            rows.append((md, inc, azi))
    path = tmp_path / "grid.csv"
    path.write_text(
        "MD (m),Inc (deg),Azimuth True (deg)\n"
        + "\n".join(f"{m},{i},{a}" for m, i, a in rows)
        + "\n"
    )
    return path


def run(
    stations_file: Path,
    latitude: float,
    tool: dict[str, Any],
    positions,
    *,
    dwell: float = 2.0,
    seed: int = 1,
    options: CompassOptions | None = None,
):
    spec = SimulationSpec.model_validate(
        {
            "name": "grid",
            "seed": seed,
            "site": {
                "latitude": latitude,
                "date": "2026-11-21",
                "magnetic": {"total_field": 50000.0, "dip": 70.0, "declination": 5.0},
            },
            "well": {"stations": str(stations_file)},
            "tool": tool,
            "survey": {
                "mode": "point",
                "every": 30,
                "dwell": dwell,
                "move_time": 1.0,
                "speed": 30.0,
                "positions": positions,
            },
        }
    )
    spec.well.load(read_stations)
    sim = simulate(spec)
    readings = position_readings(sim.samples, TRIM)
    stations, rejects = compass(readings, latitude, options or CompassOptions())
    return sim, stations, rejects


def truth_at(sim, stations: pa.Table) -> dict[str, np.ndarray]:
    """True inclination, azimuth and gyro toolface of the frame x axis at each station's
    first position (from the truth table, through an independent rotation)."""
    truth = sim.truth
    t_true = truth.column("time").to_numpy()
    samples = sim.samples
    pos = samples.column("position").to_numpy(zero_copy_only=False)
    stn = samples.column("station").to_numpy(zero_copy_only=False)
    out = {"inc": [], "azi": [], "gtf": []}
    for s in stations.column("station").to_numpy():
        i = int(np.flatnonzero((stn == s) & (pos == 0))[-1])
        assert t_true[i] == samples.column("time")[i].as_py()
        a, inc, tf = (np.radians(truth.column(c)[i].as_py()) for c in ("azi", "inc", "toolface"))
        c_bn = Rotation.from_euler("ZYZ", [a, inc, tf]).as_matrix()
        north = c_bn.T @ np.array([1.0, 0.0, 0.0])
        out["inc"].append(np.degrees(inc))
        out["azi"].append(np.degrees(a))
        out["gtf"].append(np.degrees(np.arctan2(-north[1], north[0])) % 360)
    return {k: np.array(v) for k, v in out.items()}


def angle_error(a, b):
    return (np.asarray(a) - np.asarray(b) + 180.0) % 360.0 - 180.0


BIASED = {"bias": (3.0, -2.0, 0.0), "bias_trend": (1.5, -0.8, 0.0)}
TOOLS = {
    # single-axis gyro on a rotating frame, seed 004's five positions
    "x": (
        {"preset": "ideal", "overrides": {"gyro_axes": "x", "gyro": BIASED}},
        [0, 90, 180, 270, 0],
        CompassOptions(),
    ),
    # dynamically tuned XY gyro: ψ0, ψ0 + 180°, ψ0
    "xy": (
        {"preset": "ideal", "overrides": {"gyro_axes": "xy", "gyro": BIASED}},
        [0, 180, 0],
        CompassOptions(),
    ),
    # three-axis: x/y biases removed by the positions, z (bias-free here) joins the fit
    "xyz": (
        {"preset": "ideal", "overrides": {"gyro_axes": "xyz", "gyro": BIASED}},
        [0, 90, 180, 270, 0],
        CompassOptions(z_bias_sigma=0.01),
    ),
}


@pytest.mark.parametrize("axes", sorted(TOOLS))
@pytest.mark.parametrize("latitude", [0.0, 35.0, 61.25, 80.0])
def test_noise_free_recovery_over_the_grid(tmp_path: Path, axes: str, latitude: float):
    tool, positions, options = TOOLS[axes]
    sim, stations, rejects = run(
        grid_well(tmp_path, INCS, AZIS),
        latitude,
        tool,
        positions,
        options=options.model_copy(update={"noise_floor": 0.01}),
    )
    assert rejects.num_rows == 0
    inclined = stations.filter(pa.compute.equal(stations.column("mode"), "inclined"))
    inclined = inclined.filter(pa.compute.greater(inclined.column("inc"), 4.0))
    truth = truth_at(sim, inclined)
    np.testing.assert_allclose(inclined.column("inc").to_numpy(), truth["inc"], atol=1e-6)
    err = angle_error(inclined.column("azi").to_numpy(), truth["azi"])
    horizontal = np.abs(truth["inc"] - 90) < 6
    if axes == "xyz":  # the axial gyro resolves A ↔ 180° − A near horizontal
        assert np.abs(err).max() < 1e-6
    else:
        assert np.abs(err[~horizontal]).max() < 1e-6
    # the bias at the station's mid-time: 3 °/h plus 1.5 °/h per hour since the start
    hours = inclined.column("time").to_numpy() / 3600
    np.testing.assert_allclose(inclined.column("bias").to_numpy(), 3.0 + 1.5 * hours, atol=1e-6)
    np.testing.assert_allclose(inclined.column("trend").to_numpy(), 1.5, atol=1e-4)
    gtf = angle_error(inclined.column("gyro_toolface").to_numpy(), truth["gtf"])
    assert np.abs(gtf[~horizontal]).max() < 1e-6


def test_closed_form_agrees_with_least_squares_on_equal_steps():
    rng = np.random.default_rng(3)
    cases = []
    for _ in range(50):
        h, r, b, d = [*rng.normal(0, 10, 2).tolist(), rng.normal(0, 5), rng.normal(0, 0.01)]
        psi0 = rng.uniform(0, 2 * np.pi)
        alpha = psi0 + np.radians([0, 90, 180, 270, 360])
        t = 100.0 + np.arange(5) * 43.0
        y = h * np.cos(alpha) + r * np.sin(alpha) + b + d * (t - t.mean())
        cases.append((psi0, y, design(alpha, t, y[:, None], np.ones((5, 1)), 2)))
    fits = fit_all([problem for *_, problem in cases])  # the 50 stations fitted at once
    for (psi0, y, _), fit in zip(cases, fits, strict=True):
        assert isinstance(fit, Fit)
        w1, w2 = five_position_closed_form(y)
        u, v = fit.uv
        assert w1 == pytest.approx(u * np.cos(psi0) + v * np.sin(psi0), abs=1e-9)
        assert w2 == pytest.approx(-u * np.sin(psi0) + v * np.cos(psi0), abs=1e-9)


def test_noisy_errors_match_the_predicted_sigma(tmp_path: Path):
    """White gyro and accelerometer noise plus bias and trend: error / σ has unit spread."""
    noisy = {
        "preset": "ideal",
        "overrides": {
            "gyro_axes": "x",
            "gyro": {**BIASED, "noise_density": 0.004},
            "accelerometer": {"noise_density": 0.02},
        },
    }
    incs = [10, 25, 40, 55, 70, 110]
    azis = list(range(0, 360, 15))
    errors, incs_err = [], []
    for latitude, seed in (
        (20.0, 1),
        (45.0, 2),
        (61.25, 3),
        (70.0, 4),
        (30.0, 5),
        (55.0, 6),
        (10.0, 7),
    ):
        sim, stations, _ = run(
            grid_well(tmp_path, incs, azis), latitude, noisy, [0, 90, 180, 270, 0], seed=seed
        )
        inclined = stations.filter(pa.compute.greater(stations.column("inc"), 5.0))
        truth = truth_at(sim, inclined)
        errors.append(
            angle_error(inclined.column("azi").to_numpy(), truth["azi"])
            / inclined.column("sigma_azi").to_numpy()
        )
        incs_err.append(
            (inclined.column("inc").to_numpy() - truth["inc"])
            / inclined.column("sigma_inc").to_numpy()
        )
    z = np.concatenate(errors)
    zi = np.concatenate(incs_err)
    assert len(z) >= 1000
    assert 0.8 < z.std() < 1.2, z.std()
    assert abs(z.mean()) < 0.1
    assert 0.8 < zi.std() < 1.2, zi.std()


def test_near_vertical_toolface_and_the_mode_switch(tmp_path: Path):
    noisy = {
        "preset": "ideal",
        "overrides": {"gyro_axes": "x", "gyro": {**BIASED, "noise_density": 0.004}},
    }
    incs = [0.5, 1.0, 2.0, 2.9, 3.1, 4.0]
    azis = list(range(0, 360, 10))
    sim, stations, _ = run(
        grid_well(tmp_path, incs, azis),
        61.25,
        noisy,
        [0, 90, 180, 270, 0],
        options=CompassOptions(vertical_below=3.0),
    )
    stations = stations.filter(pa.compute.greater(stations.column("md"), 1.0))
    truth = truth_at(sim, stations)
    mode = np.array(stations.column("mode").to_pylist())
    assert set(mode[truth["inc"] < 2.95]) == {"near-vertical"}
    assert set(mode[truth["inc"] > 3.05]) == {"inclined"}
    nv = mode == "near-vertical"
    z = (
        angle_error(stations.column("gyro_toolface").to_numpy()[nv], truth["gtf"][nv])
        / (stations.column("sigma_toolface").to_numpy()[nv])
    )
    assert len(z) >= 100
    assert 0.7 < z.std() < 1.3, z.std()
    assert set(stations.column("solver").to_numpy()[nv]) == {"toolface"}


def test_single_position_three_axis_tool_uses_the_general_formula(tmp_path: Path):
    """One position, no frame turn: biases cannot be removed (flagged); with bias-free
    gyros the maximum-likelihood azimuth equals DOMAIN's general formula d × ω."""
    from pipeline.gyrocompass.solve import general_azimuth

    tool = {"preset": "ideal", "overrides": {"gyro_axes": "xyz"}}
    sim, stations, rejects = run(
        grid_well(tmp_path, [20, 60, 100], AZIS),
        61.25,
        tool,
        [0],
        options=CompassOptions(noise_floor=0.01, z_bias_sigma=0.01),
    )
    assert rejects.num_rows == 0
    inclined = stations.filter(pa.compute.equal(stations.column("mode"), "inclined"))
    assert all("bias_not_removed" in f for f in inclined.column("flags").to_pylist())
    truth = truth_at(sim, inclined)
    err = angle_error(inclined.column("azi").to_numpy(), truth["azi"])
    assert np.abs(err).max() < 1e-6
    samples = sim.samples.to_pandas()
    at_rest = samples[samples.position == 0].groupby("station").mean(numeric_only=True)
    for row in inclined.to_pylist():
        mean = at_rest.loc[row["station"]]
        a = general_azimuth(
            mean[["gyro_x", "gyro_y", "gyro_z"]].to_numpy(float),
            mean[["acc_x", "acc_y", "acc_z"]].to_numpy(float),
        )
        assert angle_error(np.degrees(a), row["azi"]) == pytest.approx(0.0, abs=1e-6)

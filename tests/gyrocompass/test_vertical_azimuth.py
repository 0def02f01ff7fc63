"""Azimuth at vertical (issue 18, item 1): where the measured horizontal gravity cannot tell
the high side, the azimuth is NaN, flagged ``azimuth_undefined``, σ undefined — and NaN
flows through minimum curvature, position uncertainty, every export and the report. Driven
through the Python API and the ``point-gyro`` pipeline on simulated wells with vertical
stations, noise-free and noisy."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml

import pipeline as gp
from pipeline.errors import InputFileError
from tests_support import EXAMPLE_SITE, simulate_and_run

SECTIONS = [
    {"kind": "vertical", "length": 60},
    {"kind": "build", "dls": 6.0, "inc": 20, "azi": 37},
    {"kind": "hold", "to_md": 180},
]
SURVEY = {"mode": "point", "every": 30, "dwell": 8, "move_time": 1.0, "speed": 10.0}
# noise-free accelerometers, a noisy single-axis gyro
NOISE_FREE = {"preset": "ideal", "overrides": {"gyro_axes": "x", "gyro": {"noise_density": 0.004}}}


def plan(tool: dict[str, Any], seed: int = 5) -> dict[str, Any]:
    return {
        "name": "vertical-top",
        "seed": seed,
        "site": EXAMPLE_SITE,
        "well": {"sections": SECTIONS},
        "tool": tool,
        "survey": SURVEY,
    }


def compassed(tool: dict[str, Any], seed: int = 5) -> tuple[Any, Any]:
    sim = gp.simulate(plan(tool, seed))
    return sim, gp.compass(gp.position_readings(sim.samples)).stations


def test_noise_free_vertical_stations_have_no_azimuth_whatever_the_run():
    for seed in (5, 6):  # the azimuth used to change from run to run (180°, 284.8°, …)
        _, st = compassed(NOISE_FREE, seed)
        vertical = st["inc"].to_numpy() < 1e-6
        assert vertical.sum() == 3  # 0, 30, 60 m
        assert np.isnan(st["azi"][vertical]).all()
        assert np.isnan(st["sigma_azi"][vertical]).all()
        assert np.isnan(st["highside_toolface"][vertical]).all()
        assert all(f == "azimuth_undefined" for f in st["flags"][vertical])
        # the gyro toolface stands: it needs no tilt
        assert np.isfinite(st["gyro_toolface"][vertical]).all()
        inclined = ~vertical
        assert np.isfinite(st["azi"][inclined]).all()
        assert not any("azimuth_undefined" in f for f in st["flags"][inclined])
        err = (st["azi"][inclined].to_numpy() - 37.0 + 180.0) % 360.0 - 180.0
        assert np.all(np.abs(err) < 4 * st["sigma_azi"][inclined].to_numpy())


def test_biased_accelerometers_at_vertical_are_undefined_and_a_small_tilt_is_not():
    """mems-vrg: 1–2 mg accelerometer biases read as a tilt of ~0.01° at I = 0 — one that
    turns with the frame, which its σ shows; at 1° the tilt is real and gives an azimuth."""
    _, st = compassed({"preset": "mems-vrg"})
    vertical = st["md"].to_numpy() <= 60.0
    assert all("azimuth_undefined" in f for f in st["flags"][vertical])
    assert np.isnan(st["azi"][vertical]).all()
    # the bias's apparent tilt has no direction: it does not walk the well off north
    traj = gp.minimum_curvature(st)
    assert (traj["north"][vertical] == 0.0).all() and (traj["east"][vertical] == 0.0).all()
    tilted = {
        **plan({"preset": "mems-vrg"}),
        "well": {
            "sections": [
                {"kind": "vertical", "length": 30},
                {"kind": "build", "dls": 1.0, "inc": 1.0, "azi": 120},
                {"kind": "hold", "to_md": 120},
            ]
        },
    }
    sim = gp.simulate(tilted)
    st = gp.compass(gp.position_readings(sim.samples)).stations
    at_one = st["md"].to_numpy() >= 60.0
    assert all("azimuth_from_toolface" in f for f in st["flags"][at_one])
    err = (st["azi"][at_one].to_numpy() - 120.0 + 180.0) % 360.0 - 180.0
    sigma = st["sigma_azi"][at_one].to_numpy()
    assert np.all(np.isfinite(sigma)) and np.all(np.abs(err) < 4 * sigma)


def test_minimum_curvature_and_uncertainty_take_any_azimuth_at_vertical():
    sim, st = compassed(NOISE_FREE)
    traj = gp.minimum_curvature(st)
    truth = sim.truth.set_index("time")
    vertical = np.isnan(st["azi"].to_numpy())
    for row, at, undefined in zip(traj.itertuples(), st["time"], vertical, strict=True):
        want = truth.iloc[np.argmin(np.abs(truth.index.to_numpy() - at))]
        if undefined:  # straight down: exactly under the wellhead
            assert row.north == 0.0 and row.east == 0.0
        else:  # within the azimuth noise (σ ≈ 0.5° over ≤ 25 m of departure)
            assert abs(row.north - want["north"]) < 0.6
            assert abs(row.east - want["east"]) < 0.6
    assert (
        np.isnan(traj["azi"][:3]).all() and np.isfinite(traj[["north", "east", "tvd"]]).all().all()
    )
    # interpolation on the same arcs: straight down, then leaving vertical towards 37°
    points = gp.interpolate(traj, md=[15.0, 45.0, 75.0])
    assert points["north"][:2].tolist() == [0.0, 0.0] and np.isnan(points["azi"][:2]).all()
    assert abs(points["azi"].iloc[2] - 37.0) < 2.0 and points["north"].iloc[2] > 0.0
    cov = gp.position_uncertainty(traj)
    assert np.isfinite(cov[["cov_nn", "cov_ee", "cov_vv", "ellipse_major"]]).all().all()
    assert (cov["cov_nn"].iloc[1:] > 0).all()


def test_minimum_curvature_leaving_vertical_follows_the_arc_of_the_next_azimuth():
    """One step from vertical (azimuth undefined) to I = 10°, A = 60° over 100 m: the
    circular arc in the vertical plane of 60°, R = ΔMD/I."""
    frame = pd.DataFrame(
        {"md": [0.0, 100.0, 200.0], "inc": [0.0, 0.0, 10.0], "azi": [np.nan, np.nan, 60.0]}
    )
    frame.attrs["north_reference"] = "true"
    traj = gp.minimum_curvature(frame)
    radius = 100.0 / np.radians(10.0)
    horizontal = radius * (1 - np.cos(np.radians(10.0)))
    assert traj["north"].iloc[2] == pytest.approx(horizontal * np.cos(np.radians(60.0)), abs=1e-9)
    assert traj["east"].iloc[2] == pytest.approx(horizontal * np.sin(np.radians(60.0)), abs=1e-9)
    assert traj["tvd"].iloc[2] == pytest.approx(100.0 + radius * np.sin(np.radians(10.0)), abs=1e-9)
    assert traj["north"].iloc[1] == 0.0 and traj["tvd"].iloc[1] == 100.0
    assert np.isnan(traj["azi"].iloc[0])
    for method in ("tangential", "balanced_tangential", "average_angle", "radius_of_curvature"):
        other = gp.survey_method(frame, method=method)
        assert other["north"].iloc[1] == 0.0 and np.isfinite(other["north"].iloc[2]), method


def test_point_gyro_pipeline_writes_and_reads_back_undefined_azimuths(tmp_path: Path):
    out = simulate_and_run(tmp_path, yaml.safe_dump(plan(NOISE_FREE)))
    stations = pq.read_table(out / "compass.stations.parquet")
    undefined = np.isnan(stations.column("azi").to_numpy())
    assert undefined.tolist() == [True] * 3 + [False] * (stations.num_rows - 3)
    # each format's null, read back as NaN: Parquet NaN, CSV empty cell, LAS NULL, no <azi>
    assert "\n0,0,,0," in (out / "trajectory.csv").read_text()
    for name in (
        "trajectory.csv",
        "trajectory.las",
        "trajectory.xml",
        "uncertainty.trajectory.parquet",
    ):
        back = gp.read(out / name, kind="stations")
        np.testing.assert_array_equal(np.isnan(back["azi"].to_numpy()), undefined, err_msg=name)
    text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", (out / "report.html").read_text()))
    listing = re.search(r"0\.00 0\.00 (\S+) 0\.00", text)
    assert listing is not None and listing.group(1) == "undefined"
    assert "azimuth undefined processing flag 3 The hole was vertical" in text


def test_a_missing_azimuth_is_refused_unless_the_station_is_vertical(tmp_path: Path):
    good = tmp_path / "good.csv"
    good.write_text("MD (m),Inc (deg),Azimuth True (deg)\n0,0,\n30,0.5,\n60,4,40\n")
    back = gp.read(good, kind="stations")
    assert np.isnan(back["azi"][:2]).all() and back["azi"][2] == 40.0
    bad = tmp_path / "bad.csv"
    bad.write_text("MD (m),Inc (deg),Azimuth True (deg)\n0,0,\n30,5,\n60,9,40\n")
    with pytest.raises(InputFileError) as caught:
        gp.read(bad, kind="stations")
    message = str(caught.value)
    assert "bad.csv:3" in message and "'azi'" in message and "vertical" in message

"""Magnetometer diagnosis against the simulator: a bias on one axis is named with its
estimate within its σ; a field fixed in the Earth frame (over the survey, or changing with
depth like casing magnetisation) is interference, not an axis; a clean tool has no suspect."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from qc_support import MAGNETIC, SITE, point_run, random_well

from pipeline.earth.site import Site
from pipeline.qc.engine import station_checks
from pipeline.qc.vector_checks import MAGNETIC_NOTE

TOOL = {  # white noise only: gyros, accelerometers and magnetometers (14 nT per sample)
    "sample_rate": 50,
    "gyro": {"noise_density": 0.003},
    "accelerometer": {"noise_density": 0.01},
    "magnetometer": {"noise_density": 2.0},
}
BIAS = 800.0  # nT
ESTIMATE = re.compile(r"bias ≈ ([+-][\d.]+) ± ([\d.e+-]+) nT")
OFFSETS = re.compile(r"\|B\| ([+-]\d+) nT and dip ([+-][\d.]+)°")


def magnetic_failures(qc: pa.Table) -> pa.Table:
    rows = qc.filter(pc.is_in(qc.column("check"), pa.array(["magnetic_field", "magnetic_dip"])))
    return rows.filter(pc.invert(rows.column("passed")))


def failing(summary: pa.Table) -> list[dict]:
    return [r for r in summary.to_pylist() if "magnetic" in r["failed_checks"]]


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_a_magnetometer_bias_is_named_with_its_axis_and_estimate(tmp_path: Path, axis: str):
    bias = [BIAS if a == axis else 0.0 for a in "xyz"]
    tool = {**TOOL, "magnetometer": {**TOOL["magnetometer"], "bias": bias}}
    sim, readings, site = point_run(random_well(tmp_path / "w.csv", 12, seed=5), tool)
    qc, summary = station_checks(readings, site, samples=sim.samples)
    stations = failing(summary)
    assert len(stations) >= 6  # 800 nT fails |B| or dip (300 nT, 0.25°) at most stations
    assert {r["suspect"] for r in stations} == {f"mag {axis}"}
    estimate, sigma = map(float, ESTIMATE.search(stations[0]["diagnosis"]).groups())
    assert 0 < sigma < 20.0 and abs(estimate - BIAS) <= 3 * sigma
    rows = magnetic_failures(qc)
    assert set(rows.column("suspect").to_pylist()) == {f"mag {axis}"}
    assert not any(MAGNETIC_NOTE in d for d in rows.column("detail").to_pylist())


def test_a_field_fixed_in_the_earth_frame_is_interference_not_an_axis(tmp_path: Path):
    """Simulated in a field 600 nT stronger and 0.5° steeper than the reference the checks
    use: every position and station sees the same offset."""
    disturbed = {**MAGNETIC, "total_field": MAGNETIC["total_field"] + 600, "dip": 78.79}
    sim, readings, _ = point_run(
        random_well(tmp_path / "w.csv", 12, seed=5), TOOL, site={**SITE, "magnetic": disturbed}
    )
    _, summary = station_checks(readings, Site.model_validate(SITE), samples=sim.samples)
    stations = failing(summary)
    assert len(stations) == 13
    assert {r["suspect"] for r in stations} == {"interference"}
    for r in stations:  # the offsets, to the readings' noise (1.6 nT, 0.002° per mean)
        field, dip = map(float, OFFSETS.search(r["diagnosis"]).groups())
        assert abs(field - 600) <= 5 and abs(dip - 0.5) <= 0.02


def test_casing_magnetisation_changing_with_depth_is_interference(tmp_path: Path):
    """A field along the hole axis (fixed in the Earth frame at each depth) whose strength
    changes with depth: the positions of a station agree, no single axis bias fits."""
    sim, readings, site = point_run(random_well(tmp_path / "w.csv", 12, seed=5), TOOL)
    samples = sim.samples
    md = samples.column("md").to_numpy()
    axial = 1500.0 * np.sin(md / 40.0)  # nT, stations 30 m apart: strength and sign change
    mag_z = samples.column("mag_z").to_numpy() + axial
    i = samples.schema.get_field_index("mag_z")
    samples = samples.set_column(i, samples.schema.field("mag_z"), pa.array(mag_z))
    qc, summary = station_checks(readings, site, samples=samples)
    stations = failing(summary)
    assert len(stations) >= 6
    assert {r["suspect"] for r in stations} == {"interference"}
    assert not any(s.startswith("mag") for s in magnetic_failures(qc).column("suspect").to_pylist())


def test_a_clean_tool_has_no_suspect(tmp_path: Path):
    sim, readings, site = point_run(random_well(tmp_path / "w.csv", 12, seed=5), TOOL)
    qc, summary = station_checks(readings, site, samples=sim.samples)
    assert magnetic_failures(qc).num_rows == 0
    assert set(summary.column("suspect").to_pylist()) == {""}
    assert set(summary.column("diagnosis").to_pylist()) == {""}

"""The σ of a magnetometer bias the diagnosis estimates covers the tool's accelerometer
errors (issue 29 item 8): simulated tools with their catalogue errors (the well's
tool_preset) and 800 nT injected on one magnetometer axis, through the public API
(simulate → position_readings → validity_checks). The dip the bias is fitted against is
measured with the accelerometers, so their bias, misalignment and scale factor leak into
the estimate alike at every reading: the scatter alone (the σ before; stations every 30 m)
put a mems-vrg's y estimate of +781.1 nT 43 σ from 800 nT. Every axis, both signs, two presets and several
seeds: benchmarks/study_magnetic_sigma.py (mems-vrg, dtg-xy and nav-grade, |z| ≤ 1.35)."""

from __future__ import annotations

import re

import pytest

import pipeline as gp
from tests_support import ROOT

WELL = ROOT / "examples" / "stations-j-well.csv"
SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
BIAS = 800.0  # nT
ESTIMATE = re.compile(r"mag ([xyz]): bias ≈ ([+-][\d.]+) ± ([\d.e+-]+) nT")


def estimate(preset: str, axis: str, bias: float, seed: int, **params: float) -> tuple:
    """(axis named, estimate nT, stated σ nT) of a simulated point survey of the j-well
    (every 60 m) by ``preset`` with ``bias`` on magnetometer ``axis``."""
    plan = {
        "name": "magnetic-sigma",
        "seed": seed,
        "site": SITE,
        "well": {"stations": str(WELL)},
        "tool": {
            "preset": preset,
            "overrides": {
                "magnetometer": {
                    "noise_density": 2.0,
                    "bias": [bias if a == axis else 0.0 for a in "xyz"],
                }
            },
        },
        "survey": {
            "mode": "point",
            "every": 60,
            "dwell": 2.0,
            "move_time": 1.0,
            "settle_time": 0.5,
            "speed": 30.0,
            "positions": [0, 90, 180, 270, 0],
        },
    }
    sim = gp.simulate(plan)
    readings = gp.position_readings(sim.samples, trim_start=0.5, min_dwell=1.0)
    summary = gp.validity_checks(readings, samples=sim.samples, **params).summary
    rows = zip(summary["diagnosis"], summary["failed_checks"], strict=True)
    failed = [d for d, f in rows if "magnetic" in f]
    found = {m.groups() for d in failed if (m := ESTIMATE.search(d))}
    assert len(failed) >= 10 and len(found) == 1, found  # one estimate, at every failing station
    named, value, sigma = found.pop()
    return named, float(value), float(sigma)


@pytest.mark.parametrize(
    ("preset", "axis", "sign", "seed"),
    [
        ("mems-vrg", "x", 1, 1),
        ("mems-vrg", "y", 1, 2),
        ("mems-vrg", "z", -1, 3),
        ("dtg-xy", "x", -1, 4),
        ("dtg-xy", "y", -1, 5),
        ("dtg-xy", "z", 1, 6),
    ],
)
def test_an_injected_bias_is_within_three_of_its_stated_sigma(
    preset: str, axis: str, sign: int, seed: int
) -> None:
    named, value, sigma = estimate(preset, axis, sign * BIAS, seed)
    assert named == axis
    assert abs(value - sign * BIAS) <= 3 * sigma, (value, sigma)
    assert sigma < 30.0  # nT: the accelerometers' share, not a σ that covers anything


def test_without_the_accelerometer_errors_the_sigma_is_too_small() -> None:
    """The same survey with the accelerometer magnitudes set to zero: the scatter alone."""
    exact = {"acc_bias": 0.0, "acc_misalignment": 0.0, "acc_scale_factor": 0.0}
    _, value, sigma = estimate("mems-vrg", "y", BIAS, 2, **exact)
    assert abs(value - BIAS) > 10 * sigma, (value, sigma)

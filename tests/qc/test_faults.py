"""Fault isolation against the simulator: a fault injected on one sensor is named at the
stations where it exceeds twice its tolerance (rate measured over many stations and
printed), its size is estimated, and where the geometry cannot tell the answer is
'undetermined'."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest
from qc_support import random_well

from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.qc.engine import ISOLATED, station_checks
from pipeline.qc.options import QcOptions, Tolerance
from pipeline.qc.sensors import readings_sensors
from pipeline.qc.vector_checks import VECTOR_CHECKS
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from tests_support import read_stations

SITE = {"latitude": 61.25, "longitude": 73.4, "date": "2026-11-21"}
TRIM = ReadingOptions(trim_start=0.5, min_dwell=1.0)
NOISE = {
    "sample_rate": 50,
    "gyro": {"noise_density": 0.003},
    "accelerometer": {"noise_density": 0.01},
}


def run(
    tmp_path: Path,
    fault: dict[str, Any],
    *,
    n=200,
    positions=(0, 90, 180, 270, 0),
    inc=(5.0, 120.0),
    noise: dict[str, Any] | None = None,
    options: QcOptions | None = None,
    seed=3,
):
    """Simulate a faulty three-axis white-noise tool; return readings, QC rows, summary."""
    tool = {k: dict(v) if isinstance(v, dict) else v for k, v in (noise or NOISE).items()}
    for sensor, errors in fault.items():
        tool[sensor] = {**tool[sensor], **errors}
    spec = SimulationSpec.model_validate(
        {
            "name": "faults",
            "seed": seed,
            "site": SITE,
            "well": {"stations": str(random_well(tmp_path / "w.csv", n, seed, inc))},
            "tool": {"preset": "ideal", "overrides": {**tool, "magnetometer": None}},
            "survey": {
                "mode": "point",
                "every": 30,
                "dwell": 2.0,
                "move_time": 1.0,
                "settle_time": 0.5,
                "speed": 30.0,
                "positions": list(positions),
            },
        }
    )
    spec.well.load(read_stations)
    readings = position_readings(simulate(spec).samples, TRIM)
    qc, summary = station_checks(readings, spec.site, options or QcOptions())
    return readings, qc, summary


def exceeding(readings: pa.Table, qc: pa.Table, undo) -> np.ndarray:
    """Stations where the injected fault changes some gyro/accelerometer check by more than
    twice its tolerance: ``undo(ω, g)`` gives the fault-free readings."""
    sensors = readings_sensors(readings)
    clean_w, clean_g = undo(sensors.gyro.copy(), sensors.acc.copy())
    ratio = np.zeros(readings.num_rows)
    for name in ISOLATED:
        spec = VECTOR_CHECKS[name]
        rows = qc.filter(pc.equal(qc.column("check"), name))

        def value(w, g, spec=spec):
            return spec.func(*[w if s == "gyro" else g for s in spec.sensors])

        effect = value(sensors.gyro, sensors.acc) - value(clean_w, clean_g)
        ratio = np.maximum(ratio, np.abs(effect) / rows.column("tolerance").to_numpy())
    station = readings.column("station").to_numpy()
    return np.unique(station[ratio > 2.0])


def verdicts(summary: pa.Table, stations: np.ndarray) -> tuple[list[str], list[str]]:
    at = summary.filter(pc.is_in(summary.column("station"), pa.array(stations)))
    return at.column("suspect").to_pylist(), at.column("diagnosis").to_pylist()


def rate_report(what: str, suspects: list[str], expected: str) -> tuple[float, float]:
    right = sum(s == expected for s in suspects) / len(suspects)
    wrong = sum(s not in (expected, "undetermined") for s in suspects) / len(suspects)
    undetermined = sum(s == "undetermined" for s in suspects) / len(suspects)
    print(
        f"{what}: {len(suspects)} stations, named {right:.3f}, undetermined "
        f"{undetermined:.3f}, wrong {wrong:.3f}"
    )
    return right, wrong


def estimates(diagnoses: list[str], unit: str) -> np.ndarray:
    pattern = re.compile(r"≈ ([+-][0-9.]+) " + re.escape(unit))
    return np.array([float(m.group(1)) for d in diagnoses if (m := pattern.search(d))])


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_gyro_bias_on_one_axis_is_named(tmp_path: Path, axis: int):
    bias = [0.0, 0.0, 0.0]
    bias[axis] = 2.0  # °/h; default tolerances ≈ 0.67 °/h for this noise
    readings, qc, summary = run(tmp_path, {"gyro": {"bias": bias}})

    def undo(w, g):
        w[:, axis] -= 2.0
        return w, g

    stations = exceeding(readings, qc, undo)
    assert len(stations) >= 150
    suspects, diagnoses = verdicts(summary, stations)
    sensor = f"gyro {'xyz'[axis]}"
    right, wrong = rate_report(f"{sensor} bias 2 °/h", suspects, sensor)
    assert right >= 0.9 and wrong <= 0.02
    named = [d for s, d in zip(suspects, diagnoses, strict=True) if s == sensor]
    found = estimates(named, "°/h")
    assert len(found) >= 0.9 * len(named)
    assert abs(np.median(found) - 2.0) < 0.1


@pytest.mark.parametrize(
    ("fault", "sensor", "undo"),
    [
        ({"scale_factor": [10000, 0, 0]}, "acc x", lambda g: g[:, 0] / 1.01),
        ({"scale_factor": [0, 0, 10000]}, "acc z", lambda g: g[:, 2] / 1.01),
        ({"bias": [0, 0.05, 0]}, "acc y", lambda g: g[:, 1] - 0.05),
    ],
)
def test_accelerometer_scale_or_bias_on_one_axis_is_named(tmp_path: Path, fault, sensor, undo):
    readings, qc, summary = run(tmp_path, {"accelerometer": fault})
    axis = "xyz".index(sensor[-1])

    def clean(w, g):
        g[:, axis] = undo(g)
        return w, g

    stations = exceeding(readings, qc, clean)
    assert len(stations) >= 80
    suspects, diagnoses = verdicts(summary, stations)
    right, wrong = rate_report(f"{sensor} {fault}", suspects, sensor)
    assert right >= 0.9 and wrong <= 0.02
    if "scale_factor" in fault:
        found = estimates(
            [d for s, d in zip(suspects, diagnoses, strict=True) if s == sensor], "ppm"
        )
        assert abs(np.median(found) - 10000) < 500


def test_misaligned_triads_are_measured_but_not_attributed(tmp_path: Path):
    """A rotation of the gyro triad shows only in the angle between ω and g: the diagnosis
    names the rotation (≈ 50 mrad) and says the triad cannot be told — 'undetermined'."""
    quiet = {**NOISE, "gyro": {"noise_density": 0.001}}
    rotation = [[0, 0, 0], [0, 0, -50], [0, 50, 0]]  # 50 mrad about x
    options = QcOptions(**{name: Tolerance(sigma=3) for name in ISOLATED})
    readings, qc, summary = run(
        tmp_path, {"gyro": {"misalignment": rotation}}, noise=quiet, options=options
    )

    def undo(w, g):
        return w @ np.linalg.inv(np.eye(3) + np.array(rotation) * 1e-3).T, g

    stations = exceeding(readings, qc, undo)
    assert len(stations) >= 150
    suspects, diagnoses = verdicts(summary, stations)
    triads = [d for d in diagnoses if d.startswith("gyro triad rotated")]
    rate = len(triads) / len(stations)
    print(f"gyro triad rotated 50 mrad: {len(stations)} stations, diagnosed {rate:.3f}")
    assert rate >= 0.9
    assert set(suspects) == {"undetermined"}
    found = estimates([d.replace("by ≈ ", "≈ +") for d in triads], "mrad")
    assert abs(np.median(found) - 50) < 5


def test_one_position_at_random_attitudes_names_less_but_never_wrongly(tmp_path: Path):
    """One frame position: fewer equations than with the frame turned, so more stations are
    'undetermined' — but a named sensor is the right one."""
    readings, qc, summary = run(tmp_path, {"gyro": {"bias": [0, 2.0, 0]}}, positions=(0,))

    def undo(w, g):
        w[:, 1] -= 2.0
        return w, g

    stations = exceeding(readings, qc, undo)
    suspects, _ = verdicts(summary, stations)
    right, wrong = rate_report("gyro y bias 2 °/h, one position", suspects, "gyro y")
    assert wrong <= 0.02
    assert 0.1 < right < 0.9  # both outcomes occur: the attitude decides


def test_symmetric_geometry_cannot_tell_x_from_y(tmp_path: Path):
    """Vertical tool, one position, north halfway between x and y (housing roll −45°, no
    torsion): the checks see only |ω_h| and ω_v, and a bias on y restores them as well as
    the true one on x (with another size). Always 'undetermined', naming both."""
    spec = SimulationSpec.model_validate(
        {
            "name": "symmetric",
            "seed": 4,
            "site": SITE,
            "well": {"sections": [{"kind": "vertical", "length": 600}]},
            "tool": {
                "preset": "ideal",
                "overrides": {
                    **NOISE,
                    "magnetometer": None,
                    "gyro": {"noise_density": 0.003, "bias": [2.0, 0, 0]},
                },
            },
            "survey": {
                "mode": "point",
                "every": 30,
                "dwell": 2.0,
                "move_time": 1.0,
                "positions": [0],
                "start_roll": -45.0,
                "torsion": {"spin_sigma": 0.0, "oscillation": 0.0},
            },
        }
    )
    readings = position_readings(simulate(spec).samples, TRIM)
    sensors = readings_sensors(readings)
    np.testing.assert_allclose(sensors.gyro[:, 0] - 2.0, sensors.gyro[:, 1], atol=0.6)
    _, summary = station_checks(readings, spec.site)
    assert summary.num_rows == 21
    assert set(summary.column("suspect").to_pylist()) == {"undetermined"}
    for diagnosis in summary.column("diagnosis").to_pylist():
        assert "gyro x: bias ≈ +" in diagnosis and "gyro y: bias ≈ +" in diagnosis
        assert "cannot tell them apart" in diagnosis

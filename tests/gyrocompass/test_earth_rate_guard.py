"""Compassing refuses an Earth rate that is not the Earth's.

Gyro rates in rad/s or deg/s taken for °/h used to compass to azimuths near 180° with a σ of
1e-5° and no flag. Now the horizontal Earth rate the position fit finds must be Ω cos φ
(and, with the axial gyro in the fit, the vertical one Ω sin φ) within the tolerance; a
station outside is rejected with the ratio and a hint, and when most stations fail, the
record's units are wrong and every station goes. Good data, a large bias (removed by the
fit) and a three-axis tool are solved as before.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from pipeline.gyrocompass.azimuth import model
from pipeline.gyrocompass.earth_rate import HINT, EarthRate, earth_rate_check
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.precision import OMEGA_DEG_H
from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.gyrocompass.solve import compass
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from tests_support import ROOT, gyropipe_cli

LATITUDE = 61.25
K = OMEGA_DEG_H * np.cos(np.radians(LATITUDE))  # 7.23 °/h
UNITS = {"rad/s": np.radians(1.0) / 3600.0, "deg/s": 1.0 / 3600.0}
"""What a record in each unit, taken for °/h, reads instead of 1 °/h."""
PLAN: dict[str, Any] = {
    "name": "short-j",
    "seed": 11,
    "site": {
        "latitude": LATITUDE,
        "longitude": 73.4,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
    },
    "well": {
        "sections": [
            {"kind": "vertical", "length": 60},
            {"kind": "build", "dls": 9.0, "inc": 40, "azi": 37},
            {"kind": "hold", "length": 60},
        ]
    },
    "tool": {"preset": "mems-vrg"},
    "survey": {"mode": "point", "every": 30, "dwell": 20, "move_time": 2},
}
"""Stations at I = 0, 0, 0, 9, 18, 27, 36, 40, 40° (azimuth 37°): the one at 27° is near
the geometry (I = 90° − φ, A = 180°) where a transverse gyro sees almost no Earth rate."""
TRIM = ReadingOptions(trim_start=1.0)
RATIO = re.compile(r"fitted horizontal Earth rate \S+ °/h is (\S+)× the expected 7\.23 °/h")


def samples_of(tool: dict[str, Any]) -> pa.Table:
    return simulate(SimulationSpec.model_validate({**PLAN, "tool": tool})).samples


@pytest.fixture(scope="module")
def mems() -> pa.Table:
    return samples_of({"preset": "mems-vrg"})


def in_unit(samples: pa.Table, factor: float) -> pa.Table:
    """The samples with every gyro column multiplied by ``factor``, still labelled °/h: a
    record in another unit that a reader took for °/h."""
    for name in samples.column_names:
        if name.startswith("gyro_"):
            i = samples.schema.get_field_index(name)
            scaled = pc.multiply(samples.column(name), factor)
            samples = samples.set_column(i, samples.schema.field(name), scaled)
    return samples


def solve(samples: pa.Table, **options: Any) -> tuple[pa.Table, pa.Table]:
    return compass(position_readings(samples, TRIM), LATITUDE, CompassOptions(**options))


def azimuth_error(stations: pa.Table, truth: float = 37.0) -> np.ndarray:
    return (stations.column("azi").to_numpy() - truth + 180.0) % 360.0 - 180.0


def test_rates_in_deg_per_hour_are_solved(mems: pa.Table):
    stations, rejects = solve(mems)
    assert rejects.num_rows == 0
    assert stations.num_rows == 9
    inclined = stations.filter(pc.greater(stations.column("inc"), 5.0))
    sigma = inclined.column("sigma_azi").to_numpy()
    assert np.all(np.abs(azimuth_error(inclined)) < 4 * sigma)


@pytest.mark.parametrize("unit", sorted(UNITS))
def test_rates_in_another_unit_reject_every_station(mems: pa.Table, unit: str):
    stations, rejects = solve(in_unit(mems, UNITS[unit]))
    assert stations.num_rows == 0, "no azimuth may come out of a units mistake"
    assert rejects.column("station").to_pylist() == list(range(9))
    reasons = rejects.column("reason").to_pylist()
    assert all(f"{HINT} (they look like {unit})" in reason for reason in reasons), reasons
    ratios = [float(RATIO.search(reason).group(1)) for reason in reasons]  # type: ignore[union-attr]
    # near vertical the fit sees the rates as they are: the unit's factor (noise aside)
    assert all(0.2 * UNITS[unit] < r < 5 * UNITS[unit] for r in ratios[:3]), ratios
    # inclined, the vertical share subtracted leaves Ω sin φ tan I: 0.29× at 9°, 1.5× at 40°
    assert ratios[3] == pytest.approx(np.tan(np.radians(LATITUDE)) * np.tan(np.radians(9)), 0.1)
    # at 27° that is 0.93×, inside the tolerance: rejected with the record, not on its own
    assert ", but the Earth rate is implausible at 8 of 9 stations" in reasons[5]


@pytest.fixture(scope="module")
def xyz() -> pa.Table:
    """A three-axis tool: white gyro noise, transverse biases (the axial one is known to
    0.05 °/h: ``z_bias_sigma``)."""
    gyro = {"noise_density": 0.004, "bias": (3, -2, 0)}
    return samples_of({"preset": "ideal", "overrides": {"gyro_axes": "xyz", "gyro": gyro}})


def test_a_three_axis_tool_checks_both_components_at_every_station(xyz: pa.Table):
    samples = xyz
    stations, rejects = solve(samples, z_bias_sigma=0.05)
    assert rejects.num_rows == 0
    assert np.abs(azimuth_error(stations.filter(pc.greater(stations.column("inc"), 5.0)))).max() < 1
    _, rejects = solve(in_unit(samples, UNITS["rad/s"]), z_bias_sigma=0.05)
    reasons = rejects.column("reason").to_pylist()
    assert len(reasons) == 9
    assert not [r for r in reasons if "implausible at" in r], "each station fails on its own"
    inclined = reasons[3:]
    expected_up = OMEGA_DEG_H * np.sin(np.radians(LATITUDE))
    assert all("vertical Earth rate" in r and f"{expected_up:.2f} °/h" in r for r in inclined)
    assert all("(they look like rad/s)" in r for r in inclined), inclined


def test_a_large_bias_is_removed_and_solved():
    """A turn-on bias of 60 °/h (8× the horizontal Earth rate) drifting 10 °/h per hour: the
    multi-position fit removes it, the Earth rate left is the Earth's."""
    tool = {"preset": "mems-vrg", "overrides": {"gyro": {"bias": (60, 60, 60)}}}
    tool["overrides"]["gyro"]["bias_trend"] = (10, 10, 10)
    stations, rejects = solve(samples_of(tool))
    assert rejects.num_rows == 0
    hours = stations.column("time").to_numpy() / 3600
    np.testing.assert_allclose(stations.column("bias").to_numpy(), 60 + 10 * hours, atol=1.0)
    inclined = stations.filter(pc.greater(stations.column("inc"), 5.0))
    sigma = inclined.column("sigma_azi").to_numpy()
    assert np.all(np.abs(azimuth_error(inclined)) < 4 * sigma)


def test_the_tolerance_is_an_option(xyz: pa.Table):
    """Gyros reading 1.3× the true rate (a scale-factor error) are refused by default and
    accepted with a wider tolerance."""
    strong = in_unit(xyz, 1.3)
    _, rejects = solve(strong, z_bias_sigma=0.05)
    reasons = rejects.column("reason").to_pylist()
    assert len(reasons) == 9 and all(HINT in r for r in reasons)
    assert "is 1.3× the expected 7.23 °/h at 61.25° N" in reasons[0]
    assert "fitted vertical Earth rate 17 °/h is 1.3× the expected 13.19 °/h" in reasons[-1]
    stations, rejects = solve(strong, z_bias_sigma=0.05, earth_rate_tolerance=0.4)
    assert rejects.num_rows == 0 and stations.num_rows == 9


def test_one_bad_station_does_not_take_the_others(mems: pa.Table):
    stations = mems.column("station").to_numpy(zero_copy_only=False)
    gyro = mems.column("gyro_x").to_numpy().copy()
    gyro[stations == 7] *= UNITS["rad/s"]  # a dead gyro at one station
    i = mems.schema.get_field_index("gyro_x")
    solved, rejects = solve(mems.set_column(i, mems.schema.field("gyro_x"), pa.array(gyro)))
    assert rejects.column("station").to_pylist() == [7]
    assert solved.num_rows == 8


@pytest.mark.parametrize("latitude", [-70.0, 0.0, 35.0, 61.25, 80.0])
def test_earth_rate_check_finds_the_earths_rate_in_noise_free_components(latitude: float):
    rng = np.random.default_rng(7)
    lat = np.radians(latitude)
    k, up = OMEGA_DEG_H * np.cos(lat), OMEGA_DEG_H * np.sin(lat)
    for _ in range(50):
        azimuth, inc = rng.uniform(0, 2 * np.pi), np.radians(rng.uniform(5, 175))
        for m in (2, 3):
            obs = model(np.array(azimuth), np.array(inc), lat, m)
            checks = earth_rate_check(obs, np.eye(m) * 1e-4, inc, lat, 0.2)
            assert [c.component for c in checks] == ["horizontal", "vertical"][: m - 1]
            assert checks[0].fitted == pytest.approx(k, abs=1e-9)
            assert all(c.ok for c in checks)
            if m == 3:
                assert checks[1].fitted == pytest.approx(up, abs=1e-9)
    toolface = rng.uniform(0, 2 * np.pi)
    north = k * np.array([np.cos(toolface), -np.sin(toolface)])
    (check,) = earth_rate_check(north, np.eye(2) * 1e-4, 0.01, lat, 0.2, near_vertical=True)
    assert check.fitted == pytest.approx(k) and check.ok


def test_a_fit_near_horizontal_within_its_noise_of_the_earths_rate_passes():
    """At 88°, A = 0°, σ 0.23 °/h: a fit 2.1 σ from the Earth's own (h, r), its along-hole
    share ((h − Ω sin φ sin I)/cos I, σ 6.6 °/h) at zero, was rejected as 0.058× the Earth
    rate (are the gyro rates in °/h?): the first-order σ of |(along, r)| at the fit saw only
    r's. Rates in rad/s at the same geometry are still refused."""
    lat, inc = np.radians(LATITUDE), np.radians(88.0)
    up = OMEGA_DEG_H * np.sin(lat)
    truth = model(np.array(0.0), np.array(inc), lat, 2)
    fit = np.array([up * np.sin(inc), 0.42])  # along = 0
    cov = np.eye(2) * 0.23**2
    assert np.sqrt((fit - truth) @ np.linalg.inv(cov) @ (fit - truth)) < 2.2
    (check,) = earth_rate_check(fit, cov, inc, lat, 0.2)
    assert check.ok and check.ratio < 0.06
    (wrong,) = earth_rate_check(truth * UNITS["rad/s"], cov, inc, lat, 0.2)
    assert not wrong.ok


def test_the_reason_names_the_ratio_and_the_unit():
    check = EarthRate("horizontal", 0.000035, K, 0.2 * K)
    assert not check.ok
    assert check.describe(61.25) == (
        "fitted horizontal Earth rate 0.000035 °/h is 0.0000048× the expected 7.23 °/h at 61.25° N"
    )
    assert check.looks_like() == "they look like rad/s"
    assert EarthRate("horizontal", K * 3600, K, 1).looks_like() == (
        "they look like °/h converted as if they were deg/s"
    )
    assert EarthRate("horizontal", 3.0, K, 1).looks_like() == ""


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A simulated run written by the CLI (samples with the site in their well metadata)."""
    root = tmp_path_factory.mktemp("sim")
    (root / "plan.yaml").write_text(
        "name: short-j\nseed: 11\nsite: {latitude: 61.25, longitude: 73.4, date: 2026-11-21}\n"
        "well:\n  sections:\n    - {kind: vertical, length: 60}\n"
        "    - {kind: build, dls: 9.0, inc: 40, azi: 37}\n    - {kind: hold, length: 60}\n"
        "tool: {preset: mems-vrg}\nsurvey: {mode: point, every: 30, dwell: 20, move_time: 2}\n"
    )
    gyropipe_cli("simulate", str(root / "plan.yaml"), "--out", str(root), check=True)
    return root


@pytest.mark.parametrize("unit", sorted(UNITS))
def test_the_point_gyro_pipeline_stops_on_a_units_mistake(
    simulated: Path, tmp_path: Path, unit: str
):
    samples = tmp_path / "samples.parquet"
    pq.write_table(in_unit(pq.read_table(simulated / "samples.parquet"), UNITS[unit]), samples)
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run",
        str(ROOT / "pipelines" / "point-gyro.yaml"),
        "--input",
        str(samples),
        "--out",
        str(out),
    )
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Traceback" not in result.stderr
    assert "stage 'compass'" in result.stderr
    assert "compass rejected all 9 stations, so its stations table would have no rows: " in (
        result.stderr
    )
    assert f"{HINT} (they look like {unit})" in result.stderr
    assert not (out / "compass.stations.parquet").exists()
    assert not (out / "run.json").exists()

"""Compassing through the public interface: pipelines from raw samples and from
pre-averaged readings, and the bad inputs that must be rejected or flagged."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.solve import compass
from pipeline.tables import PositionReadings
from tests_support import ROOT, gyropipe_cli

PLAN = """
name: short-j
seed: 11
site: {latitude: 61.25, longitude: 73.4, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 60}
    - {kind: build, dls: 9.0, inc: 40, azi: 37}
    - {kind: hold, length: 60}
tool: {preset: mems-vrg}
survey: {mode: point, every: 30, dwell: 20, move_time: 2}
"""


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("sim")
    (root / "plan.yaml").write_text(PLAN)
    gyropipe_cli("simulate", str(root / "plan.yaml"), "--out", str(root), check=True)
    return root


def run(pipeline: str, input_file: Path, out: Path, *extra: str):
    return gyropipe_cli(
        "run",
        str(ROOT / "pipelines" / pipeline),
        "--input",
        str(input_file),
        "--out",
        str(out),
        *extra,
    )


def test_point_gyro_pipeline_from_raw_samples(simulated: Path, tmp_path: Path):
    result = run("point-gyro.yaml", simulated / "samples.parquet", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    stations = pq.read_table(tmp_path / "out" / "compass.stations.parquet")
    truth = pq.read_table(simulated / "stations.parquet")
    assert stations.num_rows == truth.num_rows
    inclined = np.array(stations.column("mode").to_pylist()) == "inclined"
    assert inclined.sum() >= 5
    err = (stations.column("azi").to_numpy() - truth.column("azi").to_numpy() + 180) % 360 - 180
    sigma = stations.column("sigma_azi").to_numpy()
    assert np.all(np.abs(err[inclined]) < 4 * sigma[inclined])
    np.testing.assert_allclose(
        stations.column("inc").to_numpy(), truth.column("inc").to_numpy(), atol=0.05
    )
    trajectory = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet")
    assert trajectory.schema.field("azi").metadata[b"north_reference"] == b"true"
    manifest = json.loads((tmp_path / "out" / "run.json").read_text())
    assert manifest["well"]["latitude"] == 61.25


def test_pipeline_from_pre_averaged_readings(simulated: Path, tmp_path: Path):
    first = run("point-gyro.yaml", simulated / "samples.parquet", tmp_path / "a")
    assert first.returncode == 0, first.stderr
    readings = tmp_path / "a" / "readings.readings.parquet"
    second = run("point-gyro-readings.yaml", readings, tmp_path / "b")
    assert second.returncode == 0, second.stderr
    a = pq.read_table(tmp_path / "a" / "compass.stations.parquet")
    b = pq.read_table(tmp_path / "b" / "compass.stations.parquet")
    np.testing.assert_allclose(a.column("azi").to_numpy(), b.column("azi").to_numpy())


def test_a_near_vertical_station_without_a_frame_angle_is_rejected_alone(
    simulated: Path, tmp_path: Path
):
    """A frame-angle sensor's dropout (a null frame angle) at one position of a near-vertical
    station, whose fit the frame angle references: that station is rejected, saying why, and
    the run goes on (it stopped with "SVD did not converge")."""
    first = run("point-gyro.yaml", simulated / "samples.parquet", tmp_path / "a")
    assert first.returncode == 0, first.stderr
    readings = pq.read_table(tmp_path / "a" / "readings.readings.parquet")
    solved = pq.read_table(tmp_path / "a" / "compass.stations.parquet")
    vertical = solved.column("station")[0].as_py()
    assert solved.column("inc")[0].as_py() < 3.0  # near vertical (vertical_below: 3°)
    frame = readings.column("frame_angle").to_pylist()
    frame[readings.column("station").to_pylist().index(vertical) + 1] = None
    index = readings.schema.get_field_index("frame_angle")
    dropped = readings.set_column(index, readings.schema.field(index), pa.array(frame))
    pq.write_table(dropped, tmp_path / "dropout.parquet")
    result = run("point-gyro-readings.yaml", tmp_path / "dropout.parquet", tmp_path / "b")
    assert result.returncode == 0, result.output
    rejects = pq.read_table(tmp_path / "b" / "compass.rejects.parquet").to_pylist()
    assert [(r["station"], r["reason"]) for r in rejects] == [
        (vertical, "near vertical and a position without a frame angle to reference the fit")
    ]
    others = pq.read_table(tmp_path / "b" / "compass.stations.parquet")
    assert others.column("station").to_pylist() == solved.column("station").to_pylist()[1:]


def test_bundled_readings_csv_runs_through_the_readings_pipeline(tmp_path: Path):
    result = run(
        "point-gyro-readings.yaml", ROOT / "examples" / "readings-j-well.csv", tmp_path / "out"
    )
    assert result.returncode == 0, result.stderr
    stations = pq.read_table(tmp_path / "out" / "compass.stations.parquet")
    inclined = np.array(stations.column("mode").to_pylist()) == "inclined"
    azi = stations.column("azi").to_numpy()[inclined]
    sigma = stations.column("sigma_azi").to_numpy()[inclined]
    # the J well's plan azimuth is 37° once it builds (the file is a simulated run)
    assert np.all(np.abs(azi - 37.0) < 4 * sigma)


def test_missing_latitude_is_a_clear_error(simulated: Path, tmp_path: Path):
    readings = tmp_path / "r.parquet"
    table = pq.read_table(simulated / "samples.parquet").replace_schema_metadata({})
    pq.write_table(table, readings)
    result = run("point-gyro.yaml", readings, tmp_path / "out")
    assert result.returncode == 1
    assert "stage 'validity'" in result.stderr and "latitude" in result.stderr
    assert not (tmp_path / "out" / "run.json").exists()
    ok = run("point-gyro.yaml", readings, tmp_path / "ok", "--well", "latitude=61.25")
    assert ok.returncode == 0, ok.stderr


@pytest.mark.parametrize("gap", ["30 s lost", "half the rate"])
def test_a_time_gap_is_named_where_it_is(simulated: Path, tmp_path: Path, gap: str):
    table = pq.read_table(simulated / "samples.parquet")
    t = table.column("time").to_numpy()  # 100 Hz
    i0 = 2 * len(t) // 3  # two thirds of the way in
    rows = np.arange(len(t))
    if gap == "30 s lost":  # rows i0 … i0 + 2999 dropped: a step of 30.01 s after row i0 − 1
        keep = (rows < i0) | (rows >= i0 + 3000)
        after, step, count = i0 - 1, "30.01", 1
    else:  # every other row from i0 on: steps of 0.02 s after row i0
        keep = (rows < i0) | ((rows - i0) % 2 == 0)
        after, step, count = i0, "0.02", int(keep[i0:].sum()) - 1
    samples = tmp_path / "samples.parquet"
    pq.write_table(table.filter(pa.array(keep)), samples)
    result = run("point-gyro.yaml", samples, tmp_path / "out")
    assert result.returncode != 0 and "Traceback" not in result.stderr
    expected = (
        f"the usual step is 0.01 s, but the step at t = {t[after]:g} s is {step} s "
        f"(after row {after}; {count} step(s) off the usual"
    )
    assert expected in result.stderr, result.stderr


def readings_table(alphas_deg, *, frame=None, axes="x") -> pa.Table:
    """Noise-free readings of one inclined station (A = 37°, I = 40°, 61.25° N)."""
    k, s = 15.041067 * np.cos(np.radians(61.25)), 15.041067 * np.sin(np.radians(61.25))
    a, i = np.radians(37.0), np.radians(40.0)
    h, r = k * np.cos(a) * np.cos(i) + s * np.sin(i), -k * np.sin(a)
    psi = np.radians(alphas_deg)
    g = 9.82
    n = len(psi)
    data = {
        "station": np.zeros(n, dtype=int),
        "md": np.full(n, 500.0),
        "position": np.arange(n),
        "t": 10.0 + 40.0 * np.arange(n),
        "gyro_x": h * np.cos(psi) + r * np.sin(psi) + 2.0,
        "acc_x": -g * np.sin(i) * np.cos(psi),
        "acc_y": g * np.sin(i) * np.sin(psi),
        "acc_z": np.full(n, g * np.cos(i)),
    }
    if frame is not None:
        data["frame_angle"] = np.mod(frame, 360.0)
    return PositionReadings.compiled().make_table(data)


OPTIONS = CompassOptions(gyro_sigma=0.05, acc_sigma=1e-4)


def test_fewer_positions_than_unknowns_is_rejected():
    stations, rejects = compass(readings_table([0, 90, 180]), 61.25, OPTIONS)
    assert stations.num_rows == 0
    assert "3 position(s) cannot resolve 4 unknowns" in rejects.column("reason")[0].as_py()
    ok, _ = compass(
        readings_table([0, 90, 180]), 61.25, OPTIONS.model_copy(update={"trend": False})
    )
    assert ok.column("azi")[0].as_py() == pytest.approx(37.0, abs=1e-6)


def test_positions_not_spanning_the_circle_are_rejected():
    _, rejects = compass(readings_table([0, 2, 4, 6, 8]), 61.25, OPTIONS)
    assert "do not span the circle" in rejects.column("reason")[0].as_py()


def test_stations_rejected_among_solved_ones_keep_their_reasons():
    """The stations' fits are made together: one not spanning the circle beside solved ones
    of its shape, and one with too few positions, are rejected as alone; the others solve."""
    alphas = [[0, 90, 180, 270, 0], [0, 2, 4, 6, 8], [0, 90, 180], [10, 100, 190, 280, 10]]
    tables = []
    for i, angles in enumerate(alphas):
        one = readings_table(angles)
        one = one.set_column(0, "station", pa.array(np.full(one.num_rows, i)))
        tables.append(one.set_column(3, "t", pa.array(one.column("t").to_numpy() + 1000.0 * i)))
    stations, rejects = compass(pa.concat_tables(tables), 61.25, OPTIONS)
    assert stations.column("station").to_pylist() == [0, 3]
    np.testing.assert_allclose(stations.column("azi").to_numpy(), 37.0, atol=1e-6)
    assert rejects.column("station").to_pylist() == [1, 2]
    reasons = rejects.column("reason").to_pylist()
    assert "do not span the circle" in reasons[0]
    assert "3 position(s) cannot resolve 4 unknowns" in reasons[1]


def test_frame_angle_disagreeing_with_accelerometers_is_flagged():
    good = readings_table([10, 100, 190, 280, 10], frame=np.array([0, 90, 180, 270, 0]))
    stations, _ = compass(good, 61.25, OPTIONS)
    assert stations.column("flags")[0].as_py() == ""
    slipped = readings_table([10, 100, 190, 280, 10], frame=np.array([0, 90, 170, 270, 0]))
    stations, _ = compass(slipped, 61.25, OPTIONS)
    assert "frame_mismatch" in stations.column("flags")[0].as_py()


def test_inconsistent_residuals_are_flagged():
    table = readings_table([0, 90, 180, 270, 0, 45, 135])
    gyro = table.column("gyro_x").to_numpy().copy()
    gyro[3] += 1.0  # the tool moved during one position: 20σ off the model
    table = table.set_column(
        table.schema.get_field_index("gyro_x"), table.schema.field("gyro_x"), pa.array(gyro)
    )
    stations, _ = compass(table, 61.25, OPTIONS)
    assert "inconsistent" in stations.column("flags")[0].as_py()


def test_missing_sigma_is_a_clear_error():
    with pytest.raises(ValueError, match="declare gyro_sigma"):
        compass(readings_table([0, 90, 180, 270, 0]), 61.25, CompassOptions())


def test_accelerometers_not_measuring_gravity_are_rejected():
    table = readings_table([0, 90, 180, 270, 0])
    for name in ("acc_x", "acc_y", "acc_z"):  # as if the file were in g, not m/s²
        i = table.schema.get_field_index(name)
        table = table.set_column(
            i, table.schema.field(name), pa.array(table.column(name).to_numpy() / 9.81)
        )
    _, rejects = compass(table, 61.25, OPTIONS)
    assert "not gravity" in rejects.column("reason")[0].as_py()

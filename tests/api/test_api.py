"""The Python API (``import pipeline as gp``) driven end to end with DataFrames and with Arrow
tables: simulated raw samples → readings → validity checks → compass → trajectory →
uncertainty → interpolation → report and files; the same numbers as the pipelines compute,
declared units converted or refused, and ``gp.run`` in memory equal to the command line."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import ParameterError, SpecError, UnitError
from pipeline.runner import RunInputError
from tests_support import ROOT, export_tolerance, gyropipe_cli

SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "elevation": 54.3,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
POINT = {
    "name": "api-point",
    "seed": 3,
    "site": SITE,
    "well": {
        "sections": [
            {"kind": "vertical", "length": 60},
            {"kind": "build", "dls": 6.0, "inc": 30, "azi": 40},
            {"kind": "hold", "to_md": 300},
        ]
    },
    "tool": {"preset": "mems-vrg"},
    "survey": {
        "mode": "point",
        "every": 60,
        "positions": [0, 90, 180, 270, 0],
        "dwell": 6,
        "move_time": 1.0,
        "speed": 10.0,
    },
}
KINDS = ["frame", "arrow"]


def as_kind(table: pd.DataFrame | pa.Table, kind: str) -> pd.DataFrame | pa.Table:
    """``table`` as a DataFrame or an Arrow table (units carried either way)."""
    if kind == "frame":
        return table if isinstance(table, pd.DataFrame) else gp.to_frame(table)
    return table if isinstance(table, pa.Table) else gp.to_table(table)


def arrow(table: pd.DataFrame | pa.Table) -> pa.Table:
    return table if isinstance(table, pa.Table) else gp.to_table(table)


@pytest.fixture(scope="module")
def simulation() -> gp.Tables:
    return gp.simulate(POINT)


EPOCH = "1795000000"
"""SOURCE_DATE_EPOCH of the runs compared byte for byte (their start time)."""


@pytest.fixture(scope="module")
def samples_file(simulation: gp.Tables, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("samples") / "samples.parquet"
    gp.write(simulation.samples, path)
    return path


@pytest.fixture(scope="module")
def pipeline_run(samples_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shipped point-gyro pipeline run by the command line on the simulated samples."""
    out = tmp_path_factory.mktemp("cli") / "out"
    args = ["run", "pipelines/point-gyro.yaml", "--input", str(samples_file), "--out", str(out)]
    result = gyropipe_cli(*args, env={"SOURCE_DATE_EPOCH": EPOCH})
    assert result.returncode == 0, result.stderr
    return out


def test_the_public_surface_is_curated() -> None:
    public = {name for name in dir(gp) if not name.startswith("_")}
    assert set(gp.__all__) - {"__version__"} <= public
    for name in gp.__all__:
        assert getattr(gp, name) is not None
    functions = [getattr(gp, n) for n in gp.__all__ if callable(getattr(gp, n))]
    assert all(f.__doc__ for f in functions)


@pytest.mark.parametrize("kind", KINDS)
def test_point_survey_end_to_end(
    kind: str, simulation: gp.Tables, pipeline_run: Path, tmp_path: Path
) -> None:
    """Every step as a function call gives the tables the point-gyro pipeline persists."""
    samples = as_kind(simulation.samples, kind)
    readings = gp.position_readings(samples, trim_start=1.0)
    assert type(readings) is type(samples)
    checked = gp.validity_checks(readings, samples=samples)
    assert set(checked) == {"qc", "summary", "readings"}
    solved = gp.compass(checked.readings)
    trajectory = gp.minimum_curvature(solved.stations)
    assert isinstance(trajectory, type(samples))
    expected = pq.read_table(pipeline_run / "trajectory.trajectory.parquet")
    got = arrow(trajectory)
    for column in ("md", "inc", "azi", "north", "east", "tvd"):
        np.testing.assert_array_equal(
            got.column(column).to_numpy(), expected.column(column).to_numpy()
        )
    assert got.schema.field("azi").metadata[b"north_reference"] == b"true"
    # the compassed azimuth is the simulator's own within its predicted σ (mems-vrg, 6 s)
    truth = arrow(simulation.stations)
    azi = np.interp(got.column("md").to_numpy(), truth["md"].to_numpy(), truth["azi"].to_numpy())
    sigma = arrow(solved.stations).column("sigma_azi").to_numpy()
    inclined = got.column("inc").to_numpy() > 5
    z = (got.column("azi").to_numpy() - azi) / sigma
    assert inclined.sum() >= 3 and np.abs(z[inclined]).max() < 4

    uncertain = arrow(gp.position_uncertainty(trajectory))
    for name in ("cov_nn", "cov_ee", "cov_vv", "ellipse_major_conf", "ellipse_minor_conf"):
        values = uncertain.column(name).to_numpy()
        assert np.isfinite(values).all() and values[-1] > 0, name
    assert uncertain.schema.field("cov_nn").metadata[b"unit"] == b"m2"
    points = arrow(gp.interpolate(trajectory, md=[100.0, 150.0]))
    assert points.column("md").to_pylist() == [100.0, 150.0]
    crossings = arrow(gp.interpolate(trajectory, tvd=120.0))
    assert crossings.num_rows == 1
    np.testing.assert_allclose(crossings.column("tvd").to_numpy(), [120.0], atol=1e-9)

    written = gp.report(trajectory, tmp_path / "well", qc=checked.qc, title="API well")
    assert sorted(p.name for p in written) == ["well.html", "well.pdf"]
    assert "API well" in (tmp_path / "well.html").read_text()
    path = gp.write(trajectory, tmp_path / "trajectory.csv")
    back = gp.read(path, kind="stations")
    md = got.column("md").to_numpy()  # the CSV holds it at 0.1 mm (pipeline.io.precision)
    assert np.all(np.abs(np.asarray(back["md"]) - md) <= export_tolerance("m", md))
    assert back.attrs["units"]["md"] == "m" and back.attrs["north_reference"] == "true"


@pytest.mark.parametrize("kind", KINDS)
def test_declared_units_are_converted(kind: str) -> None:
    feet = pd.DataFrame({"md": [0.0, 1000.0, 2000.0], "inc": [0.0, 3.0, 6.0]})
    feet["azi"] = [0.0, 45.0, 46.0]
    feet.attrs = {"units": {"md": "ft"}, "north_reference": "grid"}
    metres = feet.assign(md=feet["md"] * 0.3048)
    metres.attrs = {"north_reference": "grid"}
    a = arrow(gp.minimum_curvature(as_kind(feet, kind) if kind == "frame" else gp.to_table(feet)))
    b = arrow(gp.minimum_curvature(metres))
    np.testing.assert_allclose(a.column("md").to_numpy(), [0.0, 304.8, 609.6], rtol=1e-15)
    np.testing.assert_allclose(a.column("tvd").to_numpy(), b.column("tvd").to_numpy(), rtol=1e-14)
    assert a.schema.field("azi").metadata[b"north_reference"] == b"grid"


def test_gyro_rates_declared_in_rad_per_s_are_converted(simulation: gp.Tables) -> None:
    samples = simulation.samples.copy()
    samples.attrs = dict(simulation.samples.attrs)
    factor = np.pi / 180 / 3600  # deg/h → rad/s
    gyros = [c for c in samples.columns if c.startswith("gyro_")]
    assert gyros
    for name in gyros:
        samples[name] = samples[name] * factor
    samples.attrs["units"] = {**samples.attrs["units"], **dict.fromkeys(gyros, "rad/s")}
    a = arrow(gp.position_readings(samples, trim_start=1.0))
    b = arrow(gp.position_readings(simulation.samples, trim_start=1.0))
    np.testing.assert_allclose(
        a.column("gyro_x").to_numpy(), b.column("gyro_x").to_numpy(), rtol=1e-12
    )


def test_a_unit_of_the_wrong_quantity_is_refused() -> None:
    frame = pd.DataFrame({"md": [0.0, 10.0], "inc": [0.0, 1.0], "azi": [0.0, 2.0]})
    frame.attrs = {"units": {"md": "deg/h"}, "north_reference": "true"}
    with pytest.raises(UnitError, match=r"column 'md'.*an angular rate, expected a length"):
        gp.minimum_curvature(frame)
    frame.attrs = {"units": {"md": "furlong"}, "north_reference": "true"}
    with pytest.raises(UnitError, match=r"column 'md': unknown unit 'furlong'"):
        gp.minimum_curvature(frame)


def test_plain_dataframes_need_a_north_reference() -> None:
    frame = pd.DataFrame({"md": [0.0, 10.0], "inc": [0.0, 1.0], "azi": [0.0, 2.0]})
    with pytest.raises(ParameterError, match="north reference of column 'azi' is unknown"):
        gp.minimum_curvature(frame)
    done = gp.minimum_curvature(frame, well={"north_reference": "magnetic"})
    assert done.attrs["north_reference"] == "magnetic"


def test_wrong_parameters_are_named() -> None:
    frame = pd.DataFrame({"md": [0.0, 10.0], "inc": [0.0, 1.0], "azi": [0.0, 2.0]})
    frame.attrs = {"north_reference": "true"}
    with pytest.raises(ParameterError, match="minimum_curvature: unknown parameter 'vs_azimth'"):
        gp.minimum_curvature(frame, vs_azimth=10)
    with pytest.raises(
        ParameterError, match=r"compass: latitude: .*less than or equal to 90 \(got 161\)"
    ):
        gp.compass(gp.simulate(POINT).samples.head(0), latitude=161)


@pytest.mark.parametrize("kind", KINDS)
def test_drift_functions(kind: str) -> None:
    calibration = gp.read(ROOT / "examples" / "calibration-ig50.csv", kind="calibration")
    result = gp.calibrate_drift(as_kind(calibration, kind))
    assert set(result) == {"result", "series"}
    table = arrow(result.result)
    selected = table.filter(table.column("selected"))
    assert selected.num_rows == 1 and selected.column("verdict").to_pylist() == ["linear"]
    free = as_kind(
        gp.simulate(ROOT / "examples" / "plans" / "j-well-free-gyro.yaml").readings, kind
    )
    corrected = gp.correct_drift(free, source="tie_in")
    assert set(corrected) == {"readings", "stations", "qc"}
    assert isinstance(corrected.stations, type(free)) and len(corrected.stations) > 0
    with_calibration = gp.correct_drift(free, calibration=result.result, source="calibration")
    assert len(with_calibration.stations) == len(corrected.stations)


@pytest.mark.parametrize("kind", KINDS)
def test_station_methods(kind: str) -> None:
    stations = pd.DataFrame({"md": [0.0, 100.0, 200.0], "inc": [0.0, 10.0, 20.0]})
    stations["azi"] = [0.0, 40.0, 40.0]
    stations.attrs = {"north_reference": "true"}
    given = as_kind(stations, kind) if kind == "frame" else gp.to_table(stations)
    tangential = arrow(gp.survey_method(given, method="tangential"))
    exact = arrow(gp.minimum_curvature(given))
    # tangential puts the whole course at the lower station's inclination: deeper TVD error
    tvd_t, tvd_m = tangential.column("tvd").to_numpy(), exact.column("tvd").to_numpy()
    assert tvd_t[-1] < tvd_m[-1]
    np.testing.assert_allclose(tvd_t[1], 100 * np.cos(np.radians(10.0)), rtol=1e-12)


@pytest.mark.parametrize("kind", KINDS)
def test_continuous_integration(kind: str) -> None:
    plan = {
        "name": "api-continuous",
        "seed": 2,
        "site": SITE,
        "well": {
            "sections": [
                {"kind": "vertical", "length": 20},
                {"kind": "build", "dls": 10.0, "inc": 30, "azi": 40},
                {"kind": "hold", "to_md": 200},
            ]
        },
        "tool": {"preset": "ideal"},
        "survey": {"mode": "continuous", "start_md": 120, "end_md": 180, "speed": 2.0},
    }
    samples = as_kind(gp.simulate(plan).samples, kind)
    readings = gp.position_readings(samples, trim_start=0.5, min_dwell=1.0)
    stops = gp.compass(readings, noise_floor=0.01).stations
    run = gp.integrate_continuous(samples, stops)
    assert set(run) == {"stations", "series"}
    azi = arrow(run.stations).column("azi").to_numpy()
    assert np.abs(azi - 40.0).max() < 0.05


def test_run_in_memory_equals_the_command_line(
    simulation: gp.Tables, samples_file: Path, pipeline_run: Path
) -> None:
    result = gp.run(ROOT / "pipelines" / "point-gyro.yaml", {"samples": samples_file})
    assert result.out is None and result.outputs == []
    manifest = json.loads((pipeline_run / "run.json").read_text())
    persisted = [f["file"] for f in manifest["outputs"] if f["file"].endswith(".parquet")]
    assert persisted
    for name in persisted:
        table = pq.read_table(pipeline_run / name)
        key = name.removesuffix(".parquet")
        ours = result.tables[key]
        assert ours.schema.equals(table.schema), key  # units and north references too
        pd.testing.assert_frame_equal(ours.to_pandas(), table.to_pandas(), check_exact=True)
    frame = result.frame("compass.stations")
    assert frame.attrs["units"]["azi"] == "deg"
    # a name that is no output says which are (a stage id alone is not one)
    with pytest.raises(KeyError, match=r"'compass' is not an output .*compass\.stations"):
        result.frame("compass")
    assert "compass" not in result.tables and "compass.stations" in result.tables
    # a table given in memory runs the same
    again = gp.run(ROOT / "pipelines" / "point-gyro.yaml", simulation.samples)
    pd.testing.assert_frame_equal(  # NaN (undefined azimuths at vertical) equal to NaN
        again.tables["trajectory.trajectory"].to_pandas(),
        result.tables["trajectory.trajectory"].to_pandas(),
        check_exact=True,
    )


def test_run_into_a_directory_writes_what_the_cli_writes(
    samples_file: Path, pipeline_run: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Byte for byte, reports included (the same start time through SOURCE_DATE_EPOCH)."""
    monkeypatch.setenv("SOURCE_DATE_EPOCH", EPOCH)
    monkeypatch.chdir(ROOT)  # the pipeline named as on the command line (reports print it)
    out = tmp_path / "api"
    result = gp.run("pipelines/point-gyro.yaml", {"samples": samples_file}, out=out)
    cli = json.loads((pipeline_run / "run.json").read_text())
    api = json.loads((out / "run.json").read_text())
    assert [f["file"] for f in api["outputs"]] == [f["file"] for f in cli["outputs"]]
    for theirs, ours in zip(cli["outputs"], api["outputs"], strict=True):
        assert ours["sha256"] == theirs["sha256"], ours["file"]
        assert hashlib.sha256((out / ours["file"]).read_bytes()).hexdigest() == ours["sha256"]
    assert result.outputs == [out / f["file"] for f in api["outputs"]]
    assert api["started"] == cli["started"] == "2026-11-18T11:06:40+00:00"


def test_run_errors() -> None:
    with pytest.raises(SpecError):
        gp.run(ROOT / "pipelines" / "survey.yaml", "x.csv", set={"trajectory.nope": 1})
    with pytest.raises(RunInputError, match="no such file"):
        gp.run(ROOT / "pipelines" / "survey.yaml", {"stations": "missing.csv"})
    with pytest.raises(RunInputError, match="unknown input 'wrong'"):
        gp.run(ROOT / "pipelines" / "survey.yaml", {"wrong": "x.csv"})


def test_read_any_las_log_like_lasio() -> None:
    import lasio

    path = ROOT / "tests" / "data" / "las" / "gr.las"
    frame = gp.read(path)
    theirs = lasio.read(str(path))
    assert [c for c in frame.columns if c != "source_line"] == [c.mnemonic for c in theirs.curves]
    assert frame.attrs["units"] == {c.mnemonic: c.unit for c in theirs.curves}
    for curve in theirs.curves:
        np.testing.assert_array_equal(frame[curve.mnemonic].to_numpy(), curve.data)
    assert frame.attrs["well"]["well"] == theirs.well["WELL"].value


def test_gyro_rates_in_rad_per_s_given_as_deg_per_h_never_give_an_azimuth(
    simulation: gp.Tables,
) -> None:
    """A units mistake (rad/s numbers, no unit declared): every station is rejected with the
    hint, none is solved."""
    samples = simulation.samples.copy()
    samples.attrs = dict(simulation.samples.attrs)
    for name in [c for c in samples.columns if c.startswith("gyro_")]:
        samples[name] = samples[name] * (np.pi / 180 / 3600)
    readings = gp.position_readings(samples, trim_start=1.0)
    with pytest.raises(gp.GyropipeError, match=r"are the gyro rates in °/h\?"):
        gp.compass(readings)

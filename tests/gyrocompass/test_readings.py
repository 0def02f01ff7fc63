"""Raw point-survey samples → position readings, against the simulator as forward model:
means against the closed forms of DOMAIN.md §2/§5, noise against the configured ARW, trims,
dwell detection against the markers, tool axes, errors, and the circular frame-angle mean."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest

from pipeline.earth.frames import OMEGA_EARTH
from pipeline.earth.gravity import normal_gravity
from pipeline.errors import ContractViolation
from pipeline.gyrocompass.readings import ReadingOptions, exact_median, position_readings
from pipeline.gyrocompass.readings_stream import stream_position_readings
from pipeline.sim.simulate import Simulation, simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.streams import TableStream
from pipeline.tables import PositionReadings, RawSamples

FS = 100.0
LAT, ELEVATION = 61.25, 120.0
OMEGA_DEG_H = np.degrees(OMEGA_EARTH) * 3600
SITE = {
    "latitude": LAT,
    "longitude": 73.4,
    "elevation": ELEVATION,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
WELL = [
    {"kind": "vertical", "length": 20},
    {"kind": "curve", "dls": 30.0, "inc": 50, "azi": 120},
    {"kind": "hold", "length": 50},
]
STATIONS = [10.0, 40.0, 80.0]
POSITIONS = [0.0, 90.0, 180.0, 270.0, 0.0]
NOISY = {"preset": "ideal", "overrides": {"gyro": {"noise_density": 0.05}}}
ARW_SIGMA = 60 * 0.05 * np.sqrt(FS)  # per-sample σ of 0.05 deg/√h at 100 Hz, deg/h


@cache
def run(tool: str = "ideal", dwell: float = 8.0, **survey: Any) -> Simulation:
    tools = {"ideal": {"preset": "ideal"}, "noisy": NOISY}
    return simulate(
        SimulationSpec.model_validate(
            {
                "name": "readings",
                "seed": 5,
                "site": SITE,
                "well": {"sections": WELL},
                "tool": tools[tool],
                "survey": {
                    "mode": "point",
                    "stations": STATIONS,
                    "positions": POSITIONS,
                    "dwell": dwell,
                    "move_time": 1.0,
                    "settle_time": 1.0,
                    "speed": 5.0,
                    **survey,
                },
            }
        )
    )


def col(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy())


def expected_signals(truth: pa.Table, t: np.ndarray) -> dict[str, np.ndarray]:
    """Gyro (deg/h) and accelerometer (m/s²) signals at rest (DOMAIN §2, §5) for the true
    attitude at times ``t``."""
    i = np.round(t * FS).astype(int)
    inc, azi, tf = (np.radians(col(truth, c)[i]) for c in ("inc", "azi", "toolface"))
    k, s = OMEGA_DEG_H * np.cos(np.radians(LAT)), OMEGA_DEG_H * np.sin(np.radians(LAT))
    h = k * np.cos(azi) * np.cos(inc) + s * np.sin(inc)
    r = -k * np.sin(azi)
    g = normal_gravity(LAT, ELEVATION)
    return {
        "gyro_x": h * np.cos(tf) + r * np.sin(tf),
        "gyro_y": -h * np.sin(tf) + r * np.cos(tf),
        "gyro_z": k * np.sin(inc) * np.cos(azi) - s * np.cos(inc),
        "acc_x": -g * np.sin(inc) * np.cos(tf),
        "acc_y": g * np.sin(inc) * np.sin(tf),
        "acc_z": g * np.cos(inc),
    }


def angle_gap(a: np.ndarray, b: np.ndarray | float) -> np.ndarray:
    return np.abs((np.asarray(a) - b + 180.0) % 360.0 - 180.0)


def test_ideal_tool_with_markers_reads_the_closed_forms() -> None:
    sim = run()
    readings = position_readings(sim.samples)
    PositionReadings.validate_table(readings)
    assert readings.schema.field("gyro_x").metadata == {b"unit": b"deg/h"}
    np.testing.assert_array_equal(col(readings, "station"), np.repeat([0, 1, 2], 5))
    np.testing.assert_array_equal(col(readings, "position"), np.tile(np.arange(5), 3))
    np.testing.assert_allclose(col(readings, "md"), np.repeat(STATIONS, 5), atol=1e-9)
    expected = expected_signals(sim.truth, col(readings, "t"))
    for name, values in expected.items():
        atol = 1e-9 if name.startswith("gyro") else 1e-12
        np.testing.assert_allclose(col(readings, name), values, atol=atol, err_msg=name)
        assert np.all(col(readings, f"{name}_std") < atol)
    assert np.all(angle_gap(col(readings, "frame_angle"), np.tile(POSITIONS, 3)) < 1e-9)
    n = col(readings, "n")
    assert set(n) <= {700, 701}  # (8 s dwell − 1 s trim) at 100 Hz
    np.testing.assert_allclose(col(readings, "duration"), n / FS)


def test_white_gyro_noise_sets_the_std_columns() -> None:
    readings = position_readings(run("noisy", dwell=20.0).samples)
    ideal = position_readings(run("ideal", dwell=20.0).samples)
    n = col(readings, "n")
    assert set(n) <= {1900, 1901}  # (20 s − 1 s) · 100 Hz
    stds = np.stack([col(readings, f"gyro_{a}_std") for a in "xyz"])
    assert np.all(np.abs(stds / ARW_SIGMA - 1) < 0.07)  # one reading: 1.6 % σ
    assert np.sqrt(np.mean(stds**2)) / ARW_SIGMA == pytest.approx(1, abs=0.015)
    for axis in "xyz":
        z = (col(readings, f"gyro_{axis}") - col(ideal, f"gyro_{axis}")) / (ARW_SIGMA / np.sqrt(n))
        assert np.all(np.abs(z) < 4.5), axis
    assert np.all(col(readings, "acc_z_std") < 1e-12)  # accelerometers stay ideal


def test_trim_drops_exactly_the_configured_seconds() -> None:
    samples = run().samples
    full = position_readings(samples, ReadingOptions(trim_start=0, trim_end=0))
    trimmed = position_readings(samples, ReadingOptions(trim_start=2.5, trim_end=1.5, min_dwell=2))
    np.testing.assert_array_equal(col(full, "n") - col(trimmed, "n"), 400)
    np.testing.assert_allclose(col(trimmed, "t") - col(full, "t"), (2.5 - 1.5) / 2, atol=1e-9)
    marked = ~pc.is_null(samples.column("position")).to_numpy(zero_copy_only=False)
    time = col(samples, "time")
    first = time[np.flatnonzero(np.diff(marked.astype(int)) == 1) + 1]
    np.testing.assert_allclose(col(full, "t") - (col(full, "n") - 1) / (2 * FS), first)


def test_detection_finds_the_marked_readings() -> None:
    # quick frame moves, no settling: marked and detected dwells differ by the samples the
    # detector cannot tell from the dwell (move ramps inside the angle tolerance) and by
    # those it cuts where the tool arrives or leaves: the detected readings take in no
    # sample of travel (within 2 of the marks) and lose at most the 1 s smoothing window
    sim = run("noisy", dwell=10.0, move_time=0.1, settle_time=0.0)
    odometer_noise = sim.samples.set_column(
        1,
        sim.samples.schema.field("md"),
        pa.array(
            col(sim.samples, "md") + np.random.default_rng(1).normal(0, 0.05, sim.samples.num_rows)
        ),
    )
    marked = position_readings(odometer_noise)
    found = position_readings(odometer_noise.drop_columns(["station", "position"]))
    assert found.num_rows == marked.num_rows == 15
    for name in ("station", "position"):
        np.testing.assert_array_equal(col(found, name), col(marked, name))
    np.testing.assert_allclose(col(found, "md"), np.repeat(STATIONS, 5), atol=0.01)
    inner = np.isin(col(marked, "position"), [1, 2, 3])  # between two frame moves
    n_marked, n_found = col(marked, "n"), col(found, "n")
    assert np.all(np.abs(n_found - n_marked)[inner] <= 2)
    assert np.all(n_found >= n_marked - FS * 1.0)
    first_marked, first_found = (
        col(r, "t") - (col(r, "n") - 1) / (2 * FS) for r in (marked, found)
    )
    assert np.all(first_found >= first_marked - 2 / FS)
    assert np.all(first_found + n_found / FS <= first_marked + (n_marked + 2) / FS)
    np.testing.assert_allclose(col(found, "t")[inner], col(marked, "t")[inner], atol=0.02)
    for axis in "xyz":
        diff = col(found, f"gyro_{axis}")[inner] - col(marked, f"gyro_{axis}")[inner]
        assert np.all(np.abs(diff) < 0.5 * ARW_SIGMA / np.sqrt(n_marked[inner])), axis
    assert np.all(angle_gap(col(found, "frame_angle"), np.tile(POSITIONS, 3)) < 0.01)


@pytest.mark.parametrize("axes", ["x", "xy", "xyz"])
def test_every_gyro_axis_of_the_tool_is_read(axes: str) -> None:
    tool = {"preset": "ideal", "overrides": {"gyro_axes": axes}}
    spec = SimulationSpec.model_validate(
        {
            "name": "axes",
            "site": SITE,
            "well": {"sections": WELL},
            "tool": tool,
            "survey": {"mode": "point", "stations": [50.0], "dwell": 7.0, "move_time": 1.0},
        }
    )
    readings = position_readings(simulate(spec).samples)
    for axis in "xyz":
        present = axis in axes
        assert (f"gyro_{axis}" in readings.column_names) is present
        assert (f"gyro_{axis}_std" in readings.column_names) is present
    PositionReadings.validate_table(readings)


def synthetic(
    md: np.ndarray, angle: np.ndarray | None, *, station: Any = None, position: Any = None
) -> pa.Table:
    """RawSamples at 10 Hz with a constant sensor signal and the given MD, frame angle and
    markers."""
    n = md.size
    columns: dict[str, Any] = {"time": np.arange(n) / 10.0, "md": md}
    if angle is not None:
        columns["frame_angle"] = angle % 360.0
    columns |= {"gyro_x": np.full(n, 5.0), "acc_x": np.zeros(n), "acc_y": np.zeros(n)}
    columns["acc_z"] = np.full(n, 9.81)
    if station is not None:
        columns |= {"station": station, "position": position}
    return RawSamples.compiled().make_table(columns)


def profile(knots: list[tuple[float, float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """MD and frame angle at 10 Hz, piecewise linear through (time s, md m, angle deg)."""
    t_k, md_k, angle_k = (np.array(v) for v in zip(*knots, strict=True))
    t = np.arange(0, t_k[-1] + 1e-9, 0.1)
    return np.interp(t, t_k, md_k), np.interp(t, t_k, angle_k)


def test_detection_numbers_stations_and_positions() -> None:
    md, angle = profile(
        [
            (0, 100, 10), (10, 100, 10), (11, 100, 100), (21, 100, 100),  # station 0
            (31, 110, 100), (41, 110, 100), (42, 110, 10), (52, 110, 10),  # travel, station 1
            (55, 107, 10), (58, 110, 10), (68, 110, 10),  # pulled up 3 m and back: station 2
            (69, 110.3, 10), (79, 110.3, 10),  # crept 0.3 m (< station_gap): same station
        ]
    )  # fmt: skip
    found = position_readings(synthetic(md, angle), ReadingOptions(md_smoothing=0))
    np.testing.assert_array_equal(col(found, "station"), [0, 0, 1, 1, 2, 2])
    np.testing.assert_array_equal(col(found, "position"), [0, 1, 0, 1, 0, 1])
    md_found = col(found, "md")  # one MD per station: the median over its dwells
    np.testing.assert_allclose(md_found[:4], [100, 100, 110, 110])
    assert md_found[4] == md_found[5] and 110 < md_found[4] < 110.3
    np.testing.assert_allclose(col(found, "frame_angle"), [10, 100, 100, 10, 10, 10], atol=1e-9)
    assert np.all(col(found, "gyro_x") == 5.0)


def test_circular_mean_of_the_frame_angle_wraps_at_360() -> None:
    jitter = np.tile([359.8, 0.1], 50)  # circular mean 359.95
    table = synthetic(np.full(100, 30.0), jitter, station=[0] * 100, position=[0] * 100)
    options = ReadingOptions(trim_start=0, min_dwell=5)
    for samples in (table, table.drop_columns(["station", "position"])):  # markers, detection
        readings = position_readings(samples, options)
        assert readings.num_rows == 1
        assert col(readings, "frame_angle")[0] == pytest.approx(359.95, abs=1e-9)
    around_zero = synthetic(np.full(100, 30.0), np.tile([359.9, 0.1], 50))
    mean = col(position_readings(around_zero, options), "frame_angle")[0]
    assert 0 <= mean < 360 and angle_gap(mean, 0.0) < 1e-9


def test_no_markers_and_no_frame_angle_is_an_error() -> None:
    samples = run().samples.drop_columns(["station", "position", "frame_angle"])
    with pytest.raises(ValueError, match="neither station/position markers nor a frame_angle"):
        position_readings(samples)


def test_a_marked_position_too_short_after_trimming_is_an_error() -> None:
    with pytest.raises(ValueError, match=r"too short after trimming.*station 0 position 0"):
        position_readings(run().samples, ReadingOptions(trim_start=4.0))  # 8 − 4 < 5 s


def test_non_uniform_time_is_an_error() -> None:
    samples = run().samples
    keep = np.ones(samples.num_rows, dtype=bool)
    keep[1234] = False  # a dropped sample
    with pytest.raises(ValueError, match=r"not uniformly sampled.*t = 12\.33 s is 0\.02 s"):
        position_readings(samples.filter(pa.array(keep)))


def test_a_position_marked_in_two_runs_is_an_error() -> None:
    samples = run().samples
    station = pc.if_else(pc.equal(samples.column("station"), 1), 0, samples.column("station"))
    relabelled = samples.set_column(
        samples.column_names.index("station"), samples.schema.field("station"), station
    )
    with pytest.raises(ValueError, match=r"separate runs.*station 0 position 0 at t = 1, \d"):
        position_readings(relabelled)


@pytest.mark.parametrize("rows", [None, 777])
def test_a_station_marked_again_after_others_is_refused_whole_or_streamed(
    rows: int | None,
) -> None:
    """Station 2's positions relabelled as station 0's positions 100…: station 0 is visited
    again after station 1. Its readings are not merged into the first visit (another depth,
    another time) on the whole table or on a stream cut anywhere."""
    samples = run().samples
    station, position = (samples.column(n) for n in ("station", "position"))
    later = pc.equal(station, 2)
    relabelled = samples.set_column(
        samples.column_names.index("station"),
        samples.schema.field("station"),
        pc.if_else(later, 0, station),
    ).set_column(
        samples.column_names.index("position"),
        samples.schema.field("position"),
        pc.if_else(later, pc.add(position, 100), position),
    )
    t = samples.column("time").to_numpy()
    marked = station.to_numpy(zero_copy_only=False)
    at = ~np.isnan(position.to_numpy(zero_copy_only=False).astype(float))  # and a position
    visits = [t[np.flatnonzero((marked == s) & at)[0]] for s in (0, 2)]
    expected = rf"station 0 at t = {visits[0]:g}, {visits[1]:g} s.*as a station of its own"
    read = (
        (lambda: position_readings(relabelled))
        if rows is None
        else (lambda: stream_position_readings(TableStream.from_table(relabelled, rows)))
    )
    with pytest.raises(ValueError, match=expected):
        read()


def test_marker_and_column_problems_are_errors() -> None:
    samples = run().samples
    with pytest.raises(ValueError, match="position markers but no station markers"):
        position_readings(samples.drop_columns(["station"]))
    with pytest.raises(ValueError, match="no md column"):
        position_readings(samples.drop_columns(["md"]))
    with pytest.raises(ValueError, match="no frame positions found"):
        position_readings(
            samples.drop_columns(["station", "position"]), ReadingOptions(min_dwell=60)
        )


def test_input_units_are_checked() -> None:
    samples = run().samples
    index = samples.column_names.index("gyro_x")
    field = samples.schema.field("gyro_x").with_metadata({"unit": "rad/s"})
    with pytest.raises(ContractViolation, match="gyro_x"):
        position_readings(samples.set_column(index, field, samples.column("gyro_x")))


@pytest.mark.parametrize(
    "pieces",
    [
        [np.random.default_rng(1).normal(450.0, 0.05, 21_400)],  # a station's odometer MD
        [np.random.default_rng(2).normal(size=n) for n in (7_000, 0, 6_001, 9_000)],  # odd
        [np.repeat(np.arange(4.0), 3_000)],  # ties at the middle
        [np.sort(np.random.default_rng(3).standard_cauchy(50_000))],  # sorted, heavy tails
        [np.r_[np.random.default_rng(4).normal(size=9_999), np.nan]],  # a NaN: NaN
        [np.array([2.0, -1.0, 5.0])],  # few values
        [np.random.default_rng(5).uniform(1e308, 1.7e308, 4_097)],  # odd: the middle, not 2x/2
    ],
)
def test_the_station_md_median_is_numpys_median_of_the_pieces_together(
    pieces: list[np.ndarray],
) -> None:
    expected = np.median(np.concatenate(pieces))
    got = exact_median(pieces)
    assert got == expected or (np.isnan(got) and np.isnan(expected))

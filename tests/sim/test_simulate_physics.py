"""The simulator against physics, independently of any estimator: Earth rate, gravity and
the geomagnetic field at rest (DOMAIN.md §2 closed forms), body rates and accelerations of
a moving tool against finite differences of the truth, and each error term alone."""

from __future__ import annotations

from typing import Any

import allantools
import numpy as np
import pyarrow as pa
import pytest
from scipy.spatial.transform import Rotation

from pipeline.earth.frames import OMEGA_EARTH
from pipeline.earth.gravity import normal_gravity
from pipeline.sim.plan import WellPath, WellPlan, build_path
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec

LAT = 61.25
OMEGA_DEG_H = np.degrees(OMEGA_EARTH) * 3600
SITE = {
    "latitude": LAT,
    "longitude": 73.4,
    "elevation": 120.0,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
# attitudes across the sphere: vertical, inclined every way, horizontal, upward (I > 90°)
SPHERE = [
    {"kind": "vertical", "length": 20},
    {"kind": "curve", "dls": 30.0, "inc": 35, "azi": 40},
    {"kind": "curve", "dls": 30.0, "inc": 90, "azi": 160},
    {"kind": "curve", "dls": 30.0, "inc": 125, "azi": 250},
    {"kind": "curve", "dls": 30.0, "inc": 170, "azi": 330},
]


def spec(
    survey: dict[str, Any], *, tool: dict[str, Any] | None = None, sections=None, seed: int = 3
) -> SimulationSpec:
    return SimulationSpec.model_validate(
        {
            "name": "t",
            "seed": seed,
            "site": SITE,
            "well": {"sections": sections or SPHERE},
            "tool": tool or {"preset": "ideal"},
            "survey": survey,
        }
    )


POINT = {"mode": "point", "every": 25, "dwell": 2.0, "move_time": 1.0, "speed": 5.0}


def columns(table: pa.Table, *names: str) -> np.ndarray:
    return np.stack([table.column(n).to_numpy() for n in names], axis=-1)


@pytest.fixture(scope="module")
def point_run():
    return simulate(spec(POINT))


def test_at_rest_the_triads_measure_earth_rate_gravity_and_field(point_run):
    samples, truth = point_run.samples, point_run.truth
    rest = ~pa.compute.is_null(samples.column("position")).to_numpy(zero_copy_only=False)
    assert rest.sum() > 1000
    gyro = columns(samples, "gyro_x", "gyro_y", "gyro_z")[rest]
    acc = columns(samples, "acc_x", "acc_y", "acc_z")[rest]
    mag = columns(samples, "mag_x", "mag_y", "mag_z")[rest]
    np.testing.assert_allclose(np.linalg.norm(gyro, axis=1), OMEGA_DEG_H, rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(acc, axis=1), normal_gravity(LAT, 120.0), rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(mag, axis=1), 59731.0, rtol=1e-12)
    # latitude from gyros + accelerometers (DOMAIN §3): ω_v = ω·u, u = −g/|g| (up)
    up = -acc / np.linalg.norm(acc, axis=1, keepdims=True)
    w_v = np.sum(gyro * up, axis=1)
    w_h = np.sqrt(np.sum(gyro**2, axis=1) - w_v**2)
    np.testing.assert_allclose(np.degrees(np.arctan2(w_v, w_h)), LAT, atol=1e-7)
    # dip from magnetometers and accelerometers: asin(B·d/|B|), d = g/|g|
    dip = np.degrees(np.arcsin(np.sum(mag * -up, axis=1) / np.linalg.norm(mag, axis=1)))
    np.testing.assert_allclose(dip, 78.29, atol=1e-9)

    # closed forms of DOMAIN §2 and §5 with the true angles
    inc, azi, tf = (
        np.radians(truth.column(c).to_numpy()[rest]) for c in ("inc", "azi", "toolface")
    )
    assert np.ptp(np.degrees(inc)) > 150 and np.ptp(np.degrees(azi)) > 250  # across the sphere
    g = normal_gravity(LAT, 120.0)
    expected_g = g * np.stack(
        [-np.sin(inc) * np.cos(tf), np.sin(inc) * np.sin(tf), np.cos(inc)], -1
    )
    np.testing.assert_allclose(acc, expected_g, atol=1e-9)
    phi = np.radians(LAT)
    h = gyro[:, 0] * np.cos(tf) - gyro[:, 1] * np.sin(tf)
    r = gyro[:, 0] * np.sin(tf) + gyro[:, 1] * np.cos(tf)
    k = OMEGA_DEG_H * np.cos(phi)
    np.testing.assert_allclose(
        h, k * np.cos(azi) * np.cos(inc) + OMEGA_DEG_H * np.sin(phi) * np.sin(inc), atol=1e-9
    )
    np.testing.assert_allclose(r, -k * np.sin(azi), atol=1e-9)
    np.testing.assert_allclose(
        gyro[:, 2],
        k * np.sin(inc) * np.cos(azi) - OMEGA_DEG_H * np.sin(phi) * np.cos(inc),
        atol=1e-9,
    )
    # inclination and toolface back from gravity (the inverse of DOMAIN §2)
    np.testing.assert_allclose(
        np.arctan2(np.hypot(acc[:, 0], acc[:, 1]), acc[:, 2]), inc, atol=1e-9
    )


def test_point_survey_structure(point_run):
    samples = point_run.samples
    station = samples.column("station").to_numpy(zero_copy_only=False)
    position = samples.column("position").to_numpy(zero_copy_only=False)
    angle = samples.column("frame_angle").to_numpy()
    dwell = ~np.isnan(position)
    first = dwell & (station == 3)
    for j, expected in enumerate([0, 90, 180, 270, 0]):
        at = first & (position == j)
        assert at.sum() in (200, 201)  # 2 s at 100 Hz
        spread = np.ptp(np.unwrap(np.radians(angle[at])))
        assert spread < 1e-12
        rel = (angle[at][0] - angle[first & (position == 0)][0]) % 360
        assert rel == pytest.approx(expected % 360, abs=1e-9)
    mds = point_run.stations.column("md").to_numpy()
    np.testing.assert_allclose(np.diff(mds), 25.0)
    t = samples.column("time").to_numpy()
    np.testing.assert_allclose(np.diff(t), 0.01, atol=1e-12)


def finite_difference_check(run, interior: np.ndarray, sections) -> None:
    """Body rate = rotation between neighbouring samples (central, log map) + Earth rate;
    accelerometers = gravity − second difference of the position (gravity convention).
    Samples whose neighbours straddle a junction of two arcs (where the curvature, hence
    the rate, jumps) are left out: no finite difference resolves a jump."""
    truth, samples = run.truth, run.samples
    t = truth.column("time").to_numpy()
    dt = t[1] - t[0]
    angles = np.radians(columns(truth, "azi", "inc", "toolface"))
    c = Rotation.from_euler("ZYZ", angles).as_matrix()  # intrinsic: Rz(A)·Ry(I)·Rz(ψ)
    i = np.flatnonzero(interior)
    i = i[(i > 0) & (i < len(t) - 1)]
    md = truth.column("md").to_numpy()
    junctions = plan_path(sections).md0
    lo, hi = np.minimum(md[i - 1], md[i + 1]), np.maximum(md[i - 1], md[i + 1])
    straddle = ((junctions[None, :] > lo[:, None]) & (junctions[None, :] < hi[:, None])).any(1)
    assert straddle.sum() < 0.01 * len(i)
    i = i[~straddle]
    step = Rotation.from_matrix(np.einsum("nji,njk->nik", c[i - 1], c[i + 1]))
    # the rotation vector of C(t−dt)ᵀC(t+dt) is in the body frame at t−dt; bring it to t
    half = Rotation.from_matrix(np.einsum("nji,njk->nik", c[i], c[i - 1]))
    motion = half.apply(step.as_rotvec()) / (2 * dt)
    earth = np.array([np.cos(np.radians(LAT)), 0.0, -np.sin(np.radians(LAT))]) * OMEGA_EARTH
    expected = np.degrees(motion + np.einsum("nji,j->ni", c[i], earth)) * 3600
    gyro = columns(samples, "gyro_x", "gyro_y", "gyro_z")[i]
    assert np.abs(gyro).max() > 1e4  # the tool really turns (deg/h)
    assert np.abs(gyro - expected).max() < 2e-5 * np.abs(expected).max()
    pos = columns(truth, "north", "east", "tvd")
    accel = (pos[i + 1] - 2 * pos[i] + pos[i - 1]) / dt**2
    g = np.array([0.0, 0.0, normal_gravity(LAT, 120.0)])
    expected_acc = np.einsum("nji,nj->ni", c[i], g - accel)
    acc = columns(samples, "acc_x", "acc_y", "acc_z")[i]
    # 1e-3 m/s²: the second difference straddling a jerk step (end of travel) errs ~ jerk·dt/6
    assert np.abs(acc - expected_acc).max() < 1e-3
    assert np.median(np.abs(acc - expected_acc)) < 1e-7


def test_moving_tool_rates_match_finite_differences_point_mode():
    fast = {"preset": "ideal", "overrides": {"sample_rate": 1000.0}}
    run = simulate(spec({**POINT, "every": 40}, tool=fast, sections=SPHERE[:3]))
    moving = run.samples.column("position").is_null().to_numpy(zero_copy_only=False)
    finite_difference_check(run, moving, SPHERE[:3])


def test_continuous_mode_rates_and_stabilisation():
    sections = [
        {"kind": "vertical", "length": 20},
        {"kind": "build", "dls": 10.0, "inc": 40, "azi": 60},
        {"kind": "turn", "dls": 10.0, "inc": 40, "azi": 120},
        {"kind": "hold", "length": 40},
    ]
    survey = {
        "mode": "continuous",
        "start_md": 30,
        "speed": 2.0,
        "ramp_time": 3.0,
        "stop": {"dwell": 2.0, "move_time": 1.0},
        "stabilisation": {"residual": 3.0, "correlation": 2.0},
    }
    fast = {"preset": "ideal", "overrides": {"sample_rate": 1000.0}}
    run = simulate(spec(survey, sections=sections, tool=fast))
    stations = run.samples.column("station").to_numpy(zero_copy_only=False)
    moving = np.isnan(stations)
    # the servo engages (and lets go) with a step in frame rate: skip those two samples
    engage = np.zeros_like(moving)
    engage[1:-1] = moving[:-2] != moving[2:]
    finite_difference_check(run, moving & ~engage, sections)
    # the servo keeps the gyro (frame x) near the high side: toolface residual ~ N(0, 3°)
    tf = run.truth.column("toolface").to_numpy()[moving]
    residual = (tf + 180) % 360 - 180
    assert 1.0 < residual.std() < 6.0
    assert np.abs(residual).max() < 20
    md = run.truth.column("md").to_numpy()
    assert md[moving].min() >= 30 - 1e-9 and md.max() == pytest.approx(plan_path(sections).end_md)


@pytest.mark.parametrize("servo", [True, False], ids=["stabilised", "free"])
def test_a_continuous_run_records_its_closing_stop_to_the_plans_end(servo: bool) -> None:
    """The run lasts what its plan says, to the closing stop's last sample: opening stop
    (settle 2 s, five 2 s dwells, four 1 s moves: 16 s), 1 s frame move, travel of 300 m at
    2 m/s with 3 s ramps (300/2 + 3 = 153 s), closing stop (16 s, plus a 1 s move to its
    first position when the servo left the frame at an angle of its own): 186 or 187 s. Every
    position of the closing stop, the last one too, lasts its 2 s dwell."""
    survey = {
        "mode": "continuous",
        "start_md": 0,
        "end_md": 300,
        "speed": 2.0,
        "ramp_time": 3.0,
        "stop": {"dwell": 2.0, "move_time": 1.0},
        "stabilisation": {"enabled": servo},
    }
    sections = [{"kind": "vertical", "length": 100}, {"kind": "build", "dls": 3.0, "inc": 20}]
    samples = simulate(spec(survey, sections=sections)).samples
    end = 187.0 if servo else 186.0
    t = samples.column("time").to_numpy()
    assert end - 0.01 < t[-1] <= end + 1e-9  # 100 Hz: within one sample period
    station = samples.column("station").to_numpy(zero_copy_only=False)
    position = samples.column("position").to_numpy(zero_copy_only=False)
    for j in range(5):
        at = t[(station == 1) & (position == j)]
        assert at[-1] - at[0] == pytest.approx(2.0, abs=0.01), f"position {j}"
    assert position[-1] == 4 and station[-1] == 1


def plan_path(sections) -> WellPath:
    return build_path(WellPlan.model_validate({"sections": sections}))


@pytest.mark.parametrize(
    ("tool", "check"),
    [
        ({"gyro": {"noise_density": 0.05}}, "arw"),
        ({"gyro": {"bias": (3.0, 0.0, 0.0)}}, "bias"),
        ({"gyro": {"bias_trend": (2.0, 0.0, 0.0)}}, "trend"),
        ({"accelerometer": {"bias": (0.0, 0.0, 0.01)}}, "acc_bias"),
        ({"gyro": {"scale_factor": (1000.0, 0.0, 0.0)}}, "scale"),
        ({"odometer": {"scale_factor": 500.0}}, "odometer"),
    ],
)
def test_each_error_term_alone_shows_its_configured_size(tool, check):
    survey = {**POINT, "every": 100, "dwell": 60.0}
    sections = [
        {"kind": "vertical", "length": 50},
        {"kind": "build", "dls": 10, "inc": 30, "azi": 50},
    ]
    ideal = simulate(spec(survey, sections=sections, seed=9))
    errs = simulate(
        spec(survey, sections=sections, seed=9, tool={"preset": "ideal", "overrides": tool})
    )
    t = ideal.samples.column("time").to_numpy()
    d_gyro = errs.samples.column("gyro_x").to_numpy() - ideal.samples.column("gyro_x").to_numpy()
    if check == "arw":
        (adev,) = allantools.oadev(d_gyro, rate=100.0, data_type="freq", taus=[1.0])[1]
        assert adev == pytest.approx(60 * 0.05, rel=0.05)
    elif check == "bias":
        np.testing.assert_allclose(d_gyro, 3.0, atol=1e-9)
    elif check == "trend":
        np.testing.assert_allclose(d_gyro, 2.0 * t / 3600, atol=1e-9)
    elif check == "acc_bias":
        d = errs.samples.column("acc_z").to_numpy() - ideal.samples.column("acc_z").to_numpy()
        np.testing.assert_allclose(d, 0.01, atol=1e-12)
    elif check == "scale":
        np.testing.assert_allclose(
            d_gyro, 1e-3 * ideal.samples.column("gyro_x").to_numpy(), atol=1e-9
        )
    else:
        md = ideal.samples.column("md").to_numpy()
        d = errs.samples.column("md").to_numpy() - md
        np.testing.assert_allclose(d, 500e-6 * md, atol=1e-9)


def test_seed_reproducibility():
    survey = {**POINT, "every": 50}
    tool = {"preset": "mems-vrg"}
    sections = [{"kind": "vertical", "length": 60}]
    a = simulate(spec(survey, tool=tool, sections=sections, seed=1)).samples
    b = simulate(spec(survey, tool=tool, sections=sections, seed=1)).samples
    c = simulate(spec(survey, tool=tool, sections=sections, seed=2)).samples
    assert a.equals(b)
    assert not a.column("gyro_x").equals(c.column("gyro_x"))
    assert set(a.column_names) >= {"gyro_x", "acc_x", "acc_y", "acc_z"}
    assert "gyro_y" not in a.column_names and "mag_x" not in a.column_names  # single-axis tool

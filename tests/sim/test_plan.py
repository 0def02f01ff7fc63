"""Well plans: positions against minimum curvature and closed forms, derivatives against finite
differences, behaviour at vertical, and validation messages."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray
from pydantic import ValidationError

from pipeline.earth.frames import tool_axis
from pipeline.sim.plan import WellPath, WellPlan, build_path
from pipeline.survey.mincurve import minimum_curvature
from pipeline.tables import Stations

Floats = NDArray[np.float64]
TOL = 1e-9  # m
PER_DLS = np.radians(1.0) / 30.0  # rad/m of 1 deg/30m


def mincurve(md: Floats, inc_deg: Floats, azi_deg: Floats) -> Floats:
    """Minimum-curvature positions (n, 3), first station at (0, 0, md[0])."""
    r = minimum_curvature(md, np.radians(inc_deg), np.radians(azi_deg), tie_tvd=md[0])
    return np.stack([r.north, r.east, r.tvd], axis=-1)


def dogleg(inc0: float, azi0: float, inc1: float, azi1: float) -> float:
    """Angle (rad) between two attitudes (deg), haversine form."""
    i0, a0, i1, a1 = np.radians([inc0, azi0, inc1, azi1])
    hav = np.sin((i1 - i0) / 2) ** 2 + np.sin(i0) * np.sin(i1) * np.sin((a1 - a0) / 2) ** 2
    return float(2 * np.arcsin(np.sqrt(min(hav, 1.0))))


def smooth_survey(rng: np.random.Generator, n: int) -> tuple[Floats, Floats, Floats]:
    """A random smooth survey: MD (m), inclination and azimuth (deg)."""
    md = rng.uniform(0, 1000) + np.cumsum(rng.uniform(1, 60, n))
    inc = np.clip(rng.uniform(0, 60) + np.cumsum(rng.normal(0, 3, n)), 0, 150)
    azi = np.mod(rng.uniform(0, 360) + np.cumsum(rng.normal(0, 5, n)), 360)
    return md, inc, azi


def interior(path: WellPath, n: int, margin: float) -> Floats:
    """n MDs spread along the path, none within ``margin`` m of an arc joint."""
    md = np.linspace(path.start_md + margin, path.end_md - margin, n)
    joints = np.append(path.md0, path.end_md)
    far: Floats = md[np.min(np.abs(md[:, None] - joints[None, :]), axis=1) > margin]
    return far


J_WELL = WellPlan(
    sections=[
        {"kind": "vertical", "length": 500.0},
        {"kind": "build", "dls": 2.0, "inc": 45.0, "azi": 37.0},
        {"kind": "hold", "to_md": 2500.0},
    ]
)

# (section, inclination deg, azimuth deg at its end); every curve is followed by the attitude
# it reaches, so the section ends are known without the code under test
MIXED: list[tuple[dict[str, Any], float, float]] = [
    ({"kind": "vertical", "length": 300.0}, 0.0, 20.0),
    ({"kind": "build", "dls": 3.0, "inc": 30.0, "azi": 60.0}, 30.0, 60.0),
    ({"kind": "hold", "length": 250.0}, 30.0, 60.0),
    ({"kind": "turn", "dls": 2.5, "azi": 350.0}, 30.0, 350.0),
    ({"kind": "build", "dls": 4.0, "inc": 88.0, "length": 700.0}, 88.0, 350.0),
    ({"kind": "curve", "dls": 1.5, "inc": 70.0, "azi": 20.0}, 70.0, 20.0),
    ({"kind": "drop", "dls": 2.0, "inc": 10.0}, 10.0, 20.0),
    ({"kind": "drop", "dls": 2.0, "inc": 0.0, "to_md": 4000.0}, 0.0, 20.0),
]
MIXED_PLAN = WellPlan(start_md=100.0, start_azi=20.0, sections=[s for s, _, _ in MIXED])


def mixed_section_ends() -> tuple[Floats, Floats, Floats]:
    """MD, inclination, azimuth of the ends of the sections of MIXED and of the arcs within
    them, from the closed-form arc lengths."""
    md, inc, azi = [100.0], [0.0], [20.0]
    for section, end_inc, end_azi in MIXED:
        ends = []
        if "dls" in section:
            arc = dogleg(inc[-1], azi[-1], end_inc, end_azi) / (section["dls"] * PER_DLS)
            ends.append(md[-1] + arc)
        if "to_md" in section:
            ends.append(section["to_md"])
        elif "length" in section:
            ends.append(md[-1] + section["length"])
        md.extend(ends)
        inc.extend([end_inc] * len(ends))
        azi.extend([end_azi] * len(ends))
    return np.array(md), np.array(inc), np.array(azi)


# --- positions -----------------------------------------------------------------------------------


def test_j_well_lands_at_the_closed_form_position() -> None:
    path = build_path(J_WELL)
    radius = 30.0 / (2.0 * np.pi / 180.0)
    build_end = 500.0 + np.radians(45.0) * radius
    hold = 2500.0 - build_end
    np.testing.assert_allclose(path.md1, [500.0, build_end, 2500.0], rtol=0, atol=1e-12)
    azi = np.radians(37.0)
    s45 = np.sin(np.pi / 4)
    horizontal = radius * (1.0 - s45)
    at_build_end = np.array(
        [horizontal * np.cos(azi), horizontal * np.sin(azi), 500 + radius * s45]
    )
    at_td = at_build_end + hold * np.array([s45 * np.cos(azi), s45 * np.sin(azi), s45])
    state = path.evaluate([0.0, 500.0, build_end, 2500.0])
    np.testing.assert_allclose(state.position[0], [0.0, 0.0, 0.0], atol=TOL)
    np.testing.assert_allclose(state.position[1], [0.0, 0.0, 500.0], atol=TOL)
    np.testing.assert_allclose(state.position[2], at_build_end, atol=TOL)
    np.testing.assert_allclose(state.position[3], at_td, atol=TOL)
    np.testing.assert_allclose(np.degrees(state.inc), [0.0, 0.0, 45.0, 45.0], atol=1e-12)


def test_section_ends_equal_minimum_curvature() -> None:
    md, inc, azi = mixed_section_ends()
    path = build_path(MIXED_PLAN)
    assert md.size == 11  # two of the eight sections are an arc and a hold
    np.testing.assert_allclose(np.append(path.md0, path.end_md), md, rtol=1e-13)
    state = path.evaluate(md)
    np.testing.assert_allclose(state.position, mincurve(md, inc, azi), rtol=0, atol=TOL)
    np.testing.assert_allclose(
        state.tangent, tool_axis(np.radians(azi), np.radians(inc)), atol=1e-12
    )


def test_from_stations_reproduces_minimum_curvature() -> None:
    rng = np.random.default_rng(11)
    for n in (2, 3, 50, 400):
        md, inc, azi = smooth_survey(rng, n)
        path = WellPath.from_stations(md, inc, azi)
        state = path.evaluate(md)
        np.testing.assert_allclose(state.position, mincurve(md, inc, azi), rtol=0, atol=TOL)
        expected = tool_axis(np.radians(azi), np.radians(inc))
        np.testing.assert_allclose(state.tangent, expected, rtol=0, atol=1e-12)


attitudes = st.tuples(st.floats(0.0, 180.0), st.floats(-720.0, 720.0))


@settings(max_examples=300, deadline=None, derandomize=True)
@given(start=attitudes, end=attitudes, length=st.floats(0.01, 500.0))
def test_any_arc_is_the_minimum_curvature_arc(
    start: tuple[float, float], end: tuple[float, float], length: float
) -> None:
    beta = dogleg(*start, *end)
    if beta > np.pi - 2e-3:
        return  # a reversal: rejected, see test_from_stations_rejects_bad_surveys
    md = np.array([1000.0, 1000.0 + length])
    inc, azi = np.array([start[0], end[0]]), np.array([start[1], end[1]])
    path = WellPath.from_stations(md, inc, azi)
    s = np.linspace(md[0], md[1], 7)
    state = path.evaluate(s)
    np.testing.assert_allclose(state.position[[0, -1]], mincurve(md, inc, azi), atol=TOL)
    np.testing.assert_allclose(
        state.tangent[-1], tool_axis(*np.radians([end[1], end[0]])), atol=1e-12
    )
    # the tangent turns at a constant rate in one plane
    np.testing.assert_allclose(np.linalg.norm(state.tangent, axis=1), 1.0, rtol=1e-14)
    turned = 2 * np.arcsin(np.linalg.norm(state.tangent - state.tangent[0], axis=1) / 2)
    np.testing.assert_allclose(turned, beta * (s - md[0]) / length, atol=1e-9)
    assert np.isfinite(state.sin_inc_dazi).all()
    assert np.isfinite(state.dinc).all()


def test_tiny_doglegs_have_no_cancellation() -> None:
    for beta in (1e-7, 1e-10, 1e-13):
        inc = np.array([30.0, 30.0 + np.degrees(beta)])
        md = np.array([0.0, 80.0])
        azi = np.array([45.0, 45.0])
        state = WellPath.from_stations(md, inc, azi).evaluate(np.linspace(0, 80, 9))
        np.testing.assert_allclose(state.position[-1], mincurve(md, inc, azi)[-1], atol=TOL)
        curvature = np.linalg.norm(state.dtangent, axis=1)
        if beta >= 1e-12:
            np.testing.assert_allclose(curvature, beta / 80.0, rtol=1e-6)
        else:  # below STRAIGHT_BELOW the piece is straight
            np.testing.assert_array_equal(curvature, 0.0)


def test_tie_in() -> None:
    plan = J_WELL.model_copy(update={"start_md": 120.0})
    assert build_path(plan).evaluate(120.0).position.tolist() == [[0.0, 0.0, 120.0]]
    moved = J_WELL.model_copy(update={"start_north": 5.0, "start_east": -3.0, "start_tvd": 2.0})
    delta = build_path(moved).evaluate([0.0, 2500.0]).position
    delta -= build_path(J_WELL).evaluate([0.0, 2500.0]).position
    np.testing.assert_allclose(delta, [[5.0, -3.0, 2.0]] * 2, atol=TOL)
    path = WellPath.from_stations([80.0, 100.0], [0.0, 2.0], [0.0, 0.0], start_tvd=79.5)
    assert path.evaluate(80.0).position.tolist() == [[0.0, 0.0, 79.5]]
    assert WellPath.from_stations([80.0, 100.0], [0.0, 0.0], [0.0, 0.0]).r0[0, 2] == 80.0


def test_stations_table_round_trips() -> None:
    path = build_path(MIXED_PLAN)
    joints = np.append(path.md0, path.end_md)
    table = path.stations(joints)
    Stations.validate_table(table)
    assert table.schema.field("azi").metadata[b"north_reference"] == b"true"
    again = WellPath.from_stations(
        table.column("md").to_numpy(),
        table.column("inc").to_numpy(),
        table.column("azi").to_numpy(),
    )
    md = interior(path, 500, 0.0)
    np.testing.assert_allclose(again.evaluate(md).position, path.evaluate(md).position, atol=TOL)


def test_azimuth_turns_the_short_way_round() -> None:
    plan = WellPlan(
        start_inc=30.0, start_azi=350.0, sections=[{"kind": "turn", "dls": 2.0, "azi": 10.0}]
    )
    path = build_path(plan)
    beta = dogleg(30.0, 350.0, 30.0, 10.0)
    assert path.end_md == pytest.approx(beta / (2.0 * PER_DLS), rel=1e-12)
    azi = np.degrees(path.evaluate(np.linspace(0, path.end_md, 101)).azi)
    assert ((azi >= 350.0 - 1e-9) | (azi <= 10.0 + 1e-9)).all()


def test_evaluates_hundreds_of_thousands_of_mds_at_once() -> None:
    path = build_path(MIXED_PLAN)
    md = np.linspace(path.start_md, path.end_md, 360_000)
    state = path.evaluate(md)
    assert state.position.shape == state.d2tangent.shape == (360_000, 3)
    assert state.dazi.shape == (360_000,)
    assert np.isfinite(state.position).all()
    assert np.isfinite(state.dazi).all()


# --- derivatives ---------------------------------------------------------------------------------


def test_curvature_is_the_section_dls_and_zero_on_holds() -> None:
    path = build_path(MIXED_PLAN)
    curvature = {0: 0.0, 1: 3.0, 2: 0.0, 3: 2.5, 4: 4.0, 5: 0.0, 6: 1.5, 7: 2.0, 8: 2.0, 9: 0.0}
    joints = np.append(path.md0, path.end_md)
    for arc, dls in curvature.items():
        s = np.linspace(joints[arc], joints[arc + 1], 25)[1:-1]
        state = path.evaluate(s)
        np.testing.assert_allclose(
            np.linalg.norm(state.dtangent, axis=1), dls * PER_DLS, rtol=1e-12, atol=1e-18
        )
        np.testing.assert_allclose(np.linalg.norm(state.tangent, axis=1), 1.0, rtol=1e-14)


@pytest.mark.parametrize("source", ["plan", "stations"])
def test_derivatives_match_finite_differences(source: str) -> None:
    if source == "plan":
        path = build_path(MIXED_PLAN)
    else:
        md, inc, azi = smooth_survey(np.random.default_rng(5), 60)
        path = WellPath.from_stations(md, np.clip(inc, 5, 150), azi)
    h = 1e-3
    s = interior(path, 3000, 2 * h)
    at, ahead, behind = path.evaluate(s), path.evaluate(s + h), path.evaluate(s - h)

    def central(name: str) -> Floats:
        diff: Floats = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        return diff

    kappa = np.max(np.linalg.norm(at.dtangent, axis=1))
    np.testing.assert_allclose(central("position"), at.tangent, rtol=0, atol=1e-9)
    np.testing.assert_allclose(central("tangent"), at.dtangent, rtol=0, atol=1e-6 * kappa)
    np.testing.assert_allclose(central("dtangent"), at.d2tangent, rtol=0, atol=1e-6 * kappa**2)
    level = np.sin(at.inc) > 0.05  # away from vertical
    np.testing.assert_allclose(central("inc")[level], at.dinc[level], rtol=1e-6, atol=1e-6 * kappa)
    dazi = np.angle(np.exp(1j * (ahead.azi - behind.azi))) / (2 * h)
    np.testing.assert_allclose(dazi[level], at.dazi[level], rtol=1e-6, atol=1e-6 * kappa / 0.05)
    np.testing.assert_allclose(
        at.sin_inc_dazi[level], np.sin(at.inc[level]) * at.dazi[level], rtol=1e-12, atol=1e-20
    )


def test_build_from_vertical() -> None:
    plan = WellPlan(
        sections=[
            {"kind": "vertical", "length": 100.0},
            {"kind": "build", "dls": 3.0, "inc": 30.0, "azi": 120.0},
        ]
    )
    path = build_path(plan)
    state = path.evaluate([0.0, 50.0, 100.0, 100.0 + 1e-9, 150.0, path.end_md])
    # on the vertical section the nominal azimuth, from the kick-off on the build's azimuth
    np.testing.assert_allclose(np.degrees(state.azi), [0.0, 0.0, 120.0, 120.0, 120.0, 120.0])
    np.testing.assert_allclose(state.inc[:3], 0.0, atol=0)
    np.testing.assert_allclose(state.dinc, [0, 0] + [3.0 * PER_DLS] * 4, rtol=1e-12)
    np.testing.assert_allclose(state.dazi, 0.0, atol=1e-15)
    np.testing.assert_allclose(state.sin_inc_dazi, 0.0, atol=1e-15)


def test_low_inclination_turn() -> None:
    plan = WellPlan(start_inc=2.0, sections=[{"kind": "turn", "dls": 1.0, "azi": 90.0}])
    path = build_path(plan)
    md = np.linspace(0.0, path.end_md, 201)
    state = path.evaluate(md)
    assert np.isfinite(state.sin_inc_dazi).all()
    # the great circle between the two attitudes: compare with sin I · dA/ds by differences
    h = 1e-4
    s = md[1:-1]
    dazi = np.angle(np.exp(1j * (path.evaluate(s + h).azi - path.evaluate(s - h).azi))) / (2 * h)
    np.testing.assert_allclose(state.sin_inc_dazi[1:-1], np.sin(state.inc[1:-1]) * dazi, rtol=1e-6)
    assert state.inc.min() < np.radians(2.0)  # the arc dips towards vertical mid-way
    np.testing.assert_allclose(np.degrees(state.azi[[0, -1]]), [0.0, 90.0], atol=1e-9)


def test_arc_through_vertical() -> None:
    """A 'turn' by 180° at 0.5° inclination is a 1° arc in a vertical plane through vertical."""
    plan = WellPlan(start_inc=0.5, sections=[{"kind": "turn", "dls": 1.0, "azi": 180.0}])
    path = build_path(plan)
    assert path.end_md == pytest.approx(30.0, rel=1e-12)
    state = path.evaluate([0.0, 10.0, 15.0, 20.0, 30.0])
    kappa = PER_DLS
    np.testing.assert_allclose(np.degrees(state.inc), [0.5, 1 / 6, 0.0, 1 / 6, 0.5], atol=1e-12)
    np.testing.assert_allclose(np.degrees(state.azi), [0.0, 0.0, 180.0, 180.0, 180.0], atol=1e-9)
    np.testing.assert_allclose(state.dinc, [-kappa, -kappa, kappa, kappa, kappa], rtol=1e-9)
    np.testing.assert_allclose(state.sin_inc_dazi, 0.0, atol=1e-15)
    np.testing.assert_array_equal(state.dazi[2], 0.0)


# --- validation ----------------------------------------------------------------------------------

BAD_PLANS = [
    (
        {
            "start_inc": 10.0,
            "sections": [{"kind": "hold", "length": 10}, {"kind": "vertical", "length": 10}],
        },
        r"sections\[1\] \(vertical\): kind: the current inclination is 10.0 deg",
    ),
    (
        {"start_inc": 30.0, "sections": [{"kind": "build", "dls": 2, "inc": 20}]},
        r"sections\[0\] \(build\): inc: target 20.0 deg is below the current 30.0 deg",
    ),
    (
        {"start_inc": 30.0, "sections": [{"kind": "drop", "dls": 2, "inc": 40}]},
        r"sections\[0\] \(drop\): inc: target 40.0 deg is above",
    ),
    (
        {
            "sections": [
                {"kind": "vertical", "length": 100},
                {"kind": "build", "dls": 3, "inc": 15, "length": 100},
            ]
        },
        r"sections\[1\] \(build\): needs 15.0 deg of dogleg at dls 3.0 deg/30m = 150.0 m, "
        r"but length is 100.0 m",
    ),
    (
        {"sections": [{"kind": "build", "dls": 3, "inc": 15, "to_md": 100}]},
        r"sections\[0\] \(build\): needs 15.0 deg .* = 150.0 m, but to_md leaves 100.0 m",
    ),
    (
        {"sections": [{"kind": "vertical", "to_md": 500}, {"kind": "hold", "to_md": 400}]},
        r"sections\[1\] \(hold\): to_md: 400.0 m is not beyond the current MD 500.0 m",
    ),
    (
        {"sections": [{"kind": "vertical", "to_md": 500}, {"kind": "build", "inc": 10}]},
        r"sections\[1\] \(build\): dls: required",
    ),
    (
        {"sections": [{"kind": "hold", "length": 10, "dls": 2}]},
        r"sections\[0\] \(hold\): dls: not allowed",
    ),
    (
        {"sections": [{"kind": "hold", "length": 10, "azi": 2}]},
        r"sections\[0\] \(hold\): azi: not allowed",
    ),
    (
        {"sections": [{"kind": "hold"}]},
        r"sections\[0\] \(hold\): length/to_md: one of them is required",
    ),
    (
        {"sections": [{"kind": "hold", "length": 5, "to_md": 5}]},
        r"sections\[0\] \(hold\): length/to_md: give one, not both",
    ),
    (
        {"start_inc": 90, "sections": [{"kind": "curve", "dls": 2, "azi": 180}]},
        r"sections\[0\] \(curve\): inc/azi: .* reverses the hole",
    ),
    (
        {"start_inc": 30, "sections": [{"kind": "curve", "dls": 2, "inc": 30.0, "azi": 360}]},
        r"sections\[0\] \(curve\): inc/azi: .* is the current attitude, so the section has zero length",
    ),
    (
        {"start_inc": 30, "sections": [{"kind": "turn", "dls": 2, "inc": 35, "azi": 10}]},
        r"sections\[0\] \(turn\): inc: a turn keeps the inclination",
    ),
    (
        {"start_inc": 30, "sections": [{"kind": "turn", "dls": 2, "azi": -360}]},
        r"sections\[0\] \(turn\): azi: a turn must change the azimuth",
    ),
    (
        {"sections": [{"kind": "turn", "dls": 2, "azi": 90}]},
        r"sections\[0\] \(turn\): inc: a turn needs an inclined hole",
    ),
    (
        {"sections": [{"kind": "hold", "length": 5}, {"kind": "spiral", "length": 5}]},
        r"sections\.1\.kind\n  Input should be 'vertical', 'hold'",
    ),
    (
        {"sections": [{"kind": "hold", "length": 5, "speed": 3}]},
        r"sections\.0\.speed\n  Extra inputs are not permitted",
    ),
    (
        {"sections": [{"kind": "build", "dls": float("nan"), "inc": 3}]},
        r"sections\.0\.dls\n  Input should be a finite number",
    ),
    ({"sections": []}, r"sections\n  List should have at least 1 item"),
]


@pytest.mark.parametrize(("plan", "message"), BAD_PLANS)
def test_invalid_plans_name_section_and_field(plan: dict[str, Any], message: str) -> None:
    with pytest.raises(ValidationError, match=message):
        WellPlan.model_validate(plan)


def test_a_curve_with_no_turn_but_a_length_is_a_hold() -> None:
    plan = WellPlan(start_inc=30, sections=[{"kind": "build", "dls": 2, "length": 40}])
    path = build_path(plan)
    assert path.beta.tolist() == [0.0]
    assert path.end_md == 40.0


@pytest.mark.parametrize(
    ("md", "inc", "azi", "message"),
    [
        ([0.0], [0.0], [0.0], "equal length >= 2"),
        ([0.0, 10.0], [0.0], [0.0, 0.0], "equal length >= 2"),
        ([0.0, 10.0, 10.0], [0.0] * 3, [0.0] * 3, "md: must increase strictly; station 2"),
        ([0.0, 10.0], [0.0, np.nan], [0.0, 0.0], "inc: station 1 is not finite"),
        ([0.0, 10.0], [0.0, 181.0], [0.0, 0.0], r"inc: station 1 is 181.0 deg, outside \[0, 180\]"),
        ([0.0, 10.0, 20.0], [0.0, 90.0, 90.0], [0.0, 0.0, 180.0], "station 2 .* reversal"),
    ],
)
def test_from_stations_rejects_bad_surveys(
    md: list[float], inc: list[float], azi: list[float], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        WellPath.from_stations(md, inc, azi)


@pytest.mark.parametrize("md", [-1.0, 2500.5, np.nan])
def test_evaluate_refuses_mds_outside_the_path(md: float) -> None:
    with pytest.raises(ValueError, match=r"outside the path \[0.0, 2500.0\] m"):
        build_path(J_WELL).evaluate([10.0, md])

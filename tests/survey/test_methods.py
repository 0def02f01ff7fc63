"""Legacy survey methods against their closed forms; build/turn rates; the survey_method stage."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from pipeline.stages.stations import MethodTrajectory, SurveyMethodParams, survey_method
from pipeline.survey.methods import METHODS, build_turn_rates, survey_positions
from pipeline.tables import Stations
from pipeline.well import WellMetadata

Floats = NDArray[np.float64]


def step(method: str, i1: float, a1: float, i2: float, a2: float, L: float = 30.0) -> Floats:
    r = survey_positions(method, [100.0, 100.0 + L], [i1, i2], [a1, a2])  # type: ignore[arg-type]
    return np.array([r.north[1], r.east[1], r.tvd[1] - r.tvd[0]])


def t(i: float, a: float) -> Floats:
    return np.array([np.sin(i) * np.cos(a), np.sin(i) * np.sin(a), np.cos(i)])


I1, A1, I2, A2 = 0.4, 1.1, 0.55, 1.3


def test_tangential_uses_lower_station() -> None:
    np.testing.assert_allclose(step("tangential", I1, A1, I2, A2), 30.0 * t(I2, A2), atol=1e-12)


def test_balanced_tangential_averages_tangents() -> None:
    expected = 15.0 * (t(I1, A1) + t(I2, A2))
    np.testing.assert_allclose(step("balanced_tangential", I1, A1, I2, A2), expected, atol=1e-12)


def test_average_angle_uses_mean_angles() -> None:
    expected = 30.0 * t(0.5 * (I1 + I2), 0.5 * (A1 + A2))
    np.testing.assert_allclose(step("average_angle", I1, A1, I2, A2), expected, atol=1e-12)


def test_average_angle_wraps_azimuth_through_north() -> None:
    a1, a2 = np.radians(350.0), np.radians(10.0)
    np.testing.assert_allclose(
        step("average_angle", I1, a1, I2, a2), 30.0 * t(0.5 * (I1 + I2), 0.0), atol=1e-12
    )


def test_radius_of_curvature_textbook() -> None:
    L = 30.0
    di, da = I2 - I1, A2 - A1
    expected = np.array(
        [
            L * (np.cos(I1) - np.cos(I2)) * (np.sin(A2) - np.sin(A1)) / (di * da),
            L * (np.cos(I1) - np.cos(I2)) * (np.cos(A1) - np.cos(A2)) / (di * da),
            L * (np.sin(I2) - np.sin(I1)) / di,
        ]
    )
    np.testing.assert_allclose(step("radius_of_curvature", I1, A1, I2, A2), expected, atol=1e-12)


def test_radius_of_curvature_degenerate_cases() -> None:
    L = 30.0
    # equal inclinations: H = L sin I, ΔTVD = L cos I
    h = L * np.sin(I1)
    da = A2 - A1
    expected = np.array(
        [h * (np.sin(A2) - np.sin(A1)) / da, h * (np.cos(A1) - np.cos(A2)) / da, L * np.cos(I1)]
    )
    np.testing.assert_allclose(step("radius_of_curvature", I1, A1, I1, A2), expected, atol=1e-12)
    # equal azimuths: ΔN = H cos A, ΔE = H sin A
    di = I2 - I1
    h = L * (np.cos(I1) - np.cos(I2)) / di
    expected = np.array([h * np.cos(A1), h * np.sin(A1), L * (np.sin(I2) - np.sin(I1)) / di])
    np.testing.assert_allclose(step("radius_of_curvature", I1, A1, I2, A1), expected, atol=1e-12)
    # both equal: a straight line
    np.testing.assert_allclose(
        step("radius_of_curvature", I1, A1, I1, A1), L * t(I1, A1), atol=1e-12
    )


def test_straight_hole_all_methods_agree() -> None:
    md = np.array([0.0, 25.0, 80.0, 80.5, 300.0])
    inc = np.full(5, 0.7)
    azi = np.full(5, 2.2)
    expected = (md - md[0])[:, None] * t(0.7, 2.2)[None, :]
    for method in METHODS:
        r = survey_positions(method, md, inc, azi)
        got = np.stack([r.north, r.east, r.tvd], axis=-1)
        np.testing.assert_allclose(got, expected, atol=1e-9, err_msg=method)
        np.testing.assert_array_equal(r.dogleg, 0.0)


def arc_error(method: str, n: int) -> float:
    """Max position error on a circular arc (build 3°/30 m from vertical to 90°, azimuth 40°)."""
    kappa = np.radians(3.0) / 30.0
    s = np.linspace(0.0, np.radians(90.0) / kappa, n)
    inc = kappa * s
    azi = np.full(n, np.radians(40.0))
    r = survey_positions(method, s, inc, azi)  # type: ignore[arg-type]
    h = (1.0 - np.cos(inc)) / kappa
    exact = np.stack([h * np.cos(azi), h * np.sin(azi), np.sin(inc) / kappa], axis=-1)
    got = np.stack([r.north, r.east, r.tvd], axis=-1)
    return float(np.abs(got - exact).max())


def test_circular_arc_min_curvature_exact_others_converge() -> None:
    assert arc_error("minimum_curvature", 10) < 1e-9
    # radius of curvature is exact on an arc in a vertical plane, too
    assert arc_error("radius_of_curvature", 10) < 1e-9
    for method in ("tangential", "balanced_tangential", "average_angle"):
        errors = [arc_error(method, n) for n in (10, 40, 160)]
        assert errors[0] > errors[1] > errors[2], method
        # tangential is first order in the step, the others second order
        shrink = 10.0 if method == "tangential" else 200.0
        assert errors[2] < errors[0] / shrink, (method, errors)


def test_batch_matches_individual_surveys() -> None:
    rng = np.random.default_rng(3)
    md = np.concatenate(
        [np.cumsum(rng.uniform(5, 40, 7)), 1000.0 + np.cumsum(rng.uniform(5, 40, 5))]
    )
    inc = rng.uniform(0.0, 1.5, 12)
    azi = rng.uniform(0.0, 2 * np.pi, 12)
    offsets = np.array([0, 7, 12])
    for method in METHODS:
        batch = survey_positions(method, md, inc, azi, offsets=offsets, tie_tvd=[1.0, 2.0])
        for (lo, hi), tie in zip([(0, 7), (7, 12)], [1.0, 2.0], strict=True):
            alone = survey_positions(method, md[lo:hi], inc[lo:hi], azi[lo:hi], tie_tvd=tie)
            np.testing.assert_allclose(batch.tvd[lo:hi], alone.tvd, atol=1e-9)
            np.testing.assert_allclose(batch.north[lo:hi], alone.north, atol=1e-9)
            np.testing.assert_allclose(batch.dls[lo:hi], alone.dls, atol=1e-15)


def test_unknown_method() -> None:
    with pytest.raises(ValueError, match="unknown survey method"):
        survey_positions("bogus", [0.0, 1.0], [0.0, 0.0], [0.0, 0.0])  # type: ignore[arg-type]


def test_build_turn_rates() -> None:
    md = np.array([100.0, 130.0, 190.0])
    inc = np.radians([10.0, 13.0, 12.0])
    azi = np.radians([355.0, 5.0, 2.0])
    build, turn = build_turn_rates(md, inc, azi)
    np.testing.assert_allclose(build, [0.0, 3.0, -0.5], atol=1e-12)
    np.testing.assert_allclose(turn, [0.0, 10.0, -1.5], atol=1e-12)  # through north: +10°
    build, _ = build_turn_rates(md, inc, azi, offsets=np.array([0, 1, 3]))
    np.testing.assert_allclose(build, [0.0, 0.0, -0.5], atol=1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_survey_method_stage(method: str) -> None:
    stations = Stations.compiled().make_table(
        {
            "md": [0.0, 30.0, 60.0, 90.0],
            "inc": [0.0, 3.0, 6.0, 9.0],
            "azi": [0.0, 10.0, 20.0, 30.0],
        },
        north_reference="grid",
    )
    ctx: Any = SimpleNamespace(well=WellMetadata())
    out = survey_method({"stations": stations}, SurveyMethodParams(method=method), ctx)[
        "trajectory"
    ]  # type: ignore[arg-type]
    MethodTrajectory.compiled().validate(out)
    assert out.schema.field("azi").metadata[b"north_reference"] == b"grid"
    np.testing.assert_allclose(out.column("build").to_numpy(), [0.0, 3.0, 3.0, 3.0])
    np.testing.assert_allclose(out.column("turn").to_numpy(), [0.0, 10.0, 10.0, 10.0])
    assert out.column("tvd").to_numpy()[0] == 0.0

"""Interpolation on the minimum-curvature arc, at MDs and at TVDs (every crossing)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from pipeline.sim.plan import WellPath
from pipeline.stages.stations import (
    InterpolateMdParams,
    InterpolateTvdParams,
    PathPoints,
    SurveyMethodParams,
    TvdCrossings,
    interpolate_md_stage,
    interpolate_tvd_stage,
    survey_method,
)
from pipeline.survey.interpolate import interpolate_md, interpolate_tvd
from pipeline.tables import Stations
from pipeline.well import WellMetadata

Floats = NDArray[np.float64]
TOL = 1e-9


def smooth_survey(seed: int, n: int = 30) -> tuple[Floats, Floats, Floats]:
    """MD m, inc and azi deg; includes a straight step and a near-straight one."""
    rng = np.random.default_rng(seed)
    md = 200.0 + np.cumsum(rng.uniform(5.0, 60.0, n))
    inc = np.clip(5.0 + np.cumsum(rng.normal(2.0, 3.0, n)), 0.0, 120.0)
    azi = np.mod(30.0 + np.cumsum(rng.normal(0.0, 8.0, n)), 360.0)
    inc[5], azi[5] = inc[4], azi[4]  # straight
    inc[8], azi[8] = inc[7] + 1e-7, azi[7]  # near-straight
    return md, inc, azi


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_points_lie_on_the_arc(seed: int) -> None:
    md, inc, azi = smooth_survey(seed)
    path = WellPath.from_stations(md, inc, azi, start_north=3.0, start_east=-2.0, start_tvd=190.0)
    rng = np.random.default_rng(seed + 10)
    at = np.concatenate([rng.uniform(md[0], md[-1], 500), [md[0], md[-1]]])
    got = interpolate_md(md, np.radians(inc), np.radians(azi), at, tie=(3.0, -2.0, 190.0))
    ref = path.evaluate(at)
    pos = np.stack([got.north, got.east, got.tvd], axis=-1)
    np.testing.assert_allclose(pos, ref.position, atol=TOL, rtol=0)
    t = np.stack(
        [np.sin(got.inc) * np.cos(got.azi), np.sin(got.inc) * np.sin(got.azi), np.cos(got.inc)],
        axis=-1,
    )
    np.testing.assert_allclose(t, ref.tangent, atol=1e-12)
    np.testing.assert_array_equal(got.md, at)
    np.testing.assert_array_equal(got.target, np.arange(at.size))


def test_stations_reproduced_exactly() -> None:
    md, inc, azi = smooth_survey(4)
    inc_r, azi_r = np.radians(inc), np.radians(azi)
    got = interpolate_md(md, inc_r, azi_r, md[::-1])
    from pipeline.survey.mincurve import minimum_curvature

    mc = minimum_curvature(md, inc_r, azi_r)
    np.testing.assert_array_equal(got.inc, inc_r[::-1])
    np.testing.assert_array_equal(got.azi, np.mod(azi_r, 2 * np.pi)[::-1])
    np.testing.assert_array_equal(got.tvd, mc.tvd[::-1])
    np.testing.assert_array_equal(got.north, mc.north[::-1])


def test_outside_range_rejected() -> None:
    with pytest.raises(ValueError, match="outside"):
        interpolate_md([0.0, 10.0], [0.0, 0.1], [0.0, 0.0], [10.5])


def wavy_horizontal() -> tuple[Floats, Floats, Floats]:
    """Build to horizontal, then undulate above and below 90° (TVD rises and falls)."""
    md = np.array([0.0, 300.0, 900.0, 1100.0, 1300.0, 1500.0, 1700.0, 1900.0])
    inc = np.array([0.0, 0.0, 90.0, 94.0, 86.0, 94.0, 86.0, 90.0])
    azi = np.full(md.size, 45.0)
    return md, inc, azi


def test_tvd_crossings_on_undulating_well() -> None:
    md, inc, azi = wavy_horizontal()
    path = WellPath.from_stations(md, inc, azi, start_tvd=0.0)
    dense = np.linspace(md[0], md[-1], 200001)
    z = path.evaluate(dense).position[:, 2]
    tail = z[dense >= 900.0]
    target = float(0.5 * (tail.min() + tail.max()))
    expected = int(np.count_nonzero(np.diff(np.sign(z - target)) != 0))
    assert expected >= 3
    got = interpolate_tvd(md, np.radians(inc), np.radians(azi), [target, 100.0])
    for_target = got.target == 0
    assert np.count_nonzero(for_target) == expected
    np.testing.assert_allclose(got.tvd[for_target], target, atol=TOL)
    assert np.all(np.diff(got.md) > 0)
    ref = path.evaluate(got.md).position
    np.testing.assert_allclose(np.stack([got.north, got.east, got.tvd], -1), ref, atol=TOL)
    # the vertical section crosses 100 m once
    assert np.count_nonzero(got.target == 1) == 1
    np.testing.assert_allclose(got.md[got.target == 1], 100.0, atol=TOL)


def test_tvd_at_station_reported_once_and_out_of_range_empty() -> None:
    md, inc, azi = wavy_horizontal()
    mcz = WellPath.from_stations(md, inc, azi, start_tvd=0.0).evaluate(md[1:2]).position[0, 2]
    got = interpolate_tvd(md, np.radians(inc), np.radians(azi), [mcz, 1e6])
    assert got.md.size == 1
    assert got.md[0] == md[1]


def test_tvd_crossings_of_an_arc_through_horizontal() -> None:
    # one arc from 80° to 110° inc: TVD rises after 90° -> a target just above the max is missed,
    # just below it is crossed twice
    md, inc, azi = np.array([0.0, 300.0]), np.radians([80.0, 110.0]), np.array([0.3, 0.3])
    path = WellPath.from_stations(md, np.degrees(inc), np.degrees(azi), start_tvd=0.0)
    zmax = path.evaluate(np.linspace(0, 300, 100001)).position[:, 2].max()
    assert interpolate_tvd(md, inc, azi, [zmax + 1e-3]).md.size == 0
    got = interpolate_tvd(md, inc, azi, [zmax - 1.0])
    assert got.md.size == 2
    np.testing.assert_allclose(got.tvd, zmax - 1.0, atol=TOL)


def trajectory_table() -> Any:
    md, inc, azi = wavy_horizontal()
    stations = Stations.compiled().make_table(
        {
            "survey": ["a"] * md.size + ["b"] * 3,
            "md": np.concatenate([md, [0.0, 50.0, 100.0]]),
            "inc": np.concatenate([inc, [0.0, 5.0, 10.0]]),
            "azi": np.concatenate([azi, [0.0, 0.0, 0.0]]),
        },
        north_reference="true",
    )
    ctx: Any = SimpleNamespace(well=WellMetadata(), stage_id="stage")
    return survey_method({"stations": stations}, SurveyMethodParams(), ctx)["trajectory"], ctx


def test_interpolate_md_stage() -> None:
    traj, ctx = trajectory_table()
    params = InterpolateMdParams(md=[25.0, 1000.0], spacing=500.0)
    out = interpolate_md_stage({"trajectory": traj}, params, ctx)["points"]
    PathPoints.compiled().validate(out)
    assert out.column("survey").to_pylist() == ["a"] * 5 + ["b"] * 2
    assert out.column("md").to_pylist() == [0.0, 25.0, 500.0, 1000.0, 1500.0, 0.0, 25.0]
    assert out.schema.field("azi").metadata[b"north_reference"] == b"true"


def test_interpolate_md_params_need_something() -> None:
    with pytest.raises(ValueError, match="give md"):
        InterpolateMdParams()


def test_interpolate_tvd_stage() -> None:
    traj, ctx = trajectory_table()
    out = interpolate_tvd_stage({"trajectory": traj}, InterpolateTvdParams(tvd=[60.0]), ctx)[
        "crossings"
    ]
    TvdCrossings.compiled().validate(out)
    assert out.column("survey").to_pylist() == ["a", "b"]
    np.testing.assert_allclose(out.column("tvd").to_numpy(), 60.0, atol=TOL)
    np.testing.assert_array_equal(out.column("target_tvd").to_numpy(), 60.0)

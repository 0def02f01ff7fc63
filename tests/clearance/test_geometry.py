"""Closest approach to a minimum-curvature path against an independent search: a bounded
Brent minimisation of the distance along every step, positions from the path interpolation
(the distance to a circular arc of less than π is unimodal along it)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from pipeline.anticollision.geometry import closest_points
from pipeline.survey.interpolate import MinCurvePath, interpolate_md


def random_well(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    """MD (m), inclination, azimuth (rad) of a wandering well with irregular courses (some
    long, some straight)."""
    md = np.concatenate([[0.0], np.cumsum(rng.choice([5.0, 30.0, 30.0, 120.0], n - 1))])
    inc = np.clip(np.cumsum(rng.normal(0.0, 0.08, n)), 0.0, 2.5)
    azi = np.mod(np.cumsum(rng.normal(0.0, 0.15, n)) + 1.0, 2 * np.pi)
    straight = rng.random(n) < 0.2
    inc[1:][straight[1:]] = inc[:-1][straight[1:]]
    azi[1:][straight[1:]] = azi[:-1][straight[1:]]
    return md, inc, azi


def brute_force(path: MinCurvePath, point: np.ndarray) -> float:
    """Least distance from ``point`` to the path, course by course."""
    best = np.inf
    for k in range(path.length.size):
        step = np.array([k], dtype=np.intp)

        def dist(f: float, step: np.ndarray = step) -> float:
            return float(np.linalg.norm(path.position(step, np.array([f]))[:, 0] - point))

        res = minimize_scalar(dist, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-12})
        best = min(best, res.fun, dist(0.0), dist(1.0))
    return float(best)


@pytest.mark.parametrize("seed", range(3))
def test_closest_point_is_the_least_distance_on_the_path(seed: int):
    rng = np.random.default_rng(seed)
    md, inc, azi = random_well(rng, 25)
    path = MinCurvePath(md, inc, azi, (0.0, 0.0, 0.0))
    centre = path.r.T[rng.integers(0, md.size, 8)]
    points = centre + rng.normal(0.0, 60.0, (8, 3))
    found = closest_points(path, points)
    for k, point in enumerate(points):
        expected = brute_force(path, point)
        got = float(np.linalg.norm(found.position[k] - point))
        assert got == pytest.approx(expected, abs=1e-6)
        on_path = interpolate_md(md, inc, azi, [found.md[k]])
        where = np.array([on_path.north[0], on_path.east[0], on_path.tvd[0]])
        assert np.linalg.norm(where - found.position[k]) < 1e-9
        assert found.md[k] == pytest.approx(
            md[found.step[k]] + found.fraction[k] * (md[found.step[k] + 1] - md[found.step[k]])
        )


def test_closest_point_mid_course_beats_a_nearer_station_elsewhere():
    """A long straight course passes 10 m from the point while its end stations are 300 m
    away; a station of another part of the well is 50 m away: the course's mid-point is the
    closest approach, not anything next to the nearest station."""
    # down 1000 m, then build to horizontal heading north and run 600 m, turn back south
    md = np.array([0.0, 1000.0, 1600.0, 1700.0, 2200.0])
    inc = np.radians([0.0, 0.0, 90.0, 90.0, 90.0])
    azi = np.radians([0.0, 0.0, 0.0, 0.0, 0.0])
    path = MinCurvePath(md, inc, azi, (0.0, 0.0, 0.0))
    point = np.array([[path.r[0, 3] + 250.0, 10.0, path.r[2, 3]]])
    found = closest_points(path, point)
    assert found.step[0] == 3
    assert np.linalg.norm(found.position[0] - point[0]) == pytest.approx(10.0, abs=1e-9)
    assert found.md[0] == pytest.approx(1950.0, abs=1e-9)


def test_points_on_the_path_are_found_at_their_md():
    rng = np.random.default_rng(7)
    md, inc, azi = random_well(rng, 30)
    targets = np.sort(rng.uniform(md[0], md[-1], 40))
    on = interpolate_md(md, inc, azi, targets)
    found = closest_points(
        MinCurvePath(md, inc, azi, (0.0, 0.0, 0.0)), np.column_stack([on.north, on.east, on.tvd])
    )
    assert (
        np.abs(
            np.linalg.norm(found.position - np.column_stack([on.north, on.east, on.tvd]), axis=1)
        ).max()
        < 1e-8
    )

"""Minimum-curvature core: exact on circular arcs, batch-independent, robust at the edges."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

from pipeline.survey.mincurve import (
    REVERSAL_MARGIN,
    SERIES_BELOW,
    _ratio_factor,
    closure,
    minimum_curvature,
    vertical_section,
)

Floats = NDArray[np.float64]
TOL = 1e-9  # m


def tangent(inc: Floats, azi: Floats) -> Floats:
    """Tool axes (n, 3) in NED."""
    return np.stack([np.sin(inc) * np.cos(azi), np.sin(inc) * np.sin(azi), np.cos(inc)], axis=-1)


def angles(t: Floats) -> tuple[Floats, Floats]:
    """Inclination and azimuth in [0, 2π) of unit tool axes (n, 3)."""
    inc = np.arctan2(np.hypot(t[:, 0], t[:, 1]), t[:, 2])
    return inc, np.mod(np.arctan2(t[:, 1], t[:, 0]), 2.0 * np.pi)


def positions(md: Floats, inc: Floats, azi: Floats, **kwargs: object) -> Floats:
    r = minimum_curvature(md, inc, azi, **kwargs)  # type: ignore[arg-type]
    return np.stack([r.north, r.east, r.tvd], axis=-1)


def random_batch(
    rng: np.random.Generator, lengths: list[int]
) -> tuple[Floats, Floats, Floats, NDArray[np.intp]]:
    """Concatenated smooth random surveys and their CSR offsets."""
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.intp)
    md = np.concatenate([rng.uniform(0, 3000) + np.cumsum(rng.uniform(0, 60, n)) for n in lengths])
    inc = np.concatenate(
        [np.clip(rng.uniform(0, 2) + np.cumsum(rng.normal(0, 0.05, n)), 0, 3) for n in lengths]
    )
    azi = np.mod(
        np.concatenate([rng.uniform(0, 7) + np.cumsum(rng.normal(0, 0.1, n)) for n in lengths]),
        2 * np.pi,
    )
    return md, inc, azi, offsets


# --- closed-form geometry -----------------------------------------------------------------------


def test_straight_slant_line() -> None:
    md = np.array([100.0, 130.0, 131.5, 200.0, 450.25])
    inc, azi = np.full(5, 0.7), np.full(5, 2.2)
    r = minimum_curvature(md, inc, azi)
    expected = (md - md[0])[:, None] * tangent(inc, azi)
    np.testing.assert_allclose(np.stack([r.north, r.east, r.tvd], axis=-1), expected, atol=TOL)
    np.testing.assert_array_equal(r.dogleg, 0.0)
    np.testing.assert_array_equal(r.dls, 0.0)


def test_zero_dogleg_step_is_exactly_straight() -> None:
    inc, azi = np.array([0.3, 0.3]), np.array([5.0, 5.0])
    pos = positions(np.array([0.0, 27.3]), inc, azi)
    np.testing.assert_array_equal(pos[1], 27.3 * tangent(inc, azi)[1])
    assert _ratio_factor(np.zeros(3)).tolist() == [1.0, 1.0, 1.0]


@pytest.mark.parametrize("azimuth", [0.0, 0.7, 3.5])
def test_vertical_plane_build_arc(azimuth: float) -> None:
    build = np.radians(3.0) / 30.0  # rad/m
    radius = 1.0 / build
    rng = np.random.default_rng(1)
    # stations anywhere on the arc, including 30° steps, up to 170° inclination
    inc = np.sort(
        np.concatenate([[0.0], rng.uniform(0, np.radians(170), 12), np.radians([30, 60, 90])])
    )
    md = 500.0 + inc / build
    pos = positions(md, inc, np.full(inc.size, azimuth))
    horizontal = radius * (1.0 - np.cos(inc))
    expected = np.stack(
        [horizontal * np.cos(azimuth), horizontal * np.sin(azimuth), radius * np.sin(inc)], -1
    )
    np.testing.assert_allclose(pos, expected, atol=TOL)


def test_vertical_plane_arc_through_vertical() -> None:
    """Dropping to vertical and building again on the opposite azimuth is one arc."""
    radius = 400.0
    tilt = np.radians(np.arange(-40.0, 41.0, 20.0))  # signed inclination towards azimuth 0.5
    inc, azi = np.abs(tilt), np.where(tilt < 0, np.pi + 0.5, 0.5)
    pos = positions(radius * tilt, inc, azi)
    horizontal = radius * (np.cos(tilt[0]) - np.cos(tilt))
    expected = np.stack(
        [
            horizontal * np.cos(0.5),
            horizontal * np.sin(0.5),
            radius * (np.sin(tilt) - np.sin(tilt[0])),
        ],
        -1,
    )
    np.testing.assert_allclose(pos, expected, atol=TOL)


def test_horizontal_circle_across_blocks_and_north() -> None:
    """I = 90° with a turning azimuth that wraps through north; long enough for several blocks."""
    radius, a0 = 250.0, np.radians(300.0)
    s = np.linspace(0.0, 2.4 * np.pi * radius, 3 * 4096 + 7)  # steps of ~0.04°, then big ones
    s = np.concatenate([s, s[-1] + np.cumsum(np.radians([30.0, 45.0, 10.0])) * radius])
    azi = np.mod(a0 + s / radius, 2.0 * np.pi)
    pos = positions(s, np.full(s.size, np.pi / 2), azi)
    expected = np.stack(
        [
            radius * (np.sin(azi) - np.sin(a0)),
            radius * (np.cos(a0) - np.cos(azi)),
            np.zeros(s.size),
        ],
        -1,
    )
    np.testing.assert_allclose(pos, expected, atol=TOL)


def test_arcs_in_tilted_planes() -> None:
    """Minimum curvature is exact on any circular arc: stations on circles in random planes."""
    rng = np.random.default_rng(7)
    for _ in range(20):
        t0 = rng.normal(size=3)
        t0 /= np.linalg.norm(t0)
        u = rng.normal(size=3)
        u -= (u @ t0) * t0
        u /= np.linalg.norm(u)
        radius = rng.uniform(50, 3000)
        phi = np.sort(rng.uniform(0, 2 * np.pi, 15))  # keeps consecutive steps well below 180°
        phi = np.concatenate([[0.0], phi[np.diff(phi, prepend=0.0) < 2.5]])
        t = np.cos(phi)[:, None] * t0 + np.sin(phi)[:, None] * u
        inc, azi = angles(t)
        pos = positions(radius * phi, inc, azi)
        expected = radius * (np.sin(phi)[:, None] * t0 + (1 - np.cos(phi))[:, None] * u)
        np.testing.assert_allclose(pos, expected, atol=TOL * radius / 1000)


def test_random_step_is_the_circular_arc_between_tangents() -> None:
    rng = np.random.default_rng(3)
    inc1, inc2 = rng.uniform(0, np.pi, (2, 500))
    azi1, azi2 = rng.uniform(0, 2 * np.pi, (2, 500))
    t1, t2 = tangent(inc1, azi1), tangent(inc2, azi2)
    beta = 2 * np.arctan2(np.linalg.norm(t1 - t2, axis=1), np.linalg.norm(t1 + t2, axis=1))
    keep = (beta > 1e-3) & (beta < np.pi - 0.05)
    dmd = rng.uniform(1, 100, 500)
    md = np.stack([np.zeros(500), dmd], 1).ravel()[np.repeat(keep, 2)]
    inc = np.stack([inc1, inc2], 1).ravel()[np.repeat(keep, 2)]
    azi = np.stack([azi1, azi2], 1).ravel()[np.repeat(keep, 2)]
    r = minimum_curvature(md, inc, azi, offsets=np.arange(0, md.size + 1, 2))
    disp = np.stack([r.north, r.east, r.tvd], -1)[1::2]
    t1, t2, beta, dmd = t1[keep], t2[keep], beta[keep], dmd[keep]
    # Rodrigues form of the arc of radius ΔMD/β; equal to R·tan(β/2)·(t1 + t2)
    u = (t2 - np.cos(beta)[:, None] * t1) / np.sin(beta)[:, None]
    expected = (dmd / beta)[:, None] * (
        np.sin(beta)[:, None] * t1 + (1 - np.cos(beta))[:, None] * u
    )
    np.testing.assert_allclose(disp, expected, atol=TOL)
    np.testing.assert_allclose(r.dogleg[1::2], beta, rtol=1e-12)
    np.testing.assert_allclose(r.dls[1::2], beta / dmd, rtol=1e-12)


# --- edges --------------------------------------------------------------------------------------


def test_azimuth_wrap_through_north() -> None:
    md, inc = np.array([0.0, 30.0]), np.radians([30.0, 30.0])
    wrapped = minimum_curvature(md, inc, np.radians([359.9, 0.1]))
    signed = minimum_curvature(md, inc, np.radians([-0.1, 0.1]))
    assert wrapped.dogleg[1] < np.radians(0.2)
    np.testing.assert_allclose(wrapped.dogleg, signed.dogleg, rtol=1e-10)
    for name in ("north", "east", "tvd"):
        np.testing.assert_allclose(getattr(wrapped, name), getattr(signed, name), atol=TOL)


def test_zero_length_steps() -> None:
    md = np.array([0.0, 30.0, 30.0, 30.0, 60.0])
    inc = np.radians([10.0, 20.0, 20.0, 25.0, 25.0])
    azi = np.radians([50.0, 60.0, 60.0, 70.0, 70.0])
    r = minimum_curvature(md, inc, azi)
    pos = np.stack([r.north, r.east, r.tvd], -1)
    assert np.isfinite(pos).all()
    assert np.isfinite(r.dogleg).all()
    assert np.isfinite(r.dls).all()
    np.testing.assert_array_equal(pos[2], pos[1])
    np.testing.assert_array_equal(pos[3], pos[1])
    assert r.dogleg[2] == 0.0
    assert r.dogleg[3] > 0.0  # an angle change without movement
    assert r.dls[2] == 0.0
    assert r.dls[3] == 0.0


def test_series_and_exact_ratio_factor_agree_at_threshold() -> None:
    beta = SERIES_BELOW * (1.0 + np.linspace(-1e-3, 1e-3, 2001))
    half = beta / 2
    exact = np.tan(half) / half
    b2 = beta**2
    series = 1 + b2 / 12 + b2**2 / 120 + 17 * b2**3 / 20160
    np.testing.assert_allclose(_ratio_factor(beta), exact, rtol=1e-15)
    np.testing.assert_allclose(_ratio_factor(beta), series, rtol=1e-15)
    np.testing.assert_allclose(_ratio_factor(np.array([1e-300, 1e-8])), 1.0, rtol=1e-15)


@pytest.mark.parametrize("dogleg_gap", [0.0, 1e-4])
def test_reversal_is_rejected_naming_the_station(dogleg_gap: float) -> None:
    md, inc, azi, _ = random_batch(np.random.default_rng(0), [4, 6])
    inc[6:8], azi[6:8] = [0.5, np.pi - 0.5 - dogleg_gap], [1.0, 1.0 + np.pi]
    with pytest.raises(ValueError, match=r"survey 1, station 3 \(index 7\).*of π"):
        minimum_curvature(md, inc, azi, offsets=[0, 4, 10])


def test_near_reversal_outside_margin_and_between_surveys_is_accepted() -> None:
    gap = 2 * REVERSAL_MARGIN
    r = minimum_curvature([0.0, 10.0], [0.0, np.pi - gap], [0.0, 0.0])
    np.testing.assert_allclose(r.dogleg[1], np.pi - gap, rtol=1e-9)
    assert np.hypot(r.north[1], r.tvd[1]) <= 10.0
    # survey 0 ends going down, survey 1 starts going up: no step connects them
    r = minimum_curvature(
        [0.0, 10.0, 0.0, 10.0], [0.0, 0.0, np.pi, np.pi], np.zeros(4), offsets=[0, 2, 4]
    )
    np.testing.assert_array_equal(r.dogleg, 0.0)
    np.testing.assert_allclose(r.tvd, [0.0, 10.0, 0.0, -10.0], atol=TOL)


def test_single_station_survey() -> None:
    r = minimum_curvature([1234.0], [0.2], [0.3], tie_north=1.0, tie_east=2.0, tie_tvd=3.0)
    assert (r.north.tolist(), r.east.tolist(), r.tvd.tolist()) == ([1.0], [2.0], [3.0])
    assert r.dogleg.tolist() == [0.0]
    assert r.dls.tolist() == [0.0]


# --- batches and tie-in -------------------------------------------------------------------------


def test_batch_equals_surveys_computed_alone() -> None:
    """Survey results do not depend on the batch: lengths mix several padding classes and the
    early surveys are long and far away, which would leak rounding into a global cumsum."""
    rng = np.random.default_rng(11)
    lengths = [5000, 3, 1, 2, 64, 65, 100, *rng.integers(1, 300, 800).tolist()]
    md, inc, azi, offsets = random_batch(rng, lengths)
    md[: lengths[0]] = 1e6 * np.arange(lengths[0])
    ties = rng.uniform(-1e4, 1e4, (3, len(lengths)))
    batch = minimum_curvature(
        md, inc, azi, offsets=offsets, tie_north=ties[0], tie_east=ties[1], tie_tvd=ties[2]
    )
    for k in [*range(8), 700, len(lengths) - 1]:
        sl = slice(offsets[k], offsets[k + 1])
        alone = minimum_curvature(
            md[sl], inc[sl], azi[sl], tie_north=ties[0, k], tie_east=ties[1, k], tie_tvd=ties[2, k]
        )
        for name in ("north", "east", "tvd", "dogleg", "dls"):
            got, want = getattr(batch, name)[sl], getattr(alone, name)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * max(1.0, np.abs(want).max()))


def test_tie_in_offsets() -> None:
    md, inc, azi, offsets = random_batch(np.random.default_rng(5), [7, 1, 12])
    rel = positions(md, inc, azi, offsets=offsets)
    first = offsets[:-1]
    scalar = positions(md, inc, azi, offsets=offsets, tie_north=10.0, tie_east=-20.0, tie_tvd=300.0)
    np.testing.assert_allclose(scalar, rel + np.array([10.0, -20.0, 300.0]), atol=TOL)
    ties = np.array([[1.0, 2.0, 3.0], [-4.0, -5.0, -6.0], [700.0, 800.0, 900.0]])
    per = positions(
        md, inc, azi, offsets=offsets, tie_north=ties[0], tie_east=ties[1], tie_tvd=ties[2]
    )
    np.testing.assert_array_equal(per[first], ties.T)
    np.testing.assert_allclose(per, rel + np.repeat(ties.T, np.diff(offsets), axis=0), atol=TOL)
    np.testing.assert_array_equal(rel[first], 0.0)


def stations() -> st.SearchStrategy[tuple[Floats, Floats, Floats]]:
    row = st.tuples(
        st.one_of(st.just(0.0), st.floats(1e-3, 100)),
        st.floats(0, np.pi),
        st.floats(0, 2 * np.pi, exclude_max=True),
    )
    return st.lists(row, min_size=2, max_size=30).map(
        lambda rows: (
            np.cumsum([r[0] for r in rows]),
            np.array([r[1] for r in rows]),
            np.array([r[2] for r in rows]),
        )
    )


@settings(max_examples=300, deadline=None, derandomize=True)
@given(stations())
def test_step_invariants(survey: tuple[Floats, Floats, Floats]) -> None:
    md, inc, azi = survey
    t = tangent(inc, azi)
    assume(bool(np.all(np.einsum("ij,ij->i", t[:-1], t[1:]) > -0.999)))  # no near-reversal
    r = minimum_curvature(md, inc, azi)
    step = np.diff(np.stack([r.north, r.east, r.tvd], -1), axis=0)
    dmd, beta = np.diff(md), r.dogleg[1:]
    assert np.all((beta >= 0) & (beta <= np.pi))
    chord = np.linalg.norm(step, axis=1)
    slack = 1e-12 * (1 + md[-1])
    assert np.all(chord <= dmd + slack)
    assert np.all(np.abs(step[:, 2]) <= dmd + slack)
    # a circular arc of length ΔMD and angle β has chord ΔMD·sin(β/2)/(β/2)
    np.testing.assert_allclose(chord, dmd * np.sinc(beta / (2 * np.pi)), rtol=1e-9, atol=slack)
    np.testing.assert_allclose(
        r.dls[1:], np.where(dmd > 0, beta / np.where(dmd > 0, dmd, 1), 0), rtol=1e-12
    )


# --- validation ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        (([0.0, 1.0], [0.0], [0.0, 0.0]), {}, "equal length"),
        (([[0.0, 1.0]], [[0.0, 0.0]], [[0.0, 0.0]]), {}, "1-D"),
        (([], [], []), {}, "at least one station"),
        (([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]), {"offsets": [0.0, 2.0]}, "integer"),
        (([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]), {"offsets": [2]}, "length n_surveys"),
        (
            ([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]),
            {"offsets": [1, 2]},
            r"start at 0 and end at len\(md\) = 2",
        ),
        (([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]), {"offsets": [0, 3]}, "end at len"),
        (
            ([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]),
            {"offsets": [0, 2, 2]},
            r"offsets\[1\] = 2 and offsets\[2\] = 2",
        ),
        (
            ([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]),
            {"offsets": [0, 1, 2], "tie_tvd": [1.0, 2.0, 3.0]},
            r"tie_tvd.*\(2\)",
        ),
        (([0.0, 1.0], [0.0, 0.0], [0.0, 0.0]), {"tie_east": [[1.0]]}, "tie_east must be a scalar"),
    ],
)
def test_malformed_input_is_rejected(
    args: tuple[object, ...], kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        minimum_curvature(*args, **kwargs)  # type: ignore[arg-type]


# --- vertical section and closure ---------------------------------------------------------------


def test_vertical_section() -> None:
    north, east = np.array([3.0, 0.0, -2.0]), np.array([4.0, 5.0, 0.0])
    np.testing.assert_allclose(
        vertical_section(north, east, np.arctan2(4.0, 3.0)), [5.0, 4.0, -1.2], atol=1e-12
    )
    np.testing.assert_allclose(
        vertical_section(north, east, np.pi / 2), [4.0, 5.0, 0.0], atol=1e-12
    )
    np.testing.assert_allclose(vertical_section(north, east, np.pi), [-3.0, 0.0, 2.0], atol=1e-12)


def test_closure() -> None:
    north = np.array([0.0, 5.0, 0.0, -5.0, 0.0, 3.0, 1.0])
    east = np.array([0.0, 0.0, 5.0, 0.0, -5.0, 4.0, -1e-17])
    distance, direction = closure(north, east)
    np.testing.assert_allclose(distance, [0.0, 5.0, 5.0, 5.0, 5.0, 5.0, 1.0])
    np.testing.assert_allclose(
        direction, [0.0, 0.0, np.pi / 2, np.pi, 3 * np.pi / 2, np.arctan2(4, 3), 0.0]
    )
    assert np.all((direction >= 0) & (direction < 2 * np.pi))


# --- peer -----------------------------------------------------------------------------------------


def test_agrees_with_wellpathpy() -> None:
    mincurve = pytest.importorskip("wellpathpy.mincurve")
    md, inc, azi, _ = random_batch(np.random.default_rng(2), [300])
    md = np.unique(md)  # wellpathpy wants strictly increasing MD
    inc, azi = inc[: md.size], azi[: md.size]
    tvd, north, east, dls = mincurve.minimum_curvature(
        md, np.degrees(inc), np.degrees(azi), course_length=30
    )
    r = minimum_curvature(md, inc, azi)
    np.testing.assert_allclose(
        np.stack([r.north, r.east, r.tvd]), np.stack([north, east, tvd]), atol=1e-6
    )
    np.testing.assert_allclose(np.degrees(r.dls) * 30, dls, rtol=1e-9, atol=1e-12)

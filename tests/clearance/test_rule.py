"""The separation rule on wells whose answer is worked out by hand: parallel wells with
isotropic covariances, the levels at the limits, the travelling-cylinder angle."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.anticollision.rule import RuleLimits, SeparationRule, levels
from pipeline.anticollision.scan import Well, scan


def straight_well(
    name: str, tie: tuple[float, float, float], inc_deg: float, azi_deg: float, sigma: float
) -> Well:
    md = np.arange(0.0, 1001.0, 100.0)
    cov = np.broadcast_to(sigma**2 * np.eye(3), (md.size, 3, 3)).copy()
    return Well(
        name,
        md,
        np.full(md.size, np.radians(inc_deg)),
        np.full(md.size, np.radians(azi_deg)),
        tie,
        cov,
        radius=0.15,
    )


def test_parallel_vertical_wells_sf_by_hand():
    ref = straight_well("ref", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=2.0)
    off = straight_well("off", (0.0, 20.0, 0.0), 0.0, 0.0, sigma=3.0)
    rule = SeparationRule(k=3.5, sigma_pa=0.5, surface_margin=0.3)
    result = scan(ref, [off], rule)
    expected = (20.0 - 0.15 - 0.15 - 0.3) / (3.5 * np.sqrt(2.0**2 + 3.0**2 + 0.5**2))
    assert result.sf == pytest.approx(np.full(11, expected), rel=1e-12)
    assert result.distance == pytest.approx(np.full(11, 20.0), abs=1e-9)
    assert result.sigma_s == pytest.approx(np.full(11, np.sqrt(13.0)), rel=1e-12)
    assert result.offset_md == pytest.approx(ref.md, abs=1e-9)
    assert set(result.offset.tolist()) == {"off"}


def test_covariance_counts_only_along_the_separation():
    """σ_S takes the combined covariance along the line between the centres only: a
    large error along north does not move the SF of wells side by side east–west."""
    ref = straight_well("ref", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=0.0)
    off = straight_well("off", (0.0, 10.0, 0.0), 0.0, 0.0, sigma=0.0)
    off.cov[:, 0, 0] = 100.0**2  # north
    off.cov[:, 1, 1] = 1.0  # east
    sf = scan(ref, [off]).sf
    assert sf == pytest.approx(np.full(11, (10.0 - 0.6) / (3.5 * np.sqrt(1.0 + 0.25))))


def test_levels_at_the_limits():
    limits = RuleLimits(stop=1.0, caution=1.5)
    sf = np.array([0.2, 0.999, 1.0, 1.49, 1.5, 40.0, -3.0, np.nan])
    assert levels(sf, limits).tolist() == [
        "fail",
        "fail",
        "warn",
        "warn",
        "pass",
        "pass",
        "fail",
        "fail",
    ]


@pytest.mark.parametrize(
    ("tie", "toolface"),
    [
        ((0.0, 0.0, -30.0), 0.0),  # above a horizontal well: its high side
        ((0.0, 30.0, 0.0), 90.0),  # east of a well heading north: its right
        ((0.0, 0.0, 30.0), 180.0),  # below
        ((0.0, -30.0, 0.0), 270.0),  # west: left
        ((0.0, -1e-15, -30.0), 0.0),  # a hair left of the high side: 0°, not 360°
    ],
)
def test_travelling_cylinder_angle(tie: tuple[float, float, float], toolface: float):
    ref = straight_well("ref", (0.0, 0.0, 0.0), 90.0, 0.0, sigma=1.0)
    off = straight_well("off", tie, 90.0, 0.0, sigma=1.0)
    got = scan(ref, [off]).toolface
    assert ((got >= 0.0) & (got < 360.0)).all()
    assert np.abs((got - toolface + 180.0) % 360.0 - 180.0).max() < 1e-9


def test_coinciding_centres_take_the_largest_sigma_and_fail():
    """D = 0: no direction n̂, so σ_S is the largest σ over directions (isotropic 1 m each:
    √2 m); SF = (0 − 0.3 − 0.3)/(3.5·√(2 + 0.25)) = −0.6/5.25; the travelling-cylinder
    angle is undefined."""
    ref = straight_well("ref", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=1.0)
    result = scan(ref, [straight_well("twin", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=1.0)])
    assert result.sigma_s == pytest.approx(np.full(11, np.sqrt(2.0)))
    assert result.sf == pytest.approx(np.full(11, -0.6 / 5.25))
    assert np.isnan(result.toolface).all()
    assert set(result.level.tolist()) == {"fail"}


def test_common_point_of_exact_wells_is_the_rule_alone():
    """Both covariances zero where the centres coincide (a sidetrack's kick-off): σ_S = 0
    and SF = −(R_r + R_o + S_m)/(k·σ_pa) = −0.6/1.75, not NaN."""
    ref = straight_well("ref", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=0.0)
    result = scan(ref, [straight_well("twin", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=0.0)])
    assert result.sigma_s == pytest.approx(np.zeros(11))
    assert result.sf == pytest.approx(np.full(11, -0.6 / 1.75))


def test_least_sf_between_stations_by_hand():
    """A horizontal offset crosses 2 m east of a vertical reference at TVD 550, half-way
    between its stations at 500 and 600 m (no position uncertainty): at those stations
    D = √(2² + 50²); on the course between, the least SF is at MD 550, D = 2 m:
    (2 − 0.3 − 0.3)/(3.5·0.5) = 0.8 — a fail the stations alone (SF 28) do not show."""
    ref = straight_well("ref", (0.0, 0.0, 0.0), 0.0, 0.0, sigma=0.0)
    offset = straight_well("cross", (-500.0, 2.0, 550.0), 90.0, 0.0, sigma=0.0)
    result = scan(ref, [offset])
    at = {md: k for k, md in enumerate(result.md)}
    station = (np.hypot(2.0, 50.0) - 0.6) / 1.75
    assert result.sf[at[500.0]] == pytest.approx(station)
    assert result.sf_between[at[500.0]] == pytest.approx(0.8, abs=1e-9)
    assert result.md_between[at[500.0]] == pytest.approx(550.0, abs=1e-3)
    assert result.level[at[500.0]] == "fail"
    assert result.sf_between[at[0.0]] == pytest.approx(result.sf[at[100.0]])  # its lower end
    assert result.sf_between[-1] == result.sf[-1]  # the last station: no course below
    by_station = scan(ref, [offset], level_on="station")
    assert by_station.level[at[500.0]] == "pass"

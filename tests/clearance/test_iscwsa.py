"""The ISCWSA standard clearance set through ``gp.clearance``: the separation factors the set
gives at every reference station for offset wells 01–06 (computed with the ISCWSA MWD Rev 4
error model), and welleng's clearance given the same covariances (skipped without
welleng)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from iscwsa_support import OFFSETS, clearance_options, data, expected_sf, stations

import pipeline as gp


def sf_by_offset(result: pd.DataFrame) -> dict[str, np.ndarray]:
    return {name: result[result.offset == name].sf.to_numpy() for name in OFFSETS}


@pytest.fixture(scope="module")
def rev4() -> pd.DataFrame:
    offsets = {name: stations(name) for name in OFFSETS}
    return gp.clearance(stations("Reference well"), offsets, **clearance_options("ISCWSA-MWD-REV4"))


@pytest.mark.parametrize("name", OFFSETS)
def test_every_station_within_half_a_percent_of_the_set(rev4: pd.DataFrame, name: str):
    """The set's SF at each of the 100 reference stations, within 0.5 % (welleng's
    tolerance against the same set)."""
    sf = sf_by_offset(rev4)[name]
    expected = expected_sf(name)
    assert sf.shape == expected.shape == (100,)
    assert np.abs(sf / expected - 1.0).max() < 0.005


def test_levels_follow_the_rule(rev4: pd.DataFrame):
    """Offsets 03 and 04 come closer than SF 1 (stop); 01, 05 and 06 only to caution; 02
    passes."""
    worst = rev4.groupby("offset").sf.min()
    levels = rev4.groupby("offset")["level"].agg(lambda x: sorted(set(x)))
    for name in ("03 - well", "04 - well"):
        assert worst[name] < 1.0 and "fail" in levels[name]
    assert levels["02 - well"] == ["pass"]
    for name in ("01 - well", "05 - well", "06 - well"):
        assert 1.0 <= worst[name] < 1.5 and levels[name] == ["pass", "warn"]


def test_result_has_a_row_per_station_and_offset_with_units(rev4: pd.DataFrame):
    assert len(rev4) == 6 * 100
    assert list(rev4.columns) == [
        "offset",
        "md",
        "offset_md",
        "distance",
        "sigma_s",
        "sf",
        "level",
        "toolface",
    ]
    assert rev4.attrs["units"] == {
        "md": "m",
        "offset_md": "m",
        "distance": "m",
        "sigma_s": "m",
        "toolface": "deg",
    }
    assert set(rev4.level) <= {"pass", "warn", "fail"}


def test_surface_stations_match_the_set(rev4: pd.DataFrame):
    """Offsets 01–04 start beside the reference, their slots closest to its first station,
    where both wells' positions are known (σ_S = 0): the SF there is the
    geometry and the rule alone, (D − R_r − R_o − S_m)/(k·σ_pa). The set's clearances
    D − R_r − R_o − S_m there are 3.7e-5 m longer than 36 in and 24 in holes give (its
    radii rounded), hence 1e-4 m."""
    k_sigma = 3.5 * 0.5
    for name in OFFSETS[:4]:
        sf = sf_by_offset(rev4)[name]
        assert sf[0] * k_sigma == pytest.approx(expected_sf(name)[0] * k_sigma, abs=1e-4), name


def test_same_covariances_give_welleng_s_separation_factors():
    """welleng's ISCWSA clearance (closest point on the offset's arcs, covariance interpolated
    linearly, the same rule) given the very covariances gyropipe computed: every SF agrees."""
    we = pytest.importorskip("welleng")
    from pipeline.anticollision.models import ModelSite, well_covariance
    from pipeline.anticollision.scan import Well, scan
    from pipeline.earth.site import MagneticReference
    from pipeline.survey.mincurve import minimum_curvature

    site = ModelSite(
        latitude=60.0, magnetic=MagneticReference(total_field=50000.0, dip=70.0, declination=0.0)
    )

    def well(name: str, radius: float) -> Well:
        w = data()["wells"][name]
        md, inc, azi = (np.asarray(w[k], float) for k in ("MD", "IncDeg", "AziDeg"))
        tie = (w["N"][0], w["E"][0], w["TVD"][0])
        inc, azi = np.radians(inc), np.radians(azi)
        tvd = minimum_curvature(md, inc, azi, tie_tvd=tie[2]).tvd
        cov = well_covariance("ISCWSA-MWD-REV4", md, inc, azi, tvd, site)
        return Well(name, md, inc, azi, tie, cov, radius)

    def survey(w: Well):  # type: ignore[no-untyped-def]
        header = we.survey.SurveyHeader(
            latitude=60.0,
            b_total=50000.0,
            dip=70.0,
            declination=0.0,
            convergence=0.0,
            azi_reference="grid",
        )
        return we.survey.Survey(
            md=w.md,
            inc=np.degrees(w.inc),
            azi=np.degrees(w.azi),
            header=header,
            start_nev=list(w.tie),
            cov_nev=w.cov,
            radius=np.full(w.md.size, w.radius),
        )

    ref = well("Reference well", 0.4572)
    offsets = [well(name, 0.3048) for name in OFFSETS]
    ours = scan(ref, offsets)
    for k, off in enumerate(offsets):
        theirs = we.clearance.IscwsaClearance(survey(ref), survey(off), minimize_sf=False)
        rows = slice(100 * k, 100 * (k + 1))
        assert ours.sf[rows] == pytest.approx(np.ravel(theirs.sf), rel=1e-9), off.name
        assert ours.distance[rows] == pytest.approx(theirs.distance_cc, abs=1e-9)

"""Tests of the ISCWSA gyro position-uncertainty propagation, ellipses and stage."""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from numpy.typing import NDArray

from pipeline.errors import MissingSiteError
from pipeline.stages.survey import MinCurveParams, min_curve
from pipeline.stages.uncertainty import (
    PositionUncertainty,
    UncertaintyParams,
    position_uncertainty,
)
from pipeline.survey.mincurve import minimum_curvature
from pipeline.tables import Stations
from pipeline.uncertainty import (
    ModelSite,
    Survey,
    configure,
    ellipses,
    find_model,
    horizontal_scale,
    model_terms,
    propagate,
    station_jacobians,
    term_covariances,
    vertical_scale,
)
from pipeline.uncertainty.gyro import with_initial_azimuth, with_measured_noise
from pipeline.well import WellMetadata
from tests_support import stage_context

RUN = SimpleNamespace(tool_models={})
"""The provenance a stage reads its run's tool models from (here: no plugin's)."""
LAT = 60.0
SITE = ModelSite(latitude=LAT)


def _profile(md: NDArray[np.float64], kickoff: float = 500.0) -> tuple[Any, Any]:
    inc = np.clip((md - kickoff) / 2000.0 * 60.0, 0.0, 60.0)
    azi = np.where(md > kickoff, 45.0 + (md - kickoff) / 100.0, 45.0)
    return inc, azi


def _survey(md: NDArray[np.float64], inc_deg: Any, azi_deg: Any) -> Survey:
    inc, azi = np.radians(inc_deg), np.radians(azi_deg)
    return Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)


# ---------------------------------------------------------------- Jacobian and propagation


def test_min_curve_jacobian_matches_finite_differences() -> None:
    rng = np.random.default_rng(1)
    md = np.cumsum(rng.uniform(20.0, 40.0, 12))
    inc = rng.uniform(0.2, 1.4, 12)
    azi = rng.uniform(0.0, 2 * np.pi, 12)
    jac = station_jacobians(md, inc, azi, basis="min_curve", surface_tie=False)

    def pos(m: Any, i: Any, a: Any) -> NDArray[np.float64]:
        r = minimum_curvature(m, i, a)
        return np.stack((r.north, r.east, r.tvd), axis=-1)

    h = 1e-5

    def shifted(k: int, col: int, step: float) -> NDArray[np.float64]:
        m, i, a = md.copy(), inc.copy(), azi.copy()
        if col == 0:
            m[k] += step
        elif col == 1:
            i[k] += step
        else:
            a[k] += step / np.sin(inc[k])  # α = A·sin I
        return pos(m, i, a)

    for k in range(1, 11):
        for col in range(3):
            d = (shifted(k, col, h) - shifted(k, col, -h)) / (2 * h)  # central difference
            np.testing.assert_allclose(d[k], jac.into[k, :, col], atol=1e-7)
            np.testing.assert_allclose(d[k + 1] - d[k], jac.out[k, :, col], atol=1e-7)


def test_propagation_modes_closed_form() -> None:
    """Depth errors on a straight vertical hole from a fixed tie: a random MD error of σ at
    each station moves station K by (error_K − error_0), variance 2σ² for K > 0; a systematic
    one shifts every MD alike and moves nothing. All of it in V."""
    n = 6
    md = np.arange(n) * 10.0
    jac = station_jacobians(md, np.zeros(n), np.zeros(n), basis="min_curve", surface_tie=False)
    e = np.zeros((2, n, 3))
    e[:, :, 0] = 0.1
    cov = propagate(e, ["random", "systematic"], jac)
    k = np.arange(n)
    np.testing.assert_allclose(cov[0, :, 2, 2], 0.01 * np.where(k > 0, 2.0, 0.0), atol=1e-15)
    np.testing.assert_allclose(cov[1, :, 2, 2], 0.0, atol=1e-15)  # a shift of every MD
    assert np.all(cov[:, :, :2, :] == 0.0)


def test_propagate_rejects_bad_shapes() -> None:
    jac = station_jacobians([0.0, 10.0], [0.0, 0.1], [0.0, 0.0])
    with pytest.raises(ValueError, match="e_dia"):
        propagate(np.zeros((1, 2, 2)), ["random"], jac)
    with pytest.raises(ValueError, match="unknown propagation"):
        propagate(np.zeros((1, 2, 3)), ["bogus"], jac)  # type: ignore[list-item]


# ---------------------------------------------------------------- Monte Carlo forward check


def test_monte_carlo_matches_propagated_covariance() -> None:
    """Perturb (MD, I, A) by every GYRO-NS measurement source with its correlation (random:
    one draw per station; systematic/global: one per survey), recompute by minimum curvature,
    and compare the sample covariance with the propagated one within sampling error. (The
    course-length terms XCLA/XCLH are errors of the position itself, not of a measurement:
    not perturbed here.)"""
    md = np.arange(0.0, 1801.0, 30.0)
    inc_deg, azi_deg = _profile(md, kickoff=0.0)
    inc_deg = np.maximum(inc_deg, 5.0)  # keep A defined for the azimuth perturbation
    survey = _survey(md, inc_deg, azi_deg)
    terms = [t for t in model_terms(find_model("GYRO-NS"), SITE) if t.frame == "dia"]
    e_dia = np.stack([t.sigma * t.weight(survey) for t in terms])
    modes = [t.mode for t in terms]
    cov = propagate(
        e_dia,
        modes,
        station_jacobians(md, survey.inc, survey.azi, basis="min_curve", surface_tie=False),
    ).sum(axis=0)

    rng = np.random.default_rng(20261121)
    n_mc, n = 4000, md.size
    draws = np.empty((len(terms), n_mc, n))
    for j, mode in enumerate(modes):
        if mode == "random":
            draws[j] = rng.standard_normal((n_mc, n))
        else:
            draws[j] = rng.standard_normal((n_mc, 1))
    delta = np.einsum("tsn,tnc->snc", draws, e_dia)  # (samples, stations, (MD, I, α))
    md_p = md + delta[:, :, 0]
    inc_p = survey.inc + delta[:, :, 1]
    azi_p = survey.azi + delta[:, :, 2] / np.sin(survey.inc)
    offsets = np.arange(n_mc + 1) * n
    res = minimum_curvature(md_p.ravel(), inc_p.ravel(), azi_p.ravel(), offsets=offsets)
    pos = np.stack((res.north, res.east, res.tvd), axis=-1).reshape(n_mc, n, 3)
    sample = np.einsum("sni,snj->nij", pos - pos.mean(0), pos - pos.mean(0)) / (n_mc - 1)

    diag = np.einsum("nii->ni", cov)
    se = np.sqrt((diag[:, :, None] * diag[:, None, :] + cov**2) / n_mc)
    z = (sample - cov)[1:] / se[1:]
    assert np.abs(z).max() < 5.0, np.abs(z).max()
    rel = np.abs(np.einsum("nii->ni", sample)[-1] / diag[-1] - 1.0)
    assert rel.max() < 0.08, rel


# ---------------------------------------------------------------- agreement with welleng


@pytest.mark.parametrize("model", ["GYRO-NS", "GYRO-NS-CT", "GYRO-MWD"])
def test_agreement_with_welleng(model: str) -> None:
    """welleng's GYRO-NS, GYRO-NS-CT (OWSG A021Gc: GXY-GD and GXY-GRW accumulating above the
    15° static end inclination) and GYRO-MWD (OWSG A019Gb), term by term and in total. The
    sheet and welleng evaluate GYRO-NS-CT's stationary gyro terms on above the static end
    inclination, where this model switches them (SPE 90408): those terms are compared up to
    the switch, the others everywhere."""
    we = pytest.importorskip("welleng")
    md = np.arange(0.0, 3001.0, 30.0)
    inc_deg, azi_deg = _profile(md)
    survey = _survey(md, inc_deg, azi_deg)
    for basis in ("balanced_tangent", "min_curve"):
        header = we.survey.SurveyHeader(
            latitude=LAT, longitude=2.0, G=9.80665, azi_reference="true", dp_basis=basis
        )
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ref = we.survey.Survey(
                md=md, inc=inc_deg, azi=azi_deg, header=header, error_model=model
            ).err.errors.errors
        names, cov = term_covariances(survey, model, SITE, basis=basis, surface_tie=True)
        switched = {t.name for t in find_model(model).terms if t.switch is not None}
        if model == "GYRO-NS-CT":
            assert sorted(set(names) - {"GXY-RN-INIT"}) == sorted(ref)
            assert {"GXY-GD", "GXY-GRW"} <= set(names) - switched
            assert {"GXY-B1S", "GXY-B2S", "GXY-G4", "GXY-RN", "GXY-RN-INIT"} == switched
        below = np.flatnonzero(np.maximum.accumulate(inc_deg) <= 15.0) if switched else md
        total_ref = np.zeros_like(cov[0])
        for k, name in enumerate(names):
            if name == "GXY-RN-INIT":  # zero up to the switch
                assert not cov[k][: below.size].any()
                continue
            theirs = ref[name].cov_NEV
            total_ref += theirs
            rows = slice(0, below.size) if name in switched else slice(None)
            diff = np.abs(theirs[rows] - cov[k][rows]).max() / np.abs(theirs).max()
            # XCLA/XCLH in position as welleng has them for every tool (issue 29)
            limit = 1e-4 if basis == "min_curve" else 1e-9
            assert diff < limit, (basis, name, diff)
        total = cov.sum(axis=0)[: below.size]
        scale = np.abs(total_ref).max()
        assert np.abs(total - total_ref[: below.size]).max() / scale < 1e-5


def test_continuous_drift_and_random_walk_coefficients() -> None:
    """At constant inclination I and running speed c the drift coefficient is the time
    spent, ΔMD/(c sin I) hours, the random walk's √(ΔMD/(c sin² I)); both restart after a
    station at or below the static end inclination."""
    md = np.arange(0.0, 601.0, 30.0)
    inc = np.where(md <= 90.0, 5.0, 40.0)
    inc[md == 300.0] = 10.0  # drops below the 15° gate: the accumulation restarts
    s = _survey(md, inc, np.full(md.size, 30.0))
    tool = configure("GYRO-NS-CT", {"gxy_gd": 1.0, "gxy_grw": 1.0, "running_speed": 1800.0})
    terms = {t.name: t for t in model_terms(tool, SITE)}
    gd = terms["GXY-GD"].weight(s)[:, 2] / np.sin(s.inc)
    grw = terms["GXY-GRW"].weight(s)[:, 2] / np.sin(s.inc)
    mean_sin = np.sin(np.radians((inc[1:] + inc[:-1]) / 2))
    step = np.concatenate([[0.0], 30.0 / (1800.0 * mean_sin)])
    step_rw = np.concatenate([[0.0], 30.0 / (1800.0 * mean_sin**2)])
    restart = int(np.flatnonzero(md == 300.0)[0])
    for k in range(md.size):
        first = 4 if k < restart else restart + 1  # first leg ending above the gate
        expected = step[first : k + 1].sum() if k >= first else 0.0
        assert gd[k] == pytest.approx(expected, abs=1e-15)
        expected_rw = np.sqrt(step_rw[first : k + 1].sum()) if k >= first else 0.0
        assert grw[k] == pytest.approx(expected_rw, abs=1e-15)


def test_measured_initial_error_replaces_the_stationary_gyro_terms() -> None:
    """A continuous run from a compassed stop: one systematic azimuth error of the stop's
    measured σ, drift and random walk from the first station."""
    md = np.arange(0.0, 301.0, 10.0)
    s = _survey(md, np.full(md.size, 30.0), np.full(md.size, 70.0))
    tool = with_initial_azimuth(find_model("GYRO-NS-CT"), 2.0)
    terms = {t.name: t for t in model_terms(tool, SITE)}
    assert not any(n.startswith("GXY-B") or n in ("GXY-G4", "GXY-RN") for n in terms)
    init = terms["AZ-INIT"]
    assert init.mode == "systematic"
    np.testing.assert_allclose(init.sigma * init.weight(s)[:, 2] / np.sin(s.inc), np.radians(2.0))
    assert terms["GXY-GD"].weight(s)[1, 2] > 0.0  # accumulating from the first leg


# ---------------------------------------------------------------- ellipses


def test_ellipse_closed_forms() -> None:
    # axis-aligned: semi-axes are the σ's, major axis north (0) or east (π/2)
    e = ellipses([9.0, 1.0], [0.0, 0.0], [4.0, 4.0], [16.0, 0.25])
    np.testing.assert_allclose(e.semi_major, [3.0, 2.0])
    np.testing.assert_allclose(e.semi_minor, [2.0, 1.0])
    np.testing.assert_allclose(e.azimuth, [0.0, np.pi / 2])
    np.testing.assert_allclose(e.sigma_v, [4.0, 0.5])
    # rotated: R(θ) diag(a², b²) R(θ)ᵀ with θ = 30° clockwise from north in (N, E)
    th, a, b = np.radians(30.0), 5.0, 2.0
    u, v = np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])
    c = a**2 * np.outer(u, u) + b**2 * np.outer(v, v)
    r = ellipses(c[0, 0], c[0, 1], c[1, 1], 1.0)
    np.testing.assert_allclose([r.semi_major, r.semi_minor, r.azimuth], [a, b, th])
    # rank one, v vᵀ rounded (a continuous run's tie station: nn·ee = ne² to 3e-16 relative):
    # minor 0, not √ of the rounding of mean − radius (1.3e-12 m here); a resolved small one
    # (λ ratio 1e-10, far above ε; to the subtraction's rounding, ε/1e-10) kept; NaN (outside
    # validity) stays NaN
    tie = ellipses(
        [1.1585816078318577e-08, 1.0, 4.0, np.nan],
        [1.0041834708255498e-08, 0.0, 0.0, np.nan],
        [8.703611694357162e-09, 1e-10, 1.0, np.nan],
        1.0,
    )
    assert tie.semi_minor[0] == 0.0
    assert tie.semi_major[0] == pytest.approx(
        np.sqrt(1.1585816078318577e-08 + 8.703611694357162e-09)
    )
    assert tie.semi_minor[1] == pytest.approx(1e-5, rel=1e-5)
    assert tie.semi_minor[2] == pytest.approx(1.0)
    assert np.isnan(tie.semi_minor[3])
    # χ²(2): P(r² ≤ k²) = 1 − exp(−k²/2); 39.35 % at 1σ, k = 2.4477 at 95 %
    assert horizontal_scale(1 - np.exp(-0.5)) == pytest.approx(1.0)
    assert horizontal_scale(0.95) == pytest.approx(2.447746830680816)
    assert vertical_scale(0.95) == pytest.approx(1.959963984540054)
    with pytest.raises(ValueError, match="confidence"):
        horizontal_scale(1.0)


# ---------------------------------------------------------------- gyro parameters


def test_measured_noise_sets_gxy_rn() -> None:
    tool = with_measured_noise(find_model("GYRO-NS"), sigma_azi_deg=0.5, latitude_deg=LAT)
    md = np.array([0.0, 30.0, 60.0])
    s = _survey(md, [20.0, 20.0, 20.0], [0.0, 0.0, 0.0])
    rn = next(t for t in model_terms(tool, SITE) if t.name == "GXY-RN")
    # A = 0: √(1 − sin²I)/cos I = 1, so the azimuth σ is the measured one at any I
    sigma_a = rn.sigma * rn.weight(s)[1, 2] / np.sin(s.inc[1])
    assert np.degrees(sigma_a) == pytest.approx(0.5)


# ---------------------------------------------------------------- stage


def _stations(md: Any, inc: Any, azi: Any) -> pa.Table:
    return Stations.compiled().make_table(
        {"md": md, "inc": inc, "azi": azi}, north_reference="true"
    )


def test_stage_outputs_contract_and_matches_library() -> None:
    md = np.arange(0.0, 1501.0, 30.0)
    inc, azi = _profile(md)
    ctx: Any = stage_context(WellMetadata(latitude=LAT), provenance=RUN)
    traj = min_curve({"stations": _stations(md, inc, azi)}, MinCurveParams(tie_tvd=0.0), ctx)
    out = position_uncertainty(traj, UncertaintyParams(confidence=0.95), ctx)["trajectory"]
    PositionUncertainty.validate_table(out)
    _, cov = term_covariances(_survey(md, inc, azi), "GYRO-NS", SITE)
    total = cov.sum(axis=0)
    np.testing.assert_allclose(out.column("cov_nn").to_numpy(), total[:, 0, 0])
    np.testing.assert_allclose(out.column("cov_ev").to_numpy(), total[:, 1, 2])
    major = out.column("ellipse_major").to_numpy()
    np.testing.assert_allclose(out.column("ellipse_major_conf").to_numpy(), 2.4477468 * major)


def test_stage_gyro_ns_ct_with_tool_magnitudes() -> None:
    md = np.arange(0.0, 1501.0, 30.0)
    inc, azi = _profile(md, kickoff=0.0)
    ctx: Any = stage_context(WellMetadata(latitude=LAT), provenance=RUN)
    traj = min_curve({"stations": _stations(md, inc, azi)}, MinCurveParams(tie_tvd=0.0), ctx)
    params = UncertaintyParams(
        model="GYRO-NS-CT", init_sigma_azi=1.5, tool={"gxy_gd": 2.0, "running_speed": 3600.0}
    )
    out = position_uncertainty(traj, params, ctx)["trajectory"]
    overrides = {"sage": 0.08, "noise_reduction": 0.4082, "gxy_gd": 2.0, "running_speed": 3600.0}
    tool = with_initial_azimuth(configure("GYRO-NS-CT", overrides), 1.5)
    _, cov = term_covariances(_survey(md, inc, azi), tool, SITE)
    np.testing.assert_allclose(out.column("cov_ee").to_numpy(), cov.sum(axis=0)[:, 1, 1])
    with pytest.raises(ValueError, match="unknown tool fields"):
        UncertaintyParams(model="GYRO-NS-CT", tool={"gxy_bogus": 1.0})
    with pytest.raises(ValueError, match="continuous"):
        position_uncertainty(traj, UncertaintyParams(init_sigma_azi=1.0), ctx)


def test_stage_ties_a_continuous_model_to_the_start_stops_sigma() -> None:
    md = np.arange(300.0, 1501.0, 30.0)
    inc, azi = _profile(md, kickoff=0.0)
    ctx: Any = stage_context(WellMetadata(latitude=LAT), provenance=RUN)
    traj = min_curve({"stations": _stations(md, inc, azi)}, MinCurveParams(tie_tvd=0.0), ctx)
    # the stop nearest the first station (300 m) is the run's tie
    stops = pa.table({"md": [1500.0, 300.2], "inc": [50.0, 30.0], "sigma_azi": [3.0, 0.7]})
    wired = position_uncertainty(
        {**traj, "stops": stops}, UncertaintyParams(model="GYRO-NS-CT"), ctx
    )
    explicit = position_uncertainty(
        traj, UncertaintyParams(model="GYRO-NS-CT", init_sigma_azi=0.7), ctx
    )
    untied = position_uncertainty(traj, UncertaintyParams(model="GYRO-NS-CT"), ctx)
    for name in ("cov_nn", "cov_ee", "cov_ne"):
        np.testing.assert_array_equal(
            wired["trajectory"].column(name).to_numpy(),
            explicit["trajectory"].column(name).to_numpy(),
        )
    assert not np.allclose(
        wired["trajectory"].column("cov_ee").to_numpy(),
        untied["trajectory"].column("cov_ee").to_numpy(),
    )
    # a near-vertical tie stop does not initialise the run: as if no stops were wired
    vertical = stops.set_column(1, "inc", pa.array([50.0, 2.0]))
    as_untied = position_uncertainty(
        {**traj, "stops": vertical}, UncertaintyParams(model="GYRO-NS-CT"), ctx
    )
    np.testing.assert_array_equal(
        as_untied["trajectory"].column("cov_ee").to_numpy(),
        untied["trajectory"].column("cov_ee").to_numpy(),
    )
    # an explicit parameter wins over the wired stops
    ct2 = UncertaintyParams(model="GYRO-NS-CT", init_sigma_azi=2.0)
    overridden = position_uncertainty({**traj, "stops": stops}, ct2, ctx)
    np.testing.assert_array_equal(
        overridden["trajectory"].column("cov_ee").to_numpy(),
        position_uncertainty(traj, ct2, ctx)["trajectory"].column("cov_ee").to_numpy(),
    )


def test_stage_needs_latitude() -> None:
    md = np.arange(0.0, 91.0, 30.0)
    ctx: Any = stage_context(WellMetadata(), provenance=RUN)
    traj = min_curve({"stations": _stations(md, [0, 1, 2, 3], [0, 0, 0, 0])}, MinCurveParams(), ctx)
    with pytest.raises(MissingSiteError, match="position_uncertainty stage's `latitude`"):
        position_uncertainty(traj, UncertaintyParams(), ctx)


def test_stage_registers() -> None:
    from pipeline.registry import StageDef
    from pipeline.stages import uncertainty

    stages: list[StageDef] = []
    uncertainty.gyropipe_register_stages(stages.append)
    assert [s.name for s in stages] == ["position_uncertainty"]
    assert stages[0].outputs == {"trajectory": PositionUncertainty}

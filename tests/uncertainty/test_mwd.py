"""The ISCWSA MWD Rev 5 error model against the ISCWSA example results for test well #1,
against an independent program's diagnostics, and its sensor weights against a forward
model of the magnetic survey tool.

Agreement criterion of the issue: within ±1 %, or within ±2 units where the value is below
200 units, the unit being the spreadsheet's, m² (covariance elements of NEV position). As
1 % of 200 m² is 2 m², that is |Δ| ≤ max(0.01·|ref|, 2 m²). The references print four
decimals, so the tests also hold every cell to half a unit of that last digit (5e-5 m²).
"""

from __future__ import annotations

import datetime as dt
import json
import warnings
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from numpy.typing import NDArray

import pipeline as gp
from pipeline.earth.frames import body_to_ned, inclination_toolface, to_body
from pipeline.earth.geomagnetic import reference_field
from pipeline.earth.site import MagneticReference
from pipeline.errors import MissingSiteError
from pipeline.stages.survey import MinCurveParams, min_curve
from pipeline.stages.uncertainty import (
    PositionUncertainty,
    UncertaintyParams,
    position_uncertainty,
)
from pipeline.survey.mincurve import minimum_curvature
from pipeline.tables import Stations
from pipeline.uncertainty.engine import configure, find_model, model_terms, term_covariances
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.terms import Survey
from pipeline.uncertainty.toolmodel import ToolModel
from pipeline.well import WellMetadata
from tests_support import stage_context

RUN = SimpleNamespace(tool_models={})
"""The provenance a stage reads its run's tool models from (here: no plugin's)."""
DATA = Path(__file__).parent / "data"
WORKBOOK = DATA / "iscwsa-well-1-mwdrev5.json"
HPT = DATA / "iscwsa-well-1-hpt-diagnostics.dat"
#: Half a unit of the references' last printed digit (m²), plus float noise.
ROUNDING = 5.0e-5 * (1 + 1e-9)
COMPONENTS = {"nn": (0, 0), "ee": (1, 1), "vv": (2, 2), "ne": (0, 1), "nv": (0, 2), "ev": (1, 2)}
Floats = NDArray[np.float64]


def _issue_tolerance(ref: Floats) -> Floats:
    """±1 %, or ±2 m² below 200 m²."""
    out: Floats = np.maximum(0.01 * np.abs(ref), 2.0)
    return out


def _well_1() -> tuple[dict[str, Any], Survey, MagneticReference]:
    data = json.loads(WORKBOOK.read_text())
    head = data["header"]
    md = np.asarray(data["survey"]["md"], dtype=np.float64)
    inc = np.radians(data["survey"]["inc"])
    azi = np.radians(data["survey"]["azi"])
    assert head["azi_reference"] == "true" and head["convergence"] == 0.0
    survey = Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)
    field = MagneticReference(
        total_field=head["b_total"], dip=head["dip"], declination=head["declination"]
    )
    return data, survey, field


def _workbook_cells(
    data: dict[str, Any], survey: Survey, names: list[str], cov: Floats
) -> tuple[Floats, Floats, list[str]]:
    """(ours, reference, label) for every cell of the workbook table."""
    total = cov.sum(axis=0)
    vd = data["vd"]
    ours, ref, labels = [], [], []
    for row, (md, source) in enumerate(zip(vd["md"], vd["source"], strict=True)):
        k = int(np.flatnonzero(survey.md == md)[0])
        block = total[k] if source == "TOTAL" else cov[names.index(source), k]
        for comp, (i, j) in COMPONENTS.items():
            ours.append(block[i, j])
            ref.append(vd[comp][row])
            labels.append(f"{source} {comp} @ {md} m")
    return np.asarray(ours), np.asarray(ref), labels


def _mwd(
    survey: Survey, field: MagneticReference, model: str | ToolModel, **options: Any
) -> tuple[list[str], NDArray[np.float64]]:
    """Per-term NEV covariance (m²) and term names of an MWD model at the site's field."""
    return term_covariances(survey, model, ModelSite(magnetic=field), **options)


def test_workbook_well_1_every_source_and_total() -> None:
    """Rev 5 example workbook: all 35 sources and the totals, six covariance elements, at
    MD 1200, 2100, 5100 and 8000 m (864 cells), with the workbook's conventions (balanced
    tangent Jacobian, Rev 5 surface tie-on, DEC-OH 0.20°)."""
    data, survey, field = _well_1()
    names, cov = _mwd(survey, field, "ISCWSA-MWD-REV5", basis="balanced_tangent", surface_tie=True)
    assert [*names, "TOTAL"] == data["vd"]["source"][:36]
    ours, ref, labels = _workbook_cells(data, survey, names, cov)
    assert ref.size == 864
    diff = np.abs(ours - ref)
    assert np.all(diff <= _issue_tolerance(ref))
    worst = int(np.argmax(diff))
    assert diff[worst] <= ROUNDING, (labels[worst], ours[worst], ref[worst])
    big = np.abs(ref) >= 1.0  # relative agreement where rounding allows it: < 5e-5
    assert np.max(diff[big] / np.abs(ref[big])) < 5e-5


def test_workbook_well_1_with_exact_minimum_curvature() -> None:
    """The opt-in exact minimum-curvature Jacobian (instead of the standard's balanced
    tangent) stays within 0.46 % and 0.29 m² of the workbook at worst."""
    data, survey, field = _well_1()
    names, cov = _mwd(survey, field, "ISCWSA-MWD-REV5", basis="min_curve")
    ours, ref, _ = _workbook_cells(data, survey, names, cov)
    diff = np.abs(ours - ref)
    assert np.all(diff <= _issue_tolerance(ref))
    big = np.abs(ref) >= 1.0
    assert np.max(diff[big] / np.abs(ref[big])) < 0.005
    assert diff.max() < 0.3


def test_rev5_11_differs_from_the_workbook_only_in_dec_oh() -> None:
    """Rev 5.11 (DEC-OH 0.21°) against the Rev 5 workbook (0.20°): DEC-OH is (0.21/0.20)²
    = 1.1025 times the workbook's, every other source unchanged."""
    data, survey, field = _well_1()
    names, cov = _mwd(
        survey, field, "ISCWSA-MWD-REV5.11", basis="balanced_tangent", surface_tie=True
    )
    ours, ref, labels = _workbook_cells(data, survey, names, cov)
    dec_oh = np.array([label.startswith("DEC-OH ") for label in labels])
    other = ~dec_oh & ~np.array([label.startswith("TOTAL ") for label in labels])
    assert np.all(np.abs(ours[other] - ref[other]) <= ROUNDING)
    big = dec_oh & (np.abs(ref) > 1.0)
    np.testing.assert_allclose(ours[big] / ref[big], 1.1025, rtol=1e-4)
    rev5, rev511 = find_model("ISCWSA-MWD-REV5"), find_model("ISCWSA-MWD-REV5.11")
    assert [t.name for t in rev5.terms] == [t.name for t in rev511.terms]
    changed = [a.name for a, b in zip(rev5.terms, rev511.terms, strict=True) if a != b]
    assert changed == ["DEC-OH"]
    assert (rev5.term("DEC-OH").magnitude, rev511.term("DEC-OH").magnitude) == (0.20, 0.21)


def _hpt_rows() -> list[tuple[str, float, list[float]]]:
    rows = []
    for line in HPT.read_text().splitlines():
        parts = line.split()
        if len(parts) == 9 and parts[1] == "nev":
            rows.append((parts[0], float(parts[2]), [float(v) for v in parts[3:]]))
    return rows


def test_hpt_diagnostics_rev5_11() -> None:
    """An independent implementation (HPT, tool code MWD+SRGM A001Mc, DEC-OH 0.21°) at the
    first station off vertical (1230 m: vertical-hole bias terms, XCLA rule) and in the
    second build (5130 m): every source and the total to its printed precision."""
    _, survey, field = _well_1()
    names, cov = _mwd(
        survey, field, "ISCWSA-MWD-REV5.11", basis="balanced_tangent", surface_tie=True
    )
    rows = _hpt_rows()
    assert len(rows) == 2 * 36
    for source, md, values in rows:
        k = int(np.flatnonzero(survey.md == md)[0])
        block = cov.sum(axis=0)[k] if source == "TOTAL" else cov[names.index(source), k]
        ours = [block[i, j] for i, j in COMPONENTS.values()]
        assert np.all(np.abs(np.subtract(ours, values)) <= ROUNDING), (source, md, ours)


# ---------------------------------------------------------------- sensor forward model

G, B_TOTAL, DIP_DEG = 9.80665, 50000.0, 72.0
Readings = tuple[Floats, Floats]
Perturb = Callable[[Floats, Floats, float], Readings]


def _survey_angles(g: Floats, b: Floats) -> tuple[Floats, Floats]:
    """Inclination and magnetic azimuth (rad) from body gravity and field readings: the
    tool axis against the horizontal magnetic north h = B − (B·d)d and east d × h."""
    inc, _ = inclination_toolface(g)
    d = g / np.linalg.norm(g, axis=-1, keepdims=True)
    h = b - np.sum(b * d, axis=-1, keepdims=True) * d
    e = np.cross(d, h)
    return inc, np.arctan2(e[..., 2], h[..., 2])


def _shift(which: int, axis: int) -> Perturb:
    """A bias on one axis of the accelerometer (which = 0) or magnetometer (1) triad."""

    def perturb(g: Floats, b: Floats, e: float) -> Readings:
        triad = (g, b)[which].copy()
        triad[:, axis] += e
        return (triad, b) if which == 0 else (g, triad)

    return perturb


def _scale(which: int, factors: tuple[float, float, float]) -> Perturb:
    """Scale-factor errors e·factors on the axes of one triad."""

    def perturb(g: Floats, b: Floats, e: float) -> Readings:
        triad = (g, b)[which] * (1.0 + e * np.asarray(factors))
        return (triad, b) if which == 0 else (g, triad)

    return perturb


#: Sensor error, toolface of the x axis (rad), step and the model's weight per unit of it.
#: TI1/TI2 biases are the high-side (x at toolface 0) and lateral (y) components; the xy
#: scale factors split into a common part (σ/√2) and a differential one whose cos 2ψ and
#: sin 2ψ halves (σ/2 each) are TI2 (toolface 0) and TI3 (toolface 45°).
SENSOR_CASES: dict[str, tuple[Perturb, float, float, float]] = {
    "ABXY-TI1S": (_shift(0, 0), 0.0, 1e-6, 1.0),
    "ABXY-TI2S": (_shift(0, 1), 0.0, 1e-6, 1.0),
    "ABZ": (_shift(0, 2), 0.0, 1e-6, 1.0),
    "ASXY-TI1S": (_scale(0, (1.0, 1.0, 0.0)), 0.0, 1e-7, 1 / np.sqrt(2)),
    "ASXY-TI2S": (_scale(0, (1.0, -1.0, 0.0)), 0.0, 1e-7, 0.5),
    "ASXY-TI3S": (_scale(0, (1.0, -1.0, 0.0)), np.pi / 4, 1e-7, 0.5),
    "ASZ": (_scale(0, (0.0, 0.0, 1.0)), 0.0, 1e-7, 1.0),
    "MBXY-TI1S": (_shift(1, 0), 0.0, 1e-2, 1.0),
    "MBXY-TI2S": (_shift(1, 1), 0.0, 1e-2, 1.0),
    "MBZ": (_shift(1, 2), 0.0, 1e-2, 1.0),
    "AMIL": (_shift(1, 2), 0.0, 1e-2, 1.0),
    "MSXY-TI1S": (_scale(1, (1.0, 1.0, 0.0)), 0.0, 1e-7, 1 / np.sqrt(2)),
    "MSXY-TI2S": (_scale(1, (1.0, -1.0, 0.0)), 0.0, 1e-7, 0.5),
    "MSXY-TI3S": (_scale(1, (1.0, -1.0, 0.0)), np.pi / 4, 1e-7, 0.5),
    "MSZ": (_scale(1, (0.0, 0.0, 1.0)), 0.0, 1e-7, 1.0),
}


@pytest.mark.parametrize("name", sorted(SENSOR_CASES))
def test_sensor_weights_match_the_tool_forward_model(name: str) -> None:
    """Ideal accelerometer and magnetometer readings of a tool at (I, Am, toolface), one
    sensor error applied, inclination and magnetic azimuth recomputed: the central
    difference equals the term's (I, α) weight, up to the term's sign convention."""
    inc = np.radians([10.0, 35.0, 60.0, 85.0, 120.0])
    azi = np.radians([20.0, 75.0, 140.0, 250.0, 330.0])  # magnetic (declination 0 below)
    perturb, toolface, step, per_sigma = SENSOR_CASES[name]
    c_bn = body_to_ned(azi, inc, np.full(inc.size, toolface))
    dip = np.radians(DIP_DEG)
    g = to_body(c_bn, [0.0, 0.0, G])
    b = to_body(c_bn, B_TOTAL * np.array([np.cos(dip), 0.0, np.sin(dip)]))
    inc_p, azi_p = _survey_angles(*perturb(g, b, step))
    inc_m, azi_m = _survey_angles(*perturb(g, b, -step))
    d_inc = (inc_p - inc_m) / (2 * step)
    d_azi = np.angle(np.exp(1j * (azi_p - azi_m))) / (2 * step)
    measured = per_sigma * np.stack((d_inc, d_azi * np.sin(inc)), axis=-1)

    field = MagneticReference(total_field=B_TOTAL, dip=DIP_DEG, declination=0.0)
    term = next(
        t
        for t in model_terms(find_model("ISCWSA-MWD-REV5.11"), ModelSite(magnetic=field, g=G))
        if t.name == name
    )
    weight = term.weight(Survey.of(np.arange(inc.size) * 30.0, inc, azi, np.zeros(inc.size)))
    assert np.all(weight[:, 0] == 0.0)  # sensor errors leave MD alone
    sign = np.sign(np.sum(measured * weight[:, 1:]))
    scale = np.abs(weight[:, 1:]).max()
    np.testing.assert_allclose(sign * measured, weight[:, 1:], rtol=0, atol=1e-6 * scale)


# ---------------------------------------------------------------- agreement with welleng


@pytest.mark.parametrize("vertical_azimuth", [0.0, 30.0])
def test_agreement_with_welleng_iscwsa_mwd_rev5_11(vertical_azimuth: float) -> None:
    """welleng's ISCWSA MWD Rev5.11 on a build-and-turn well from a vertical top hole, term
    by term. XCLA/XCLH differ by 1.5e-6 (relative): welleng rounds the tortuosity 1°/100 ft
    to 0.000572615 rad/m. ABXY-TI2S: welleng's vertical-hole special case doubles only the
    east component of station 1's lateral error for the surface tie-on, so with a vertical
    azimuth A ≠ 0 its north component (−sin A) is not doubled; we double the whole lateral
    vector. Its east-vertical block agrees exactly, and with A = 0 (as on ISCWSA well #1)
    the whole term does."""
    we = pytest.importorskip("welleng")
    md = np.arange(0.0, 3001.0, 30.0)
    inc_deg = np.clip((md - 300.0) / 1500.0 * 70.0, 0.0, 70.0)
    turn = vertical_azimuth + 30.0 + (md - 300.0) / 50.0
    azi_deg = np.where(md > 300.0, turn, vertical_azimuth) % 360.0
    inc, azi = np.radians(inc_deg), np.radians(azi_deg)
    survey = Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)
    field = MagneticReference(total_field=51000.0, dip=70.0, declination=5.0)
    header = we.survey.SurveyHeader(
        latitude=60.0,
        longitude=5.0,
        b_total=field.total_field,
        dip=field.dip,
        declination=field.declination,
        G=9.80665,
        azi_reference="true",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = we.survey.Survey(
            md=md, inc=inc_deg, azi=azi_deg, header=header, error_model="ISCWSA MWD Rev5.11"
        ).err.errors.errors
    names, cov = _mwd(
        survey, field, "ISCWSA-MWD-REV5.11", basis="balanced_tangent", surface_tie=True
    )
    assert sorted(names) == sorted(ref)
    for k, name in enumerate(names):
        theirs = ref[name].cov_NEV
        rel = np.abs(theirs - cov[k]).max() / np.abs(theirs).max()
        if name == "ABXY-TI2S" and vertical_azimuth != 0.0:
            ev = np.abs(theirs[:, 1:, 1:] - cov[k][:, 1:, 1:]).max()
            assert ev <= 1e-9 * np.abs(theirs).max()
            assert rel > 1e-3  # the north component, see above
        else:
            assert rel <= (2e-6 if name.startswith("XCL") else 1e-9), name


# ---------------------------------------------------------------- stage


def _trajectory(md: Floats, inc: Floats, azi: Floats, north: str, well: WellMetadata) -> Any:
    ctx: Any = stage_context(well, provenance=RUN)
    stations: pa.Table = Stations.compiled().make_table(
        {"md": md, "inc": inc, "azi": azi}, north_reference=north
    )
    return min_curve({"stations": stations}, MinCurveParams(tie_tvd=0.0), ctx), ctx


@pytest.mark.parametrize(("north", "to_true"), [("grid", 1.5), ("magnetic", 12.0), ("true", 0.0)])
def test_stage_mwd_model_matches_library(north: str, to_true: float) -> None:
    """Azimuths are referred to true north before the MWD terms see them: grid through the
    well's convergence (1.5°), magnetic through the reference declination (12°); the
    magnetic azimuth of the terms is then true − declination. The covariance comes back in
    the listing's north: the true-north one turned by δ = ``to_true`` (N' = N cos δ + E sin δ,
    E' = E cos δ − N sin δ)."""
    md = np.arange(0.0, 2001.0, 30.0)
    inc = np.clip((md - 300.0) / 20.0, 0.0, 60.0)
    azi = np.full(md.size, 120.0)
    traj, ctx = _trajectory(md, inc, azi, north, WellMetadata(grid_convergence=1.5))
    field = MagneticReference(total_field=55000.0, dip=75.0, declination=12.0)
    params = UncertaintyParams(model="ISCWSA-MWD-REV5.11", magnetic=field, tool={"amil": 300.0})
    out = position_uncertainty(traj, params, ctx)["trajectory"]
    PositionUncertainty.validate_table(out)
    i, a = np.radians(inc), np.radians(azi + to_true)
    survey = Survey.of(md, i, a, minimum_curvature(md, i, a).tvd)
    _, cov = _mwd(survey, field, configure("ISCWSA-MWD-REV5.11", {"amil": 300.0}))
    c, s = np.cos(np.radians(to_true)), np.sin(np.radians(to_true))
    turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    total = turn @ cov.sum(axis=0) @ turn.T
    for name, (r, k) in COMPONENTS.items():
        np.testing.assert_allclose(
            out.column(f"cov_{name}").to_numpy(), total[:, r, k], rtol=1e-9, atol=1e-12
        )


def test_stage_mwd_field_from_wmm_at_the_wellhead() -> None:
    """Without ``magnetic`` the stage takes WMM2025 at the well's position and date."""
    md = np.arange(0.0, 1201.0, 30.0)
    inc = np.clip((md - 300.0) / 20.0, 0.0, 40.0)
    well = WellMetadata(
        latitude=61.25, longitude=73.4, elevation=50.0, survey_date=dt.date(2026, 11, 21)
    )
    traj, ctx = _trajectory(md, inc, np.full(md.size, 200.0), "true", well)
    out = position_uncertainty(traj, UncertaintyParams(model="ISCWSA-MWD-REV5"), ctx)
    field = reference_field(61.25, 73.4, 50.0, dt.date(2026, 11, 21)).reference()
    assert 59_000 < field.total_field < 60_500 and 77.5 < field.dip < 79.0  # ENGINEERING.md
    i, a = np.radians(inc), np.radians(np.full(md.size, 200.0))
    survey = Survey.of(md, i, a, minimum_curvature(md, i, a).tvd)
    total = _mwd(
        survey,
        field,
        "ISCWSA-MWD-REV5",
    )[1].sum(axis=0)
    np.testing.assert_allclose(out["trajectory"].column("cov_ee").to_numpy(), total[:, 1, 1])


def test_stage_mwd_parameters_are_checked() -> None:
    with pytest.raises(ValueError, match="unknown tool fields"):
        UncertaintyParams(model="ISCWSA-MWD-REV5", tool={"gxy_gd": 1.0})
    with pytest.raises(ValueError, match="apply to gyro models"):
        UncertaintyParams(model="ISCWSA-MWD-REV5", init_sigma_azi=1.0)
    with pytest.raises(ValueError, match="magnetic applies to MWD"):
        UncertaintyParams(magnetic=MagneticReference(total_field=5e4, dip=70, declination=0))
    with pytest.raises(ValueError, match="unknown model"):
        UncertaintyParams(model="MWD")
    md = np.arange(0.0, 91.0, 30.0)
    traj, ctx = _trajectory(md, np.zeros(4), np.zeros(4), "true", WellMetadata(latitude=60.0))
    with pytest.raises(
        MissingSiteError, match=r"`magnetic_field`.*missing: `longitude`, `survey_date`.*`magnetic`"
    ):
        position_uncertainty(traj, UncertaintyParams(model="ISCWSA-MWD-REV5"), ctx)


def test_the_default_settings_reproduce_the_workbook_through_the_api() -> None:
    """``gp.position_uncertainty`` with nothing but the model and the field set gives the
    workbook's TOTAL covariance at every tabulated depth (the ISCWSA conventions are the
    defaults; the exact minimum-curvature Jacobian is an opt-in)."""
    data, _, field = _well_1()
    stations = Stations.compiled().make_table(
        {key: data["survey"][key] for key in ("md", "inc", "azi")}, north_reference="true"
    )
    trajectory = gp.minimum_curvature(stations, tie_tvd=0.0)
    out = gp.position_uncertainty(trajectory, model="ISCWSA-MWD-REV5", magnetic=field.__dict__)
    vd = data["vd"]
    rows = [i for i, source in enumerate(vd["source"]) if source == "TOTAL"]
    assert len(rows) == 4
    for row in rows:
        k = int(np.flatnonzero(out.column("md").to_numpy() == vd["md"][row])[0])
        for comp in COMPONENTS:
            assert abs(out.column(f"cov_{comp}")[k].as_py() - vd[comp][row]) <= 5e-5, comp
    exact = gp.position_uncertainty(
        trajectory, model="ISCWSA-MWD-REV5", magnetic=field.__dict__, basis="min_curve"
    )
    assert not np.allclose(exact.column("cov_nn").to_numpy(), out.column("cov_nn").to_numpy())

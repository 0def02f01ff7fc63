"""Validity ranges of tool models (issue 29): a station outside a model's inclination range,
or with a σ beyond any physical position error, is refused or flagged — never a number.

GYRO-NS (OWSG: 0–89°) on ISCWSA test well #1 (to 90° at MD 5400 m) gave a lateral σ of
3.3e18 m: tan 90° ≈ 1.6e16 passed the finite check. GYRO-NS-CT switches its stationary gyro
terms at the static end inclination (frozen above it, SPE 90408) and holds to 150°.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
from numpy.typing import NDArray

import pipeline as gp
import pipeline.uncertainty as pu
from pipeline.errors import StageError, ToolModelError
from pipeline.survey.mincurve import minimum_curvature
from pipeline.uncertainty.engine import PHYSICAL_BOUND_M, OutsideValidityError
from tests_support import gyropipe_cli

DATA = Path(__file__).parent / "data"
SITE = pu.ModelSite(latitude=60.0)
Floats = NDArray[np.float64]


def _well_1() -> tuple[Floats, Floats, Floats]:
    """ISCWSA test well #1: MD (m), inclination and true azimuth (deg); 90° from 5400 m."""
    data = json.loads((DATA / "iscwsa-well-1-mwdrev5.json").read_text())
    return tuple(np.asarray(data["survey"][k], dtype=np.float64) for k in ("md", "inc", "azi"))  # type: ignore[return-value]


def _survey(md: Floats, inc_deg: Floats, azi_deg: Floats) -> pu.Survey:
    inc, azi = np.radians(inc_deg), np.radians(azi_deg)
    return pu.Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)


def _sigma(cov: Floats) -> Floats:
    return np.sqrt(np.trace(cov, axis1=-2, axis2=-1))


# ---------------------------------------------------------------- the format


def test_shipped_models_state_their_ranges() -> None:
    ranges = {n: pu.find_model(n).inclination_range_deg for n in pu.model_files()}
    assert ranges["GYRO-NS"] == (0.0, 89.0)  # OWSG A020Gb
    assert ranges["GYRO-MWD"] == (0.0, 89.0)  # OWSG A019Gb (the file extends GYRO-NS)
    assert ranges["GYRO-NS-noXCL"] == (0.0, 89.0)  # inherited
    assert ranges["GYRO-NS-CT"] == (0.0, 150.0)  # OWSG A021Gc
    assert ranges["ISCWSA-MWD-REV4"] == (0.0, 180.0)  # no limit stated: all of it
    shown = gyropipe_cli("models", "GYRO-NS-CT", check=True).stdout
    assert "valid for inclinations 0–150°" in shown
    assert "GXY-RN-INIT azi       systematic" in shown
    assert "GXY-B1 (above static_end_inc: freeze)" in shown


def test_a_child_inherits_or_sets_its_range(tmp_path: Path) -> None:
    inherit = tmp_path / "inherit.yaml"
    inherit.write_text("format: gyropipe-tool-model/1\nname: V-1\nextends: GYRO-NS\n")
    own = tmp_path / "own.yaml"
    own.write_text(
        "format: gyropipe-tool-model/1\nname: V-2\nextends: GYRO-NS\n"
        "validity: {inclination_deg: [0, 70]}\n"
    )
    assert pu.find_model(inherit).inclination_range_deg == (0.0, 89.0)
    assert pu.find_model(own).inclination_range_deg == (0.0, 70.0)


@pytest.mark.parametrize(
    ("text", "where", "words"),
    [
        ("validity: {inclination_deg: [80, 20]}", ":4:", "must rise within 0–180°"),
        ("validity: {inclination_deg: [0, 200]}", ":4:", "must rise within 0–180°"),
        ("validity: {inclinations: [0, 80]}", ":4:", "inclinations"),
        (
            "terms:\n  - {name: X, acts_on: [azi], mode: random, magnitude: 1, unit: deg,\n"
            "     weight: AZ, switch: {at: nowhere, above: freeze}}",
            ":5:",
            "switch at 'nowhere', not a parameter",
        ),
        (
            "terms:\n  - {name: X, acts_on: [azi], mode: random, magnitude: 1, unit: deg,\n"
            "     weight: AZ, switch: {at: tortuosity, above: thaw}}",
            ":6:",
            "thaw",
        ),
    ],
)
def test_a_bad_range_or_switch_is_located(
    tmp_path: Path, text: str, where: str, words: str
) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(f"format: gyropipe-tool-model/1\nname: BAD\nextends: GYRO-NS\n{text}\n")
    with pytest.raises(ToolModelError) as info:
        pu.find_model(path)
    message = str(info.value)
    assert f"bad.yaml{where}" in message and words in message, message


# ---------------------------------------------------------------- the switch


def test_stationary_terms_freeze_at_the_static_end_inclination() -> None:
    """GYRO-NS-CT above 15°: GXY-B1S keeps the azimuth error it has at 15° (interpolated
    between the stations at 10° and 20°), GXY-RN stops and GXY-RN-INIT carries the
    initialisation's noise; after a drop to 12° and a rise again, frozen anew."""
    md = np.arange(0.0, 301.0, 30.0)
    inc = np.array([0.0, 10.0, 20.0, 40.0, 60.0, 85.0, 60.0, 12.0, 30.0, 50.0, 89.9])
    azi = np.array([0.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0])
    survey = _survey(md, inc, azi)
    terms = {t.name: t for t in pu.model_terms(pu.find_model("GYRO-NS-CT"), SITE)}
    omega_h = pu.quantities.EARTH_RATE_RAD_H * np.cos(np.radians(60.0))

    def b1(i_deg: float, a_deg: float) -> float:  # the sheet's ∂A of GXY-B1
        i, a = np.radians(i_deg), np.radians(a_deg)
        return float(np.sin(a) / (omega_h * np.cos(i)))

    d_azi = terms["GXY-B1S"].weight(survey)[1:, 2] / np.sin(survey.inc[1:])  # ∂A
    tilt = lambda i, a: b1(i, a) * np.sin(np.radians(i))  # noqa: E731 (α = ∂A·sin I)
    first = (tilt(10, 30) + 0.5 * (tilt(20, 40) - tilt(10, 30))) / np.sin(np.radians(15.0))
    second = (tilt(12, 90) + 1 / 6 * (tilt(30, 100) - tilt(12, 90))) / np.sin(np.radians(15.0))
    np.testing.assert_allclose(d_azi[0], b1(10, 30), rtol=1e-12)  # live below (station 1)
    np.testing.assert_allclose(d_azi[1:6], first, rtol=1e-12)
    np.testing.assert_allclose(d_azi[6], b1(12, 90), rtol=1e-12)
    np.testing.assert_allclose(d_azi[7:], second, rtol=1e-12)  # not 1/cos 89.9°
    rn, init = terms["GXY-RN"].weight(survey), terms["GXY-RN-INIT"].weight(survey)
    above = inc > 15.0
    assert not rn[above].any() and rn[~above][1:, 2].all()  # (station 0: vertical)
    assert not init[~above].any() and init[above, 2].all()
    assert terms["GXY-RN-INIT"].mode == "systematic"


def test_gyro_ns_ct_holds_to_90_degrees_with_frozen_terms() -> None:
    """Before: GYRO-NS-CT evaluated 1/cos I on; σ on well #1 was ≈ 5e18 m past 89°."""
    cov = pu.covariance(_survey(*_well_1()), "GYRO-NS-CT", SITE)
    md = _well_1()[0]
    sigma = _sigma(cov)
    assert np.isfinite(sigma).all() and (sigma <= 0.05 * md + 1.0).all(), sigma.max()


# ---------------------------------------------------------------- refused or flagged


@pytest.mark.parametrize("model", ["GYRO-NS", "GYRO-MWD"])
def test_gyro_ns_on_well_1_is_refused_by_default(model: str) -> None:
    with pytest.raises(OutsideValidityError) as info:
        pu.covariance(_survey(*_well_1()), model, SITE)
    message = str(info.value)
    for words in (model, "0–89°", "MD 5400 m", "90°", "88 station(s)", "outside_validity"):
        assert words in message, message


@pytest.mark.parametrize("model", ["GYRO-NS", "GYRO-MWD"])
def test_gyro_ns_on_well_1_flagged_gives_nan_there(model: str) -> None:
    md, inc, azi = _well_1()
    _, per_term = pu.term_covariances(_survey(md, inc, azi), model, SITE, outside_validity="flag")
    sigma = _sigma(per_term.sum(axis=0))
    outside = md >= 5400.0
    assert np.isnan(per_term[:, outside]).all()
    assert np.isfinite(sigma[~outside]).all()
    assert sigma[~outside].max() < 1000.0  # (before: 3.3e18 m lateral at 90°)
    refused_above = pu.covariance(_survey(md[~outside], inc[~outside], azi[~outside]), model, SITE)
    np.testing.assert_array_equal(per_term.sum(axis=0)[~outside], refused_above)


def test_a_sigma_beyond_any_physical_error_is_refused_or_flagged(tmp_path: Path) -> None:
    """A term inside its model's range that grows without bound (here 1/cos I, as GYRO-NS's
    terms do) is stopped by the physical bound: σ ≤ 2·MD + 10 m."""
    path = tmp_path / "wild.yaml"
    path.write_text(
        textwrap.dedent(
            """\
            format: gyropipe-tool-model/1
            name: WILD
            terms:
              - {name: W, acts_on: [azi], mode: systematic, magnitude: 1, unit: deg,
                 weight: {azi: "1 / cos(inc)"}}
            """
        )
    )
    md = np.arange(0.0, 1201.0, 30.0)
    inc = np.minimum(md / 10.0, 90.0)
    survey = _survey(md, inc, np.full(md.size, 45.0))
    with pytest.raises(OutsideValidityError, match="beyond any physical position error"):
        pu.covariance(survey, path)
    sigma = _sigma(pu.covariance(survey, path, outside_validity="flag"))
    bound = 2.0 * md + PHYSICAL_BOUND_M
    given = np.isfinite(sigma)
    assert given[:5].all() and not given[-5:].any()
    assert np.all(sigma[given] <= bound[given])
    first = int(np.argmin(given))
    assert not given[first:].any()  # from the first one beyond on


# ---------------------------------------------------------------- the Python API and CLI


def _trajectory() -> Any:
    md, inc, azi = _well_1()
    stations = pd.DataFrame({"md": md, "inc": inc, "azi": azi})
    stations.attrs["north_reference"] = "true"
    return gp.minimum_curvature(stations, well={"latitude": 60.0})


def test_position_uncertainty_refuses_or_flags_through_the_api() -> None:
    trajectory = _trajectory()
    with pytest.raises(StageError, match="GYRO-NS holds for inclinations 0–89°"):
        gp.position_uncertainty(trajectory, model="GYRO-NS", latitude=60.0)
    out = gp.position_uncertainty(
        trajectory, model="GYRO-NS", latitude=60.0, outside_validity="flag"
    )
    flagged = out["outside_validity"].to_numpy()
    np.testing.assert_array_equal(flagged, out["md"].to_numpy() >= 5400.0)
    for column in ("cov_nn", "ellipse_major", "sigma_v", "ellipse_major_conf"):
        assert out[column][flagged].isna().all() and out[column][~flagged].notna().all()
    assert out["ellipse_major"].max() < 1000.0
    refused = gp.position_uncertainty(trajectory.iloc[:170], model="GYRO-NS", latitude=60.0)
    assert "outside_validity" not in refused.columns  # the column comes with the flag


PIPELINE = """\
name: gyro-ns-to-90
version: "1.0"
inputs:
  stations: {{description: stations}}
well: {{north_reference: "true", latitude: 60.0}}
stages:
  - id: read
    uses: read_stations
    with: {{input: stations}}
  - id: trajectory
    uses: minimum_curvature
    inputs: {{stations: read.stations}}
  - id: uncertainty
    uses: position_uncertainty
    inputs: {{trajectory: trajectory.trajectory}}
    with: {{model: GYRO-NS{extra}}}
    persist: [trajectory]
"""


def test_gyropipe_run_refuses_or_flags(tmp_path: Path) -> None:
    md, inc, azi = _well_1()
    stations = tmp_path / "well-1.csv"
    pd.DataFrame({"MD (m)": md, "Inc (deg)": inc, "Azimuth True (deg)": azi}).to_csv(
        stations, index=False
    )
    refuse = tmp_path / "refuse.yaml"
    refuse.write_text(PIPELINE.format(extra=""))
    result = gyropipe_cli("run", refuse, "--input", stations, "--out", tmp_path / "r")
    assert result.returncode != 0
    assert "GYRO-NS holds for inclinations 0–89°" in result.stderr
    assert "Traceback" not in result.stderr
    flag = tmp_path / "flag.yaml"
    flag.write_text(PIPELINE.format(extra=", outside_validity: flag"))
    gyropipe_cli("run", flag, "--input", stations, "--out", tmp_path / "f", check=True)
    table = pq.read_table(tmp_path / "f" / "uncertainty.trajectory.parquet")
    flagged = table.column("outside_validity").to_numpy()
    np.testing.assert_array_equal(flagged, table.column("md").to_numpy() >= 5400.0)
    major = table.column("ellipse_major").to_numpy()
    assert np.isnan(major[flagged]).all() and major[~flagged].max() < 1000.0

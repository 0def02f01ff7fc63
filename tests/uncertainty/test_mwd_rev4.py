"""The ISCWSA MWD Rev 4 tool model (a shipped model file) against the ISCWSA standard
clearance set: every well's 1σ high-side, lateral and along-hole position uncertainty.

The set (``tests/data/iscwsa-clearance``, README there) prints σ to four decimals (m). At
every station from MD 30 m down, σH, σL and σA agree within 0.5 % (reached: 0.14 %). Two
stations at the surface are conventions of the set, held to what they are:

- MD 0 (the slot, the set's origin): the set gives 0 for all three σ. Under the ISCWSA
  surface tie-on the first station carries its own depth error DRFR along hole (0.35 m, the
  σA the set gives from MD 1 m on); its σH and σL are 0 as in the set.
- MD 1 m (1 m below the slot, vertical): σH = σL = 0.00179 m here against the set's 0.0017
  (0.0018 for well 06, azimuth 358°): 0.09 mm, the rounding of a value near 0.00175.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

import pipeline.uncertainty as pu
from pipeline.earth.site import MagneticReference

SET = Path(__file__).parents[1] / "data" / "iscwsa-clearance" / "wells-01-06.json"
WELLS: dict[str, Any] = json.loads(SET.read_text())["wells"]
Floats = NDArray[np.float64]


def _site(header: dict[str, Any]) -> pu.ModelSite:
    assert header["convergence"] == 0.0 and header["azi_reference"] == "grid"  # grid = true
    field = MagneticReference(
        total_field=header["b_total"],
        dip=float(np.degrees(header["dip"])),  # the set gives dip in radians
        declination=header["declination"],
    )
    return pu.ModelSite(latitude=header["latitude"], magnetic=field, g=header["G"])


def _survey(well: dict[str, Any]) -> pu.Survey:
    return pu.Survey.of(
        well["MD"], np.radians(well["IncDeg"]), np.radians(well["AziDeg"]), well["TVD"]
    )


@pytest.mark.parametrize("name", sorted(WELLS))
def test_rev4_reproduces_the_clearance_set_sigmas(name: str) -> None:
    well = WELLS[name]
    survey = _survey(well)
    cov = pu.covariance(survey, "iscwsa-mwd-rev4", _site(well["header"]))
    ours = pu.hla_sigma(cov, survey.inc, survey.azi).T
    ref = np.array([well["sigmaH"], well["sigmaL"], well["sigmaA"]])
    assert well["MD"][:3] == [0, 1, 30]
    rel = np.abs(ours[:, 2:] - ref[:, 2:]) / ref[:, 2:]
    assert rel.max() <= 0.005, (name, np.unravel_index(rel.argmax(), rel.shape))
    assert rel.max() <= 0.0015  # what the model reaches: 0.14 % at worst
    # the surface conventions of the module docstring
    np.testing.assert_allclose(ours[:2, 0], 0.0, atol=1e-15)
    assert ref[2, 0] == 0.0 and ours[2, 0] == pytest.approx(0.35, abs=1e-12)
    assert np.abs(ours[:, 1] - ref[:, 1]).max() <= 1e-4


def test_rev4_model_file() -> None:
    """The file is the ISCWSA Rev 4 sheet: 27 terms (no XCL, SAG not SAGE, XYM3/XYM4
    systematic, global DECG/DBHG), reading the geomagnetic field only."""
    model = pu.find_model("ISCWSA-MWD-REV4")
    assert model is pu.find_model("iscwsa-mwd-rev4")
    assert len(model.terms) == 27
    assert model.needs == {"magnetic"}
    modes = {t.name: t.mode for t in model.terms}
    assert modes["XYM3"] == modes["XYM4"] == modes["SAG"] == "systematic"
    assert modes["DECG"] == modes["DBHG"] == modes["DSTG"] == "global"
    assert modes["DECR"] == modes["DBHR"] == modes["DRFR"] == "random"
    assert model.term("DECG").sigma == pytest.approx(np.radians(0.36), rel=1e-15)
    assert model.term("DBHG").sigma == pytest.approx(np.radians(5000.0), rel=1e-15)
    assert not any(t.name.startswith("XCL") for t in model.terms)


def test_rev4_agrees_with_welleng() -> None:
    """welleng's ISCWSA MWD Rev4 on the reference well: the total NEV covariance within
    0.5 % of its largest element at every station, 0.01 % at TD. welleng does not double the first leg's
    angle weights (the ISCWSA surface tie-on), which the set does (its σH at MD 30 m is
    0.0537 m; welleng's 0.0529): the difference is largest near the surface."""
    we = pytest.importorskip("welleng")
    well = WELLS["Reference well"]
    h = well["header"]
    header = we.survey.SurveyHeader(
        latitude=h["latitude"],
        longitude=h["longitude"],
        b_total=h["b_total"],
        dip=h["dip"],
        declination=h["declination"],
        convergence=h["convergence"],
        vertical_inc_limit=h["vertical_inc_limit"],
        G=h["G"],
        azi_reference=h["azi_reference"],
        deg=False,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = we.survey.Survey(
            md=well["MD"],
            inc=well["IncDeg"],
            azi=well["AziDeg"],
            header=header,
            error_model="ISCWSA MWD Rev4",
        ).cov_nev
    ours = pu.covariance(_survey(well), "ISCWSA-MWD-REV4", _site(h))
    scale = np.abs(theirs).max(axis=(1, 2))
    diff = np.abs(ours - theirs).max(axis=(1, 2))
    assert np.all(diff <= 0.005 * scale)  # reached: 0.48 % (MD 210 m, vertical)
    assert diff[-1] <= 1e-4 * scale[-1]  # at TD within 0.01 %

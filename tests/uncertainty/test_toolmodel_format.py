"""The tool-model file format: weights written as formulas (the OWSG sheets' published
formulas) give what the coded ISCWSA weighting functions give; every problem of a file is a
typed error located at its file, line and column; a vendor's file is selected by path in the
stage and the API, and checked by ``gyropipe models``."""

from __future__ import annotations

import datetime as dt
import json
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.typing import NDArray

import pipeline as gp
import pipeline.uncertainty as pu
from pipeline.api import stages
from pipeline.earth.site import MagneticReference
from pipeline.errors import ParameterError, ToolModelError
from pipeline.registry import Provenance, StageSetup
from pipeline.reports.literature import Citations
from pipeline.reports.parts import Parts
from pipeline.survey.mincurve import minimum_curvature
from pipeline.tables import Stations
from pipeline.uncertainty.engine import SurveyValueError
from pipeline.uncertainty.formula import Formula, FormulaError
from pipeline.uncertainty.terms import stack
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli

DATA = Path(__file__).parent / "data"
LAT = 60.0
FIELD = MagneticReference(total_field=50000.0, dip=72.0, declination=-4.0)
Floats = NDArray[np.float64]

#: The OWSG sheets' weighting formulas (GYRO-NS A020Gb and the ISCWSA MWD Rev 5 sheet), in
#: this format's names: ``azi`` is ∂A/∂ε, ``azi_sin_inc`` ∂A/∂ε·sin I where ∂A has 1/sin I.
#: The course-length terms XCLA/XCLH are in position for every model (:data:`XCL_NEV`, the
#: ISCWSA Rev 5 form), not the gyro sheets' inclination/azimuth form.
FORMULAS: dict[str, dict[str, str]] = {
    "DRFR": {"depth": "1"},
    "DSFS": {"depth": "md"},
    "DSTG": {"depth": "md * tvd"},
    "SAGE": {"inc": "abs(sin(inc)) ** 0.25"},
    "XYM1": {"inc": "abs(sin(inc))"},
    "XYM2": {"azi": "-1"},
    "XYM3E": {
        "inc": "abs(cos(inc)) * cos(azi) * where(dmd > 0, maximum(1, sqrt(10 / dmd)), 0)",
        "azi_sin_inc": "-abs(cos(inc)) * sin(azi) * where(dmd > 0, maximum(1, sqrt(10 / dmd)), 0)",
    },
    "XYM4E": {
        "inc": "abs(cos(inc)) * sin(azi) * where(dmd > 0, maximum(1, sqrt(10 / dmd)), 0)",
        "azi_sin_inc": "abs(cos(inc)) * cos(azi) * where(dmd > 0, maximum(1, sqrt(10 / dmd)), 0)",
    },
    "AXYZ-MIS": {"inc": "1"},
    "AXYZ-SF": {"inc": "1.3 * sin(inc) * cos(inc)"},
    "AXYZ-ZB": {"inc": "sin(inc) / g"},
    "GXY-B1R": {"azi": "sin(azi) / (earth_rate * cos(latitude) * cos(inc))"},
    "GXY-B2R": {"azi": "cos(azi) / (earth_rate * cos(latitude))"},
    "GXY-G1": {"azi": "cos(azi) * sin(inc) / (earth_rate * cos(latitude))"},
    "GXY-G4": {"azi": "sin(azi) * tan(inc) / (earth_rate * cos(latitude))"},
    "GXY-RN": {
        "azi": "noise_reduction * sqrt(1 - cos(azi) ** 2 * sin(inc) ** 2)"
        " / (earth_rate * cos(latitude) * cos(inc))"
    },
    "ABXY-TI1S": {"inc": "-cos(inc) / g", "azi": "cos(inc) * tan(dip) * sin(azm) / g"},
    "ABXY-TI2S": {"azi_sin_inc": "(cos(inc) - tan(dip) * cos(azm) * sin(inc)) / g"},
    "ABZ": {"inc": "-sin(inc) / g", "azi": "sin(inc) * tan(dip) * sin(azm) / g"},
    "MBXY-TI1S": {"azi": "-cos(inc) * sin(azm) / b_horiz"},
    "MBZ": {"azi": "-sin(inc) * sin(azm) / b_horiz"},
    "MSZ": {"azi": "-(sin(inc) * cos(azm) + tan(dip) * cos(inc)) * sin(inc) * sin(azm)"},
    "DEC-U": {"azi": "1"},
    "DBH-U": {"azi": "1 / (b_total * cos(dip))"},
    "AMIL": {"azi": "sin(inc) * sin(azm) / b_horiz"},
}
XCL_NEV = {
    "XCLA": {
        "north": "-dmd * maximum(where(prev(inc) < 1e-4, 0, abs(sin(inc) * sin(wrap(azi - prev(azi))))),"
        " tortuosity * dmd) * sin(azi)",
        "east": "dmd * maximum(where(prev(inc) < 1e-4, 0, abs(sin(inc) * sin(wrap(azi - prev(azi))))),"
        " tortuosity * dmd) * cos(azi)",
    },
    "XCLH": {
        "north": "dmd * maximum(abs(inc - prev(inc)), tortuosity * dmd) * cos(inc) * cos(azi)",
        "east": "dmd * maximum(abs(inc - prev(inc)), tortuosity * dmd) * cos(inc) * sin(azi)",
        "vertical": "-dmd * maximum(abs(inc - prev(inc)), tortuosity * dmd) * sin(inc)",
    },
}


def _survey() -> pu.Survey:
    """ISCWSA test well #1 to 5100 m (60° hold; the gyro models' range)."""
    data = json.loads((DATA / "iscwsa-well-1-mwdrev5.json").read_text())
    md = np.asarray(data["survey"]["md"], dtype=np.float64)
    keep = np.asarray(data["survey"]["inc"]) <= 60.0
    inc = np.radians(data["survey"]["inc"])[keep]
    azi = np.radians(data["survey"]["azi"])[keep]
    md = md[keep]
    return pu.Survey.of(md, inc, azi, minimum_curvature(md, inc, azi).tvd)


def _as_formulas(model: pu.ToolModel, path: Path) -> Path:
    """The model re-written with every term of :data:`FORMULAS` and :data:`XCL_NEV` as
    formulas, the others by code."""
    terms = []
    for t in model.terms:
        weight: Any = t.code
        if t.name in XCL_NEV:
            weight = XCL_NEV[t.name]
        elif t.name in FORMULAS:
            weight = FORMULAS[t.name]
        acts_on = list(t.acts_on)
        terms.append(
            {
                "name": t.name,
                "acts_on": acts_on,
                "mode": t.mode,
                "magnitude": t.magnitude,
                "unit": t.unit,
                "weight": weight,
            }
        )
    params = {k: {"value": v, "unit": "-"} for k, v in model.parameters.items()}
    doc = {"format": "gyropipe-tool-model/1", "name": f"{model.name}-F", "terms": terms}
    if params:
        doc["parameters"] = params
    path.write_text(json.dumps(doc))  # JSON is YAML
    return path


@pytest.mark.parametrize(
    ("name", "site"),
    [("GYRO-NS", pu.ModelSite(latitude=LAT)), ("ISCWSA-MWD-REV5.11", pu.ModelSite(magnetic=FIELD))],
)
def test_published_formulas_give_the_coded_weights(
    name: str, site: pu.ModelSite, tmp_path: Path
) -> None:
    model = pu.find_model(name)
    path = _as_formulas(model, tmp_path / "formulas.yaml")
    restated = pu.find_model(path)
    assert sum(t.code == "formula" for t in restated.terms) >= 12
    survey = _survey()
    names, ours = pu.term_covariances(survey, restated, site)
    ref_names, ref = pu.term_covariances(survey, model, site)
    assert names == ref_names
    scale = np.abs(ref).max(axis=(1, 2, 3))[:, None, None, None] + 1e-300
    np.testing.assert_allclose(ours / scale, ref / scale, rtol=0, atol=1e-12)


# ---------------------------------------------------------------- located errors

GOOD = """\
format: gyropipe-tool-model/1
name: VENDOR-1
extends: GYRO-NS
terms:
  - name: EXTRA
    acts_on: [azi]
    mode: systematic
    magnitude: 0.1
    unit: deg
    weight: {azi: "cos(inc)"}
"""


def _error(tmp_path: Path, text: str) -> str:
    path = tmp_path / "vendor.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(ToolModelError) as info:
        pu.find_model(path)
    return str(info.value)


@pytest.mark.parametrize(
    ("old", "new", "where", "message"),
    [
        (
            'weight: {azi: "cos(inc)"}',
            "weight: ABZZ",
            ":10:13",
            "unknown weighting function 'ABZZ'; did you mean 'ABZ'",
        ),
        ("unit: deg", "unit: furlong", ":9:11", "unknown unit 'furlong'"),
        (
            'weight: {azi: "cos(inc)"}',
            "weight: ABZ",
            ":6:14",
            "ABZ acts on ['azi', 'inc'], not ['azi']",
        ),
        ("mode: systematic", "mode: sometimes", ":7:11", "mode: Input should be 'random'"),
        ("cos(inc)", "cos(inc", ":10:", "azi: not a formula"),
        ("cos(inc)", "cos(inclination)", ":10:", "unknown name(s) ['inclination']"),
        ("cos(inc)", "inc.real", ":10:", "Attribute not allowed"),
        ("cos(inc)", "open(1)", ":10:", "unknown function 'open'"),
        ("extends: GYRO-NS", "extends: GYRO-XX", ":3:10", "unknown tool model 'GYRO-XX'"),
        ("name: EXTRA", "name: GXY-RN", ":5:5", "duplicate term 'GXY-RN'"),
        ("magnitude: 0.1", "magnitude: -0.1", ":8:16", "greater than or equal to 0"),
        ("format: gyropipe-tool-model/1", "format: 2", ":1:9", "format: Input should be"),
        ("    unit: deg\n", "    unit: deg\n    colour: red\n", ":10:5", "unknown field"),
        ("terms:", "remove: [XCLB]\nterms:", ":4:10", "no term 'XCLB' to remove"),
        ("terms:", "magnitudes: {GXY-R: 1}\nterms:", ":4:14", "no term 'GXY-R' to set"),
        ("terms:", "terms: [\n", ":", "malformed YAML"),
    ],
)
def test_problems_are_located(tmp_path: Path, old: str, new: str, where: str, message: str) -> None:
    assert old in GOOD
    text = _error(tmp_path, GOOD.replace(old, new, 1))
    assert f"vendor.yaml{where}" in text and message in text, text


def test_unit_of_the_wrong_dimension_and_missing_parameters(tmp_path: Path) -> None:
    text = _error(
        tmp_path,
        """\
        format: gyropipe-tool-model/1
        name: BAD
        terms:
          - {name: ABZ, acts_on: [inc, azi], mode: systematic, magnitude: 1, unit: deg, weight: ABZ}
          - {name: XCLA, acts_on: [nev], mode: random, magnitude: 0.167, unit: "-", weight: XCLA}
        """,
    )
    assert "vendor.yaml:4:" in text and "ABZ takes a magnitude in m/s2" in text
    assert "vendor.yaml:5:" in text and "needs parameter(s) ['tortuosity']" in text


def test_a_non_finite_weight_names_its_term_and_station(tmp_path: Path) -> None:
    path = tmp_path / "vendor.yaml"
    path.write_text(GOOD.replace('"cos(inc)"', '"1 / (inc - inc)"'))
    model = pu.find_model(path)
    with pytest.raises(
        ToolModelError,
        match=r"vendor\.yaml:5:5: term EXTRA: weight not finite at station 0 \(MD 0 m",
    ):
        pu.covariance(_survey(), model, pu.ModelSite(latitude=LAT))


def test_a_missing_site_quantity_is_named() -> None:
    with pytest.raises(pu.MissingSiteQuantity, match="ISCWSA-MWD-REV4 needs the site's magnetic"):
        pu.covariance(_survey(), "ISCWSA-MWD-REV4", pu.ModelSite(latitude=LAT))


def test_formula_refuses_code() -> None:
    for text in (
        "__import__('os')",
        "(lambda: 1)()",
        "[1][0]",
        "inc if inc else {}",
        "'a'",
        "arctan2(inc)",
        "sin(*inc)",
    ):
        with pytest.raises(FormulaError):
            Formula.parse(text, frozenset({"inc"}))
    f = Formula.parse("where(inc > 0.5, 1, 2) + (3 if inc < 0.2 else 4) - pi", frozenset({"inc"}))
    np.testing.assert_array_equal(
        f.evaluate({"inc": np.array([0.1, 0.3, 0.6])}), np.array([5.0, 6.0, 5.0]) - np.pi
    )


# ---------------------------------------------------------------- a vendor's file in use


def _vendor_file(tmp_path: Path) -> Path:
    path = tmp_path / "vendor.yaml"
    path.write_text(GOOD)
    return path


def test_a_vendor_file_adds_a_term_without_code(tmp_path: Path) -> None:
    """``extends: GYRO-NS`` plus one formula term is GYRO-NS plus that term's covariance
    (the term built by hand as a :class:`~pipeline.uncertainty.Term`)."""
    survey = _survey()
    site = pu.ModelSite(latitude=LAT)
    vendor = pu.covariance(survey, _vendor_file(tmp_path), site)
    base = pu.covariance(survey, "GYRO-NS", site)
    extra = pu.Term(
        "EXTRA",
        "systematic",
        np.radians(0.1),
        lambda s: stack(0.0, 0.0, np.cos(s.inc) * np.sin(s.inc), s.size),
    )
    _, alone = pu.term_covariance(survey, [extra])
    np.testing.assert_allclose(vendor, base + alone[0], rtol=1e-12, atol=1e-12)


def test_the_stage_takes_a_model_file(tmp_path: Path) -> None:
    md = np.arange(0.0, 1501.0, 30.0)
    inc = np.clip((md - 300.0) / 20.0, 0.0, 50.0)
    stations = Stations.compiled().make_table(
        {"md": md, "inc": inc, "azi": np.full(md.size, 45.0)}, north_reference="true"
    )
    trajectory = gp.minimum_curvature(stations, tie_tvd=0.0)
    path = _vendor_file(tmp_path)
    out = gp.position_uncertainty(trajectory, model=str(path), latitude=LAT)
    i, a = np.radians(inc), np.radians(np.full(md.size, 45.0))
    survey = pu.Survey.of(md, i, a, minimum_curvature(md, i, a).tvd)
    expected = pu.covariance(survey, path, pu.ModelSite(latitude=LAT))
    np.testing.assert_allclose(out.column("cov_ee").to_numpy(), expected[:, 1, 1], rtol=1e-12)
    with pytest.raises(ParameterError, match=r"absent\.yaml: no such tool-model file"):
        gp.position_uncertainty(trajectory, model=str(tmp_path / "absent.yaml"))


def test_gyropipe_models_lists_and_checks(tmp_path: Path) -> None:
    listed = gyropipe_cli("models")
    assert listed.returncode == 0, listed.stderr
    lines = listed.stdout.splitlines()
    assert lines[0] == "# ISCWSA MWD and gyro models (models/): 7 models"
    names = [line.split()[0] for line in lines[1:8]]
    assert names == [
        "GYRO-MWD",
        "GYRO-NS",
        "GYRO-NS-CT",
        "GYRO-NS-noXCL",
        "ISCWSA-MWD-REV4",
        "ISCWSA-MWD-REV5",
        "ISCWSA-MWD-REV5.11",
    ]
    bad = tmp_path / "vendor.yaml"
    bad.write_text(GOOD.replace("unit: deg", "unit: furlong"))
    checked = gyropipe_cli("models", str(bad))
    assert checked.returncode == 2
    assert f"{bad}:9:11: unknown unit 'furlong'" in checked.stderr
    assert "Traceback" not in checked.stderr


def test_the_report_names_the_model_and_cites_its_papers(tmp_path: Path) -> None:
    """The report's method statement (the uncertainty stage's report part) gives the model's
    title from its file and cites the published model (SPE 67616; SPE 90408 too for a gyro
    model), never a file path; a model without a title is named (not given the title of the
    model it extends)."""
    citations = Citations()
    for model, title, gyro in (
        ("GYRO-MWD", "OWSG gyro MWD (GYRO-MWD, A019Gb)", True),
        ("iscwsa-mwd-rev4", "ISCWSA MWD (fixed rig), Rev 4", False),
        (str(_vendor_file(tmp_path)), "VENDOR-1", True),
    ):
        stage = StageSetup(
            "u", "position_uncertainty", "builtin", {"model": model, "confidence": 0.95}
        )
        run = Provenance(
            "p", "1", "p.yaml", "0" * 64, "0", {}, {}, dt.datetime.now(dt.UTC), (stage,)
        )
        parts = Parts(
            stages.registry().report_parts(), "survey", {}, WellMetadata(), run, citations
        )
        ((label, text),) = parts.methods()
        assert label == "Position uncertainty"
        assert text.startswith(f"{title} error model propagated as in [1]")
        assert ("with the gyro terms of [2]" in text) is gyro
        assert str(tmp_path) not in text
    assert "SPE 67616" in citations.works[0] and "SPE 90408" in citations.works[1]


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_a_mutated_model_file_is_read_or_refused_with_a_located_error(
    tmp_path: Path, data: st.DataObject
) -> None:
    """Any edit of a valid file (a character dropped, replaced or inserted) either reads or
    is a ToolModelError naming the file; nothing else escapes."""
    text = (pu.MODELS_DIR / "gyro-ns-ct.yaml").read_text()
    at = data.draw(st.integers(0, len(text) - 1))
    edit = data.draw(st.sampled_from(["drop", "replace", "insert"]))
    char = data.draw(st.sampled_from([*":-[]{}#'!&*|> 0aZ.,()/", '"', "\\", "\n", "\t"]))
    mutated = {
        "drop": text[:at] + text[at + 1 :],
        "replace": text[:at] + char + text[at + 1 :],
        "insert": text[:at] + char + text[at:],
    }[edit]
    path = tmp_path / f"m{at}{edit}.yaml"
    path.write_text(mutated)
    try:
        model = pu.find_model(path)
    except ToolModelError as exc:
        problems = exc.problems
    else:
        assert model.terms
        return
    # located in the file, or in the model it extends (an edited `extends:` name)
    assert all(str(p.location).startswith(str(path)) or "GYRO" in p.message for p in problems)


@settings(max_examples=300, deadline=None)
@given(
    text=st.text(
        alphabet=st.sampled_from(list("inc+-*/()%<>=.,0123456789 abcdefghijklmnopqrstuvwxyz_[]'")),
        max_size=40,
    )
)
def test_formula_parse_refuses_or_evaluates(text: str) -> None:
    """Any text parses into a formula that evaluates over the station arrays, or is a
    FormulaError."""
    try:
        f = Formula.parse(text, frozenset({"inc", "azi"}))
    except FormulaError:
        return
    f.evaluate({"inc": np.array([0.0, 0.5]), "azi": np.array([1.0, 2.0])})


def test_a_non_finite_station_is_refused_by_name() -> None:
    s = _survey()
    azi = s.azi.copy()
    azi[3] = np.nan
    with pytest.raises(SurveyValueError, match=r"survey azi is not finite at station\(s\) \[3\]"):
        pu.covariance(pu.Survey.of(s.md, s.inc, azi, s.tvd), "GYRO-NS", pu.ModelSite(latitude=LAT))


def test_a_parameter_may_not_shadow_a_quantity(tmp_path: Path) -> None:
    text = _error(tmp_path, GOOD.replace("terms:", "parameters:\n  md: {value: 1}\nterms:"))
    assert "vendor.yaml:5:3: parameter name 'md' must be an identifier" in text


def test_a_model_extends_a_file_beside_it(tmp_path: Path) -> None:
    """``extends:`` a relative path reads the file next to the extending one, whatever the
    working directory; a cycle of files is refused, located."""
    _vendor_file(tmp_path)
    (tmp_path / "sub").mkdir()
    child = tmp_path / "sub" / "child.yaml"
    child.write_text(
        "format: gyropipe-tool-model/1\nname: CHILD\nextends: ../vendor.yaml\n"
        "magnitudes: {EXTRA: 0.2}\n"
    )
    model = pu.find_model(child)
    assert model.term("EXTRA").magnitude == 0.2 and model.term("GXY-RN").magnitude == 0.4
    loop = tmp_path / "loop.yaml"
    loop.write_text("format: gyropipe-tool-model/1\nname: LOOP\nextends: loop.yaml\n")
    with pytest.raises(ToolModelError, match=r"loop\.yaml:3:10: .*extends itself"):
        pu.find_model(loop)

"""The definitive survey: which run each depth comes from (priorities, overlap rules, depth
ranges, ties, gaps) and the covariance of one run equal to the position-uncertainty
stage's. The ties, positions and covariance of the shipped example and of three runs:
tests/survey/test_definitive_ties.py; the covariance across sections against a Monte
Carlo: tests/uncertainty/test_definitive_covariance.py."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import pyarrow as pa
import pytest

import pipeline as gp
from pipeline.earth.site import MagneticReference
from pipeline.errors import SurveyCheckWarning
from pipeline.sim.plan import Section, WellPlan, build_path
from pipeline.survey.definitive import RunStations, SurveyGapError, plan_sections, roles
from pipeline.uncertainty import ModelSite, Survey, find_model, model_terms
from pipeline.uncertainty.model import propagate_nev
from pipeline.uncertainty.terms import term_covariance, term_effects
from tests_support import ROOT, gyropipe_cli

GYRO = np.arange(0.0, 601.0, 30.0)  # 0 … 600
MWD = np.arange(570.0, 1200.0, 45.0)  # 570, 615, … 1155
FIELD = {"total_field": 59731.0, "dip": 78.29, "declination": 17.0}
EXAMPLES = ROOT / "examples" / "definitive"


def _runs(**kw: Any) -> list[RunStations]:
    a = {k[2:]: v for k, v in kw.items() if k.startswith("a_")}
    b = {k[2:]: v for k, v in kw.items() if k.startswith("b_")}
    return [RunStations("A", GYRO, **a), RunStations("B", MWD, **b)]


def _listed(runs: list[RunStations], sections: list[Any]) -> list[tuple[str, float]]:
    return [(runs[s.run].name, float(runs[s.run].md[i])) for s in sections for i in s.listed]


def test_priority_keeps_the_higher_run_and_ties_the_other_below_it() -> None:
    runs = _runs(a_priority=1)
    sections = plan_sections(runs)
    listed = _listed(runs, sections)
    assert [md for _, md in listed] == sorted(md for _, md in listed)  # one MD order
    assert [md for name, md in listed if name == "A"] == GYRO.tolist()
    assert [md for name, md in listed if name == "B"] == MWD[MWD > 600].tolist()
    # the MWD is tied at the gyro's last listed station (600 m), not at its own 570 m
    # station placed on the gyro's path; that one is an overlap station
    assert sections[1].tie_md == 600.0
    assert roles(runs, sections)[1][:1] == ["overlap"]


@pytest.mark.parametrize(
    ("kw", "switch"),
    [
        ({"a_priority": 0, "b_priority": 1}, 570.0),  # the MWD wins its whole range
        ({"rule": "lower"}, 570.0),  # the run starting deeper takes over at its start
        ({"rule": "upper", "b_priority": 5}, 600.0),  # the run above keeps its range
        ({"a_md_to": 580.0, "a_priority": 1}, 580.0),  # the gyro's range ends at 580 m
    ],
)
def test_overlap_rules_and_depth_ranges(kw: dict[str, Any], switch: float) -> None:
    rule = kw.pop("rule", "priority")
    runs = _runs(**kw)
    sections = plan_sections(runs, rule)
    listed = _listed(runs, sections)
    assert max(md for name, md in listed if name == "A") <= switch
    assert min(md for name, md in listed if name == "B") >= switch
    assert [md for _, md in listed] == sorted({md for _, md in listed})


def test_a_gap_between_runs_is_an_error_naming_them() -> None:
    with pytest.raises(SurveyGapError, match=r"no run covers 450 – 570 m MD.*A.*B"):
        plan_sections(_runs(a_md_to=450.0))


def test_a_run_inside_another_resumes_the_outer_run_tied_below_it() -> None:
    outer = RunStations("outer", np.arange(0.0, 1201.0, 30.0))
    inner = RunStations("inner", np.arange(400.0, 701.0, 20.0), priority=1)
    sections = plan_sections([outer, inner])
    assert [s.run for s in sections] == [0, 1, 0]
    assert sections[1].tie_md == 390.0 and sections[2].tie_md == 700.0  # last listed above


def test_slivers_stay_with_the_neighbour() -> None:
    """An out-run starting 2 mm above the in-run and ending 1 cm below it adds no section."""
    inrun = RunStations("in", np.arange(0.0, 901.0, 60.0), priority=1)
    outrun = RunStations("out", np.arange(0.0, 901.0, 60.0) + np.r_[-0.002, np.zeros(14), 0.01])
    assert [s.run for s in plan_sections([inrun, outrun])] == [0]
    assert [s.run for s in plan_sections([inrun, outrun], min_length=0.0)] == [1, 0, 1]


@pytest.mark.parametrize("model", ["GYRO-NS", "ISCWSA-MWD-REV5"])
def test_term_effects_are_what_term_covariance_propagates(model: str) -> None:
    md = np.arange(0.0, 901.0, 30.0)
    inc = np.radians(np.clip((md - 200) / 10, 0, 50))
    azi = np.radians(40 + md / 50)
    survey = Survey.of(md, inc, azi, md * np.cos(inc))
    tool = find_model(model)
    site = ModelSite(latitude=61.25, magnetic=MagneticReference(**FIELD))
    terms = model_terms(tool, site)
    full, star = term_effects(survey, terms, basis="balanced_tangent", surface_tie=True)
    cov = propagate_nev(full, star, [t.mode for t in terms])
    np.testing.assert_allclose(cov, term_covariance(survey, terms)[1], rtol=0, atol=1e-12)


def _stations(md: np.ndarray) -> pa.Table:
    plan = WellPlan(
        sections=[
            Section(kind="vertical", length=200),
            Section(kind="build", dls=3.0, inc=40, azi=75),
            Section(kind="hold", to_md=1300),
        ]
    )
    return build_path(plan).stations(md)


@pytest.mark.parametrize(
    "model", ["GYRO-NS", "GYRO-NS-CT", "GYRO-MWD", "ISCWSA-MWD-REV4", "ISCWSA-MWD-REV5"]
)
def test_one_run_is_the_position_uncertainty_of_its_survey(model: str) -> None:
    """With one run there is nothing to carry: the stage's covariance is the
    position-uncertainty stage's (term_covariance summed), surface tie-on included, for
    every tool model file."""
    stations = _stations(GYRO)
    needs = find_model(model).needs
    params: dict[str, Any] = {
        **({"magnetic": FIELD} if "magnetic" in needs else {}),
        **({"latitude": 61.25} if "latitude" in needs else {}),
    }
    survey = gp.definitive_survey(
        {"run": stations}, run_options={"run": {"model": model}}, **params
    ).survey
    single = gp.position_uncertainty(gp.minimum_curvature(stations), model=model, **params)
    assert isinstance(survey, pa.Table) and isinstance(single, pa.Table)
    for name in (
        "north",
        "east",
        "tvd",
        "dls",
        "cov_nn",
        "cov_ne",
        "cov_ev",
        "cov_vv",
        "ellipse_major",
    ):
        np.testing.assert_allclose(
            survey.column(name).to_numpy(), single.column(name).to_numpy(), rtol=1e-12, atol=1e-12
        )
    assert set(survey.column("run").to_pylist()) == {"run"}
    assert set(survey.column("tool_model").to_pylist()) == {model}


def test_a_gap_fails_the_run_naming_the_runs(tmp_path: Any) -> None:
    with pytest.raises(
        gp.GyropipeError,
        match=r"no run covers .* m MD \(runs ending above: GYRO-1; starting below: MWD-1\)",
    ):
        gp.run(
            ROOT / "pipelines" / "definitive.yaml",
            {"gyro": EXAMPLES / "gyro-run.csv", "mwd": EXAMPLES / "mwd-run.csv"},
            set={
                "definitive.runs": {
                    "run1": {"name": "GYRO-1", "md_to": 500.0, "priority": 1},
                    "run2": {"name": "MWD-1", "model": "ISCWSA-MWD-REV5"},
                }
            },
        )
    with pytest.raises(gp.GyropipeError, match=r"unknown (tool )?model.*'GYRO-XX'"):
        gp.definitive_survey(
            {"a": _stations(GYRO)}, run_options={"a": {"model": "GYRO-XX"}}, latitude=61.0
        )


def test_a_short_stretch_left_out_at_the_bottom_is_warned_of(tmp_path: Any) -> None:
    """The out-run's deepest station 0.4 m below the in-run's (shorter than min_length, 1 m):
    the definitive survey ends at the in-run's 900 m — and says which station it left out,
    where and how long a stretch; min_length 0 lists it. On the command line: a warning."""
    md = np.arange(0.0, 901.0, 60.0)
    inrun, outrun = _stations(md), _stations(np.r_[md[:-1], 900.4])
    options = {"in": {"priority": 1}}
    with pytest.warns(SurveyCheckWarning) as caught:
        survey = gp.definitive_survey(
            {"in": inrun, "out": outrun}, run_options=options, latitude=61.0
        )["survey"]
    assert survey["md"].to_numpy().max() == 900.0
    (text,) = [str(w.message) for w in caught if w.category is SurveyCheckWarning]
    assert "run 'out'" in text and "900.40 m MD" in text and "0.40 m below" in text
    assert "min_length" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurveyCheckWarning)
        kept = gp.definitive_survey(
            {"in": inrun, "out": outrun}, run_options=options, latitude=61.0, min_length=0.0
        )["survey"]
    assert kept["md"].to_numpy().max() == pytest.approx(900.4)

    for name, run in (("in", inrun), ("out", outrun)):
        frame = run.select(["md", "inc", "azi"]).to_pandas()
        frame.columns = ["MD (m)", "Inc (deg)", "Azimuth True (deg)"]
        frame.to_csv(tmp_path / f"{name}.csv", index=False)
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "inout-gyro.yaml", "--input", f"inrun={tmp_path / 'in.csv'}",
        "--input", f"outrun={tmp_path / 'out.csv'}", "--out", tmp_path / "o",
        "--well", "latitude=61", "--set", "report.formats=[html]",
    )  # fmt: skip
    assert "warning:" in result.stderr and "900.40 m MD" in result.stderr, result.output

"""A station listing's position uncertainty is carried through the survey pipeline or said
not to be: ``pipelines/survey.yaml`` on a point-gyro run's uncertainty trajectory (Parquet)
or its WITSML export states the file's covariances, error model, confidence and tie-on in
every deliverable; a file with part of a family of columns, or values no covariance holds,
is warned of by file and column; the tie-on statement survives a CSV and a WITSML round
trip; a north conversion turns the covariances with the azimuths. Expected values: the
input files' own bytes (read with pyarrow, csv, lasio, re), or the listings written here."""

from __future__ import annotations

import csv
import json
import re
import warnings
from pathlib import Path

import lasio
import numpy as np
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning, SurveyCheckWarning
from tests_support import (
    ROOT,
    gyropipe_cli,
    point_gyro_run,
    stage,
    without_report,
    write_pipeline,
)

SURVEY = ROOT / "pipelines" / "survey.yaml"
COV = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
TIE_KEY = b"gyropipe.uncertainty_tie_on"
NOT_INCLUDED = {
    "survey": None,
    "md": 500.0,
    "basis": "not included",
    "parent": None,
    "semi_major": None,
}
LISTING = """\
# confidence=0.95
# error_model=TEST-GYRO rev 2
# tie_on={{"surveys":[{tie}]}}
md[m],inc[deg],azi[deg],{cov},Station Type
500,10,30,0.01,0.001,0.0005,0.02,0.0002,0.004,Tie-In
600,12,32,0.04,0.004,0.002,0.08,0.0008,0.016,
700,14,34,0.09,0.009,0.0045,0.18,0.0018,0.036,
800,16,36,0.16,0.016,0.008,0.32,0.0032,0.064,Projection to TD
"""
"""A listing of a survey tied on at 500 m MD whose tie-on uncertainty is not included; its
last row a projection (no station: left out, with its covariance)."""


def listing(tmp_path: Path, tie: dict[str, object] = NOT_INCLUDED) -> Path:
    path = tmp_path / "listing.csv"
    path.write_text(LISTING.format(tie=json.dumps(tie), cov=",".join(f"{c}[m2]" for c in COV)))
    return path


@pytest.fixture(scope="module")
def point_gyro(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return point_gyro_run(tmp_path_factory.mktemp("carried"))


@pytest.fixture(scope="module")
def survey_of_parquet(point_gyro: Path) -> Path:
    out = point_gyro.parent / "survey"
    given = point_gyro / "uncertainty.trajectory.parquet"
    gyropipe_cli("run", SURVEY, "--input", given, "--out", out, check=True)
    return out


def summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text()).get("uncertainty")


def csv_comments(path: Path) -> dict[str, str]:
    lines = [ln for ln in path.read_text().splitlines() if ln.startswith("# ")]
    return dict(ln[2:].split("=", 1) for ln in lines if "=" in ln)


def csv_column(path: Path, name: str) -> np.ndarray:
    rows = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    reader = csv.DictReader(rows)
    return np.array([float(r[next(k for k in r if k.startswith(name + "["))]) for r in reader])


def test_survey_of_an_uncertainty_trajectory_states_its_uncertainty(
    point_gyro: Path, survey_of_parquet: Path
) -> None:
    given = pq.read_table(point_gyro / "uncertainty.trajectory.parquet")
    out = survey_of_parquet
    got = pq.read_table(out / "trajectory.trajectory.parquet")
    np.testing.assert_array_equal(got.column("md").to_numpy(), given.column("md").to_numpy())
    for name in (*COV, "ellipse_major_conf", "vertical_conf"):
        np.testing.assert_allclose(
            got.column(name).to_numpy(), given.column(name).to_numpy(), rtol=0, atol=1e-9
        )
    model = given.schema.field("cov_nn").metadata[b"gyropipe.error_model"].decode()
    stated = summary(out)
    assert (stated["error_model"], stated["confidence"]) == (model, 0.95)
    assert stated["tie_on"] == json.loads(given.schema.metadata[TIE_KEY])["surveys"]
    assert stated["at_td"]["semi_major"] == pytest.approx(
        given.column("ellipse_major")[-1].as_py(), abs=1e-9
    )
    assert stated["from_stations_file"] is True
    comments = csv_comments(out / "trajectory.csv")
    assert (comments["error_model"], comments["confidence"]) == (model, "0.95")
    assert json.loads(comments["tie_on"])["surveys"] == stated["tie_on"]
    np.testing.assert_allclose(
        csv_column(out / "trajectory.csv", "cov_ee"), given.column("cov_ee").to_numpy(), atol=1e-8
    )
    las = lasio.read(out / "trajectory.las", mnemonic_case="preserve")
    assert las.params["ERRMODEL"].value == model
    np.testing.assert_allclose(las["cov_vv"], given.column("cov_vv").to_numpy(), atol=1e-8)
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "Error ellipses at 95 %" in report
    assert "The position uncertainty is the one the stations file states" in report


def test_survey_of_a_witsml_export_keeps_its_matrix_cov(point_gyro: Path, tmp_path: Path) -> None:
    given = point_gyro / "trajectory.xml"
    survey = without_report("survey", tmp_path)
    gyropipe_cli("run", survey, "--input", given, "--out", tmp_path / "out", check=True)
    text = given.read_text()
    for name, element in (("cov_nn", "varianceNN"), ("cov_ev", "varianceEVert")):
        listed = [float(v) for v in re.findall(rf'<{element} uom="m2">([^<]+)<', text)]
        got = pq.read_table(tmp_path / "out" / "trajectory.trajectory.parquet").column(name)
        np.testing.assert_allclose(got.to_numpy(), listed, rtol=0, atol=1e-9)
    stated = summary(tmp_path / "out")
    assert [f["family"] for f in stated["columns"]] == ["covariance"]
    assert (
        stated["error_model"]
        == re.search(r"<name>gyropipe.error_model</name>\s*<value>([^<]+)<", text)[1]
    )
    written = json.loads(
        pq.read_table(point_gyro / "uncertainty.trajectory.parquet").schema.metadata[TIE_KEY]
    )["surveys"]
    assert stated["tie_on"] == written


def test_csv_las_and_witsml_round_trips_keep_the_tie_on_statement(tmp_path: Path) -> None:
    with pytest.warns(InputFileWarning, match="Projection to TD"):
        gp.run(SURVEY, listing(tmp_path), out=tmp_path / "out")
    out = tmp_path / "out"
    assert summary(out)["tie_on"] == [NOT_INCLUDED]
    assert json.loads(csv_comments(out / "trajectory.csv")["tie_on"]) == {"surveys": [NOT_INCLUDED]}
    assert las_tie_items(out / "trajectory.las") == {"TIEMD1": 500.0, "TIEBASIS1": "not included"}
    for name in ("trajectory.csv", "trajectory.xml", "trajectory.las"):
        assert gp.read(out / name).attrs["uncertainty"]["tie_on"] == [NOT_INCLUDED], name
    # the projection at 800 m is left out with its covariance; the others follow their rows
    np.testing.assert_allclose(
        gp.read(out / "trajectory.xml")["cov_ee"], [0.02, 0.08, 0.18], rtol=0, atol=1e-9
    )
    las = lasio.read(out / "trajectory.las", mnemonic_case="preserve")
    assert "500.00 m MD, its own uncertainty not included" in las.curves["cov_nn"].descr
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "the uncertainty of the tie-on position (of the hole above it) is not included" in (
        report
    )


def las_tie_items(path: Path) -> dict[str, object]:
    """The TIE… ~Parameter items of a LAS file, as lasio reads them."""
    las = lasio.read(path, mnemonic_case="preserve")
    return {i.mnemonic: i.value for i in las.params if i.mnemonic.startswith("TIE")}


GIVEN = {"survey": None, "md": 500.0, "basis": "given", "parent": None, "semi_major": 0.15}


def test_a_survey_of_a_las_export_carries_its_tie_on(tmp_path: Path) -> None:
    with pytest.warns(InputFileWarning, match="Projection to TD"):
        gp.run(SURVEY, listing(tmp_path, GIVEN), out=tmp_path / "first")
    las = tmp_path / "first" / "trajectory.las"
    assert las_tie_items(las) == {"TIEMD1": 500.0, "TIEBASIS1": "given", "TIESEMI1": 0.15}
    gp.run(SURVEY, las, out=tmp_path / "again")
    stated = summary(tmp_path / "again")
    assert stated["tie_on"] == [GIVEN] and stated["from_stations_file"] is True
    again = pq.read_table(tmp_path / "again" / "trajectory.trajectory.parquet")
    assert json.loads(again.schema.metadata[TIE_KEY]) == {"surveys": [GIVEN]}
    np.testing.assert_allclose(again.column("cov_ee").to_numpy(), [0.02, 0.08, 0.18], atol=1e-9)


def test_a_las_without_tie_on_items_reads_as_before(tmp_path: Path) -> None:
    with pytest.warns(InputFileWarning, match="Projection to TD"):
        gp.run(SURVEY, listing(tmp_path), out=tmp_path / "out")
    las = tmp_path / "out" / "trajectory.las"
    lines = las.read_text().splitlines(keepends=True)
    las.write_text("".join(ln for ln in lines if not ln.startswith(" TIE")))
    frame = gp.read(las)
    assert frame.attrs["uncertainty"]["tie_on"] == []
    assert frame.attrs["uncertainty"]["error_model"] == "TEST-GYRO rev 2"
    np.testing.assert_allclose(frame["cov_ee"], [0.02, 0.08, 0.18], rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    ("old", "new", "at", "said"),
    [
        (" not included ", " somewhere    ", "TIEBASIS1", "TIEBASIS1 'somewhere': Input should be"),
        ("TIEMD1  .m ", "TIEMD1  .ft", "TIEMD1", "TIEMD1 in 'ft': expected m"),
        (" TIEMD1  .m ", " TIEMD2  .m ", "TIEBASIS1", "TIEMD1 missing: the tie-on of each"),
    ],
)
def test_a_las_tie_on_item_not_as_written_is_refused_at_its_line(
    tmp_path: Path, old: str, new: str, at: str, said: str
) -> None:
    with pytest.warns(InputFileWarning, match="Projection to TD"):
        gp.run(SURVEY, listing(tmp_path), out=tmp_path / "out")
    las = tmp_path / "out" / "trajectory.las"
    text = las.read_text()
    assert old in text
    las.write_text(text.replace(old, new, 1))
    lines = las.read_text().splitlines()
    line = next(i for i, ln in enumerate(lines, 1) if re.match(rf"\s*{at}\s*\.", ln))
    with pytest.raises(InputFileError) as err:
        gp.read(las, kind="stations")
    assert f"trajectory.las:{line}: {said}" in str(err.value)


@pytest.mark.parametrize(
    ("old", "new", "said"),
    [
        (",cov_nv[m2]", "", r"columns cov_nn, cov_ne, cov_ee, cov_ev, cov_vv: without cov_nv"),
        ("600,12,32,0.04,", "600,12,32,-0.04,", r"cov_nn at MD 600.00 m holds -0.04"),
    ],
)
def test_a_listing_whose_covariances_cannot_be_carried_is_warned_of(
    tmp_path: Path, old: str, new: str, said: str
) -> None:
    path = listing(tmp_path)
    text = path.read_text().replace(old, new)
    if not new:  # the column's cells too
        text = re.sub(r"^(\d+,\d+,\d+,[^,]+,[^,]+),[^,]+", r"\1", text, flags=re.M)
    path.write_text(text)
    with pytest.warns(InputFileWarning) as caught:
        gp.run(SURVEY, path, out=tmp_path / "out")
    refused = [str(w.message) for w in caught if "not carried" in str(w.message)]
    assert len(refused) == 1 and str(path) in refused[0], refused
    assert re.search(said, refused[0]), refused[0]
    assert summary(tmp_path / "out") is None
    assert not [c for c in COV if c in gp.read(tmp_path / "out" / "trajectory.csv").columns]


def test_a_listing_without_uncertainty_states_none(tmp_path: Path) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gp.run(SURVEY, ROOT / "examples" / "stations-j-well.csv", out=tmp_path)
    assert not [w for w in caught if "uncertainty" in str(w.message)]
    assert summary(tmp_path) is None
    assert "tie_on" not in csv_comments(tmp_path / "trajectory.csv")
    assert "uncertainty_tie_on" not in (tmp_path / "trajectory.xml").read_text()
    assert "Position uncertainty" not in (tmp_path / "report.html").read_text(encoding="utf-8")


def test_positions_unlike_the_listed_ones_warn_that_the_covariances_are_theirs(
    tmp_path: Path,
) -> None:
    path = tmp_path / "listing.csv"
    path.write_text(
        "# error_model=TEST-GYRO rev 2\n"
        f"md[m],inc[deg],azi[deg],tvd[m],north[m],east[m],{','.join(f'{c}[m2]' for c in COV)}\n"
        "0,0,0,0,0,0,0,0,0,0,0,0\n"
        "100,5,30,99.9,3.8,2.2,0.01,0.001,0.0005,0.02,0.0002,0.004\n"
        "200,10,30,198,20,8,0.04,0.004,0.002,0.08,0.0008,0.016\n"  # 5 m off: another path's
    )
    with pytest.warns(SurveyCheckWarning, match="computed for its own positions, not for these"):
        result = gp.run(SURVEY, path)
    assert result.tables["trajectory.trajectory"].column("cov_nn").to_pylist() == [0, 0.01, 0.04]


def test_a_north_conversion_turns_the_covariances(tmp_path: Path) -> None:
    spec = write_pipeline(
        tmp_path,
        [
            stage("read", "read_stations"),
            stage(
                "grid",
                "north_reference",
                {"stations": "read.stations"},
                target="grid",
                convergence=30.0,
            ),
            stage("trajectory", "minimum_curvature", {"stations": "grid.stations"}),
        ],
    )
    path = listing(tmp_path)
    with pytest.warns(InputFileWarning, match="Projection to TD"):
        got = gp.run(spec, path).tables["trajectory.trajectory"]
    delta = np.radians(-30.0)  # grid azimuth = true azimuth − convergence
    turn = np.array(
        [[np.cos(delta), -np.sin(delta), 0], [np.sin(delta), np.cos(delta), 0], [0, 0, 1]]
    )
    # the second station's covariance, as the listing writes it
    c = np.array([[0.04, 0.004, 0.002], [0.004, 0.08, 0.0008], [0.002, 0.0008, 0.016]])
    want = turn @ c @ turn.T
    row = [got.column(n)[1].as_py() for n in COV]
    np.testing.assert_allclose(
        row, [want[0, 0], want[0, 1], want[0, 2], want[1, 1], want[1, 2], want[2, 2]], atol=1e-15
    )


def test_a_malformed_tie_on_line_is_refused_at_its_line(tmp_path: Path) -> None:
    path = listing(tmp_path, {"md": 500.0, "basis": "somewhere"})
    with pytest.raises(InputFileError, match=r"listing.csv:3: tie_on surveys.0.basis") as err:
        gp.read(path)
    assert "expected the tie-on as gyropipe writes it" in str(err.value)

"""What a deliverable says of its uncertainty, summed up: summary.json's ``uncertainty``
object, a DataFrame's ``attrs["uncertainty"]`` and the report's uncertainty section state the
error model, the confidence, the σ convention of each column family and the largest
horizontal semi-major axis and TD's, as the run's LAS file states them (its text, read with
lasio); a trajectory without uncertainty columns states none. A frame written again keeps
CONF and ERRMODEL."""

from __future__ import annotations

import json
import re
from pathlib import Path

import lasio
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from tests_support import ROOT, gyropipe_cli, point_gyro_run

MODEL = "GYRO-NS rev 5 (2020-10-08)"
"""The bundled GYRO-NS model file's name and revision (gyro-ns.yaml), as stated."""
LAS_STEP = 0.5e-4
"""m: half the step of the LAS file's lengths (4 decimals)."""
FAMILIES = [
    {
        "family": "covariance",
        "columns": ["cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv"],
        "scale": "1 sigma squared",
        "region": None,
    },
    {
        "family": "ellipse",
        "columns": ["ellipse_major", "ellipse_minor", "ellipse_azimuth", "sigma_v"],
        "scale": "1 sigma",
        "region": None,
    },
    {
        "family": "ellipse_conf",
        "columns": ["ellipse_major_conf", "ellipse_minor_conf"],
        "scale": "confidence",
        "region": "2-D, chi-square of 2 dof",
    },
    {
        "family": "vertical_conf",
        "columns": ["vertical_conf"],
        "scale": "confidence",
        "region": "1-D, two-sided normal",
    },
]


@pytest.fixture(scope="module")
def out(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A point-gyro run of the short well, report included."""
    return point_gyro_run(tmp_path_factory.mktemp("stated"))


def las_facts(path: Path) -> dict:
    """The facts as the LAS file's text states them: CONF, ERRMODEL, and the stations of
    the largest semi-major axis and of the largest MD."""
    las = lasio.read(path, mnemonic_case="preserve")
    md, major = las["md"], las["ellipse_major"]
    largest, deepest = int(np.argmax(major)), int(np.argmax(md))
    return {
        "confidence": las.params["CONF"].value,
        "error_model": las.params["ERRMODEL"].value,
        "largest": (md[largest], major[largest], las["ellipse_major_conf"][largest]),
        "at_td": (md[deepest], major[deepest], las["ellipse_major_conf"][deepest]),
    }


def assert_statement(stated: dict, facts: dict) -> None:
    assert stated["error_model"] == facts["error_model"] == MODEL
    assert stated["confidence"] == facts["confidence"] == 0.95
    assert stated["columns"] == FAMILIES
    for key in ("largest", "at_td"):
        md, major, conf = facts[key]
        assert stated[key]["survey"] is None
        assert stated[key]["md"] == pytest.approx(md, abs=LAS_STEP)
        assert stated[key]["semi_major"] == pytest.approx(major, abs=LAS_STEP)
        assert stated[key]["semi_major_conf"] == pytest.approx(conf, abs=LAS_STEP)
    assert stated["stations_without_sigma"] == 0


def test_summary_states_the_uncertainty_as_the_las_does(out: Path) -> None:
    facts = las_facts(out / "trajectory.las")
    doc = json.loads((out / "summary.json").read_text())
    assert_statement(doc["uncertainty"], facts)
    # the first stop reads an MD of millimetres (odometer noise): at the depth reference
    (tie,) = doc["uncertainty"]["tie_on"]
    assert tie["basis"] == "wellhead" and abs(tie["md"]) < 0.5
    # the ellipse at TD keeps the stated confidence, not one recomputed from rounded axes
    assert doc["surveys"][0]["uncertainty_at_td"]["confidence"] == 0.95


def test_frames_state_it_and_give_it_back_to_a_file(out: Path, tmp_path: Path) -> None:
    facts = las_facts(out / "trajectory.las")
    frame = gp.read(out / "uncertainty.trajectory.parquet")
    assert_statement(frame.attrs["uncertainty"], facts)
    gp.write(frame, tmp_path / "again.las")  # a frame written again: the columns state it
    las = lasio.read(tmp_path / "again.las")
    assert (las.params["CONF"].value, las.params["ERRMODEL"].value) == (0.95, MODEL)
    comments = (gp.write(frame, tmp_path / "again.csv")).read_text().splitlines()
    assert {"# confidence=0.95", f"# error_model={MODEL}"} <= set(comments)


def test_report_states_model_conventions_and_largest_ellipse(out: Path) -> None:
    facts = las_facts(out / "trajectory.las")
    text = re.sub(r"<[^>]+>", "", (out / "report.html").read_text())
    md, major, conf = facts["largest"]
    assert (
        f"Error model {MODEL}. Covariances are 1σ² (m²), semi-axes and vertical σ at 1σ, "
        "the charted and listed sizes at 95 % confidence" in text
    )
    assert (
        f"Largest horizontal semi-major axis: {conf:.2f} m at 95 % confidence, {major:.2f} m "
        f"at 1σ, at {md:.2f} m MD" in text
    )


def test_a_trajectory_without_uncertainty_states_none(tmp_path: Path) -> None:
    gyropipe_cli(
        "run", ROOT / "pipelines" / "survey.yaml",
        "--input", ROOT / "examples" / "stations-j-well.csv", "--out", tmp_path,
        check=True,
    )  # fmt: skip
    doc = json.loads((tmp_path / "summary.json").read_text())
    assert "uncertainty" not in doc
    assert doc["surveys"][0]["uncertainty_at_td"] is None
    assert "uncertainty" not in gp.read(tmp_path / "trajectory.trajectory.parquet").attrs


def test_stations_without_sigma_are_counted_not_written_as_nan(out: Path, tmp_path: Path) -> None:
    """Stations outside the error model's range (``outside_validity: flag``: NaN from the
    first on) at the bottom: the summary was refused (NaN is no JSON); now null at TD, the
    largest semi-major axis among the stations with a σ, and the count."""
    facts = las_facts(out / "trajectory.las")
    table = pq.read_table(out / "uncertainty.trajectory.parquet")
    for name in ("cov_nn", "cov_ne", "cov_ee", "ellipse_major", "ellipse_major_conf", "sigma_v"):
        i = table.schema.get_field_index(name)
        values = table.column(name).to_numpy().copy()
        values[-3:] = np.nan
        table = table.set_column(i, table.schema.field(i), pa.array(values))
    doc = json.loads(gp.write(table, tmp_path / "summary.json").read_text())
    stated = doc["uncertainty"]
    assert stated["stations_without_sigma"] == 3
    assert (stated["at_td"]["semi_major"], stated["at_td"]["semi_major_conf"]) == (None, None)
    assert stated["at_td"]["md"] == pytest.approx(facts["at_td"][0], abs=LAS_STEP)
    las = lasio.read(out / "trajectory.las", mnemonic_case="preserve")
    assert stated["largest"]["semi_major"] == pytest.approx(
        max(las["ellipse_major"][:-3]), abs=LAS_STEP
    )
    assert doc["surveys"][0]["uncertainty_at_td"]["semi_major"] is None

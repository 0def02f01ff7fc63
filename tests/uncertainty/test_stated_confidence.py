"""Every exported uncertainty column states its confidence and its error model: a point-gyro
run of a short simulated well, at the bundled pipeline's confidence and at 0.99, each
deliverable (LAS, CSV, WITSML, Parquet, MCAP) read back."""

from __future__ import annotations

from pathlib import Path

import lasio
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml
from komle.bindings.v1411.write import witsml as wml
from mcap.reader import make_reader

import pipeline as gp
from pipeline.contracts import DESCRIPTION_KEY
from pipeline.uncertainty.stated import CONFIDENCE_KEY, DIMENSIONS_KEY, ERROR_MODEL_KEY
from tests_support import ROOT, gyropipe_cli

PLAN = ROOT / "examples" / "plans" / "short-j-well.yaml"
PIPELINE = ROOT / "pipelines" / "point-gyro.yaml"
MODEL = "GYRO-NS rev 5 (2020-10-08)"
"""The bundled GYRO-NS model file's name and revision (gyro-ns.yaml), as stated."""
CONF_COLUMNS = {"ellipse_major_conf": b"2", "ellipse_minor_conf": b"2", "vertical_conf": b"1"}


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("sim")
    gyropipe_cli("simulate", PLAN, "--out", out, check=True)
    return out / "samples.parquet"


def run(samples: Path, out: Path, confidence: float | None) -> Path:
    """point-gyro (without its report) with the CSV of the uncertainty trajectory, at
    ``confidence`` (None: the pipeline's own)."""
    spec = yaml.safe_load(PIPELINE.read_text())
    spec["stages"] = [st for st in spec["stages"] if st["id"] != "report"]
    for stage in spec["stages"]:
        if stage["id"] == "uncertainty" and confidence is not None:
            stage["with"]["confidence"] = confidence
        if stage["id"] == "export_csv":
            stage["inputs"]["table"] = "uncertainty.trajectory"
    path = out / "pipeline.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    gyropipe_cli("run", path, "--input", f"samples={samples}", "--out", out / "d", check=True)
    return out / "d"


def mcap_trajectory_schema(path: Path) -> pa.Schema:
    with path.open("rb") as f:
        reader = make_reader(f)
        for schema, _, message in reader.iter_messages(topics=["/gyropipe/trajectory"]):
            assert schema is not None
            return pa.ipc.open_stream(schema.data + message.data).schema
    raise AssertionError("no trajectory topic")


def assert_fields_state(schema: pa.Schema, confidence: str) -> None:
    for name in ("cov_nn", "ellipse_major", "sigma_v", *CONF_COLUMNS):
        meta = schema.field(name).metadata
        assert meta[ERROR_MODEL_KEY] == MODEL.encode(), name
        assert (CONFIDENCE_KEY in meta) == (name in CONF_COLUMNS), name
    for name, dims in CONF_COLUMNS.items():
        meta = schema.field(name).metadata
        assert (meta[CONFIDENCE_KEY], meta[DIMENSIONS_KEY]) == (confidence.encode(), dims)


@pytest.mark.parametrize(
    ("confidence", "stated", "percent"), [(None, "0.95", "95"), (0.99, "0.99", "99")]
)
def test_every_deliverable_states_confidence_and_model(
    samples: Path, tmp_path: Path, confidence: float | None, stated: str, percent: str
) -> None:
    out = run(samples, tmp_path, confidence)

    las = lasio.read(out / "trajectory.las", mnemonic_case="preserve")
    assert las.params["CONF"].value == float(stated)
    assert las.params["ERRMODEL"].value == MODEL
    curves = {c.mnemonic: c.descr for c in las.curves}
    assert curves["ellipse_major"] == (
        f"semi-major axis of the horizontal error ellipse, 1 sigma; error model {MODEL}"
    )
    assert curves["ellipse_major_conf"] == (
        f"semi-major axis of the horizontal error ellipse at {percent} % confidence "
        f"(2-D, chi-square of 2 dof); error model {MODEL}"
    )
    assert curves["vertical_conf"] == (
        f"vertical error half-interval at {percent} % confidence (1-D, two-sided normal); "
        f"error model {MODEL}"
    )
    log = gp.read_table(out / "trajectory.las", kind="log")  # read back as a log: kept
    assert (
        log.schema.field("VERTICAL_CONF").metadata[DESCRIPTION_KEY].decode()
        == (curves["vertical_conf"])
    )

    comments = [
        line for line in (out / "trajectory.csv").read_text().splitlines() if line[0] == "#"
    ]
    assert f"# confidence={stated}" in comments
    assert f"# error_model={MODEL}" in comments

    common = wml.CreateFromDocument((out / "trajectory.xml").read_bytes()).trajectory[0].commonData
    assert common.comments.endswith(f"1 sigma squared, error model {MODEL}.")
    first = common.extensionNameValue[0]  # the schema's validation took it
    assert (first.name, first.value_.value()) == ("gyropipe.error_model", MODEL)

    assert_fields_state(pq.read_schema(out / "uncertainty.trajectory.parquet"), stated)
    assert_fields_state(mcap_trajectory_schema(out / "processed.mcap"), stated)
    for name in ("trajectory.las", "trajectory.csv", "trajectory.xml"):  # the readers take them
        assert gp.read_table(out / name).num_rows == las.data.shape[0]


def test_definitive_survey_states_the_models_of_its_runs(tmp_path: Path) -> None:
    runs = ROOT / "examples" / "definitive"
    gyropipe_cli(
        "run",
        ROOT / "pipelines" / "definitive.yaml",
        "--input",
        f"gyro={runs / 'gyro-run.csv'}",
        "--input",
        f"mwd={runs / 'mwd-run.csv'}",
        "--out",
        tmp_path,
        check=True,
    )
    models = f"{MODEL}, ISCWSA-MWD-REV5 rev 5 (2019 example workbook)"  # the two runs' files
    comments = (tmp_path / "definitive.csv").read_text().splitlines()[:20]
    assert "# confidence=0.95" in comments
    assert f"# error_model={models}" in comments
    meta = pq.read_schema(tmp_path / "definitive.survey.parquet").field("vertical_conf").metadata
    assert (meta[ERROR_MODEL_KEY], meta[CONFIDENCE_KEY]) == (models.encode(), b"0.95")


def test_a_model_the_run_changed_is_stated_with_its_changes(samples: Path, tmp_path: Path) -> None:
    """Magnitudes given and a measured compassing scatter make ellipses that are not the
    published model's: the deliverables said 'GYRO-NS rev 5' of them all the same."""
    out = run(samples, tmp_path, None)
    changed = tmp_path / "changed"
    pipeline = tmp_path / "pipeline.yaml"
    gyropipe_cli(
        "run", pipeline, "--input", f"samples={samples}", "--out", changed,
        "--set", "uncertainty.tool={GXY-G1: 0.5}", "--set", "uncertainty.measured_sigma_azi=0.2",
        check=True,
    )  # fmt: skip
    stated = f"{MODEL} with GXY-G1 0.5 deg/h/g, GXY-RN from a measured azimuth scatter of 0.2 deg"
    assert lasio.read(changed / "trajectory.las").params["ERRMODEL"].value == stated
    assert f"# error_model={stated}" in (changed / "trajectory.csv").read_text()
    schema = pq.read_schema(changed / "uncertainty.trajectory.parquet")
    assert schema.field("ellipse_major").metadata[ERROR_MODEL_KEY] == stated.encode()
    unchanged = pq.read_schema(out / "uncertainty.trajectory.parquet")
    assert unchanged.field("ellipse_major").metadata[ERROR_MODEL_KEY] == MODEL.encode()

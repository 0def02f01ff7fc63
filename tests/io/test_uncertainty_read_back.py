"""A trajectory file gyropipe wrote (CSV, LAS, WITSML) read back as stations keeps its
uncertainty columns and what the file states of them — confidence and error model, in the
columns' metadata and a frame's ``attrs`` — so a conversion writes them again; a size at a
confidence level the file does not state is left out, warned, never taken for 1σ; a
confidence that is no probability is refused at its line. Expected values: the files' text."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import lasio
import pytest
import yaml

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning
from pipeline.uncertainty.stated import CONFIDENCE_KEY, ERROR_MODEL_KEY
from tests_support import ROOT, gyropipe_cli

PLAN = ROOT / "examples" / "plans" / "short-j-well.yaml"
CONF_COLUMNS = ("ellipse_major_conf", "ellipse_minor_conf", "vertical_conf")


@pytest.fixture(scope="module")
def out(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """point-gyro (no report) of the short well, its CSV of the uncertainty trajectory."""
    root = tmp_path_factory.mktemp("read-back")
    gyropipe_cli("simulate", PLAN, "--out", root / "sim", check=True)
    spec = yaml.safe_load((ROOT / "pipelines" / "point-gyro.yaml").read_text())
    spec["stages"] = [s for s in spec["stages"] if s["id"] != "report"]
    for stage in spec["stages"]:
        if stage["id"] == "export_csv":
            stage["inputs"]["table"] = "uncertainty.trajectory"
    (root / "pipeline.yaml").write_text(yaml.safe_dump(spec, sort_keys=False))
    gyropipe_cli(
        "run", root / "pipeline.yaml", "--input", f"samples={root / 'sim' / 'samples.parquet'}",
        "--out", root / "out", check=True,
    )  # fmt: skip
    return root / "out"


def las_statements(path: Path) -> tuple[float, str]:
    las = lasio.read(path, mnemonic_case="preserve")
    return las.params["CONF"].value, las.params["ERRMODEL"].value


@pytest.mark.parametrize("name", ["trajectory.las", "trajectory.csv"])
def test_las_and_csv_keep_confidence_and_model(out: Path, name: str) -> None:
    confidence, model = las_statements(out / "trajectory.las")
    frame = gp.read(out / name)
    assert (
        frame.attrs["uncertainty"]["confidence"],
        frame.attrs["uncertainty"]["error_model"],
    ) == (
        confidence,
        model,
    )
    table = gp.read_table(out / name)
    for column in CONF_COLUMNS:
        meta = table.schema.field(column).metadata
        assert (meta[CONFIDENCE_KEY], meta[ERROR_MODEL_KEY]) == (
            str(confidence).encode(),
            model.encode(),
        )
    assert table.schema.field("cov_nn").metadata[ERROR_MODEL_KEY] == model.encode()
    assert table.schema.field("ellipse_azimuth").metadata[b"north_reference"] == b"true"
    las = lasio.read(out / "trajectory.las", mnemonic_case="preserve")
    assert frame["ellipse_major_conf"].iloc[-1] == pytest.approx(
        las["ellipse_major_conf"][-1], abs=0.5e-4
    )
    assert frame["cov_nn"].iloc[-1] == pytest.approx(las["cov_nn"][-1], abs=0.5e-8)


def test_witsml_keeps_covariances_and_model(out: Path, tmp_path: Path) -> None:
    _, model = las_statements(out / "trajectory.las")
    text = (out / "trajectory.xml").read_text()
    last = re.findall(r'<varianceNN uom="m2">([^<]+)</varianceNN>', text)[-1]
    frame = gp.read(out / "trajectory.xml")
    assert frame["cov_nn"].iloc[-1] == pytest.approx(float(last), rel=1e-12)
    stated = frame.attrs["uncertainty"]
    assert (stated["error_model"], stated["confidence"]) == (model, None)
    assert [f["family"] for f in stated["columns"]] == ["covariance"]
    gp.write(frame, tmp_path / "again.las")  # the frame's model goes with it, no CONF
    params = lasio.read(tmp_path / "again.las").params
    assert params["ERRMODEL"].value == model and "CONF" not in params


def test_conversion_writes_them_again(out: Path, tmp_path: Path) -> None:
    confidence, model = las_statements(out / "trajectory.las")
    gyropipe_cli("convert", out / "trajectory.las", tmp_path / "again.csv", check=True)
    lines = (tmp_path / "again.csv").read_text().splitlines()
    assert {f"# confidence={confidence}", f"# error_model={model}"} <= set(lines)
    assert "ellipse_major_conf[m]" in next(line for line in lines if line.startswith("md["))


def test_a_size_at_an_unstated_confidence_is_left_out(out: Path, tmp_path: Path) -> None:
    text = (out / "trajectory.las").read_text()
    conf = next(line for line in text.splitlines() if line.lstrip().startswith("CONF"))
    path = tmp_path / "no-conf.las"
    path.write_text(text.replace(conf + "\n", ""))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = gp.read_table(path)
    said = [str(w.message) for w in caught if issubclass(w.category, InputFileWarning)]
    lines = text.replace(conf + "\n", "").splitlines()
    for column in CONF_COLUMNS:
        assert column not in table.column_names
        line = 1 + next(i for i, x in enumerate(lines) if x.lstrip().startswith(column + "."))
        assert any(m.startswith(f"{path}:{line}: column {column} left out") for m in said)
    assert {"cov_nn", "ellipse_major", "sigma_v"} <= set(table.column_names)  # 1σ: kept
    csv_text = (out / "trajectory.csv").read_text()
    bare = tmp_path / "no-conf.csv"
    bare.write_text(csv_text.replace("# confidence=0.95\n", ""))
    with pytest.warns(InputFileWarning, match="left out") as caught:
        table = gp.read_table(bare)
    assert not set(CONF_COLUMNS) & set(table.column_names)
    assert [str(w.message).split(": ", 1)[1].split(" left")[0] for w in caught] == [
        f"column {c}" for c in CONF_COLUMNS
    ]


def test_a_confidence_that_is_no_probability_is_refused(out: Path, tmp_path: Path) -> None:
    csv_text = (out / "trajectory.csv").read_text()
    path = tmp_path / "percent.csv"
    path.write_text(csv_text.replace("# confidence=0.95", "# confidence=95"))
    line = 1 + csv_text.splitlines().index("# confidence=0.95")
    with pytest.raises(InputFileError, match=rf"{path.name}:{line}: confidence '95'"):
        gp.read_table(path)
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "survey.yaml", "--input", path, "--out", tmp_path / "o"
    )
    assert result.returncode != 0 and "Traceback" not in result.output
    assert f"{path.name}:{line}: confidence '95': expected a probability in (0, 1)" in result.output


def test_survey_pipeline_reads_a_trajectory_with_uncertainty(out: Path, tmp_path: Path) -> None:
    gyropipe_cli(
        "run", ROOT / "pipelines" / "survey.yaml", "--input", out / "trajectory.las",
        "--out", tmp_path, check=True,
    )  # fmt: skip
    assert (tmp_path / "trajectory.csv").is_file()

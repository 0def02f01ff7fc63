"""A run's processed.mcap read back as survey stations: survey.yaml integrates its trajectory
again (the same stations, positions and file-positions check as the run's own CSV says), the
API reads it with what its uncertainty columns state, the option ``topics`` picks the
compassed stations, and files or options that are no stations are refused in one line."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import lasio
import pytest

import pipeline as gp
from pipeline.errors import InputFileError, WrongKindError
from tests_support import ROOT, gyropipe_cli, point_gyro_run

STEP = {"md": 0.5e-4, "inc": 0.5e-6, "azi": 0.5e-6, "tvd": 0.5e-4, "north": 0.5e-4}
"""Half the step of each CSV column's decimals (m: 4, deg: 6)."""


@pytest.fixture(scope="module")
def gyro(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The outputs of a point-gyro run of the short well (no report)."""
    return point_gyro_run(tmp_path_factory.mktemp("mcap-stations"))


def csv_rows(path: Path) -> list[dict[str, float]]:
    """The data rows of a gyropipe CSV, by column name without unit (empty: NaN)."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    return [
        {key.split("[")[0]: float(value) if value else float("nan") for key, value in r.items()}
        for r in rows
    ]


def test_survey_pipeline_reads_the_runs_trajectory(gyro: Path, tmp_path: Path) -> None:
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "survey.yaml", "--input", gyro / "processed.mcap",
        "--out", tmp_path, check=True,
    )  # fmt: skip
    assert "ok:" in result.output
    before, after = csv_rows(gyro / "trajectory.csv"), csv_rows(tmp_path / "trajectory.csv")
    assert len(after) == len(before) == 10
    for old, new in zip(before, after, strict=True):
        for name, step in STEP.items():
            assert new[name] == pytest.approx(old[name], abs=2 * step, nan_ok=True), name
    checks = {
        c["check"]: c for c in json.loads((tmp_path / "summary.json").read_text())["qc"]["checks"]
    }
    assert checks["file_positions"]["evaluated"] == 10 and checks["file_positions"]["failed"] == 0


def test_api_reads_it_with_its_uncertainty_statements(gyro: Path) -> None:
    las = lasio.read(gyro / "trajectory.las", mnemonic_case="preserve")
    frame = gp.read(gyro / "processed.mcap")
    assert len(frame) == las.data.shape[0]
    assert frame["ellipse_major_conf"].iloc[-1] == pytest.approx(
        las["ellipse_major_conf"][-1], abs=0.5e-4
    )
    stated = frame.attrs["uncertainty"]
    assert (stated["confidence"], stated["error_model"]) == (
        las.params["CONF"].value,
        las.params["ERRMODEL"].value,
    )
    compassed = gp.read(gyro / "processed.mcap", topics=["/gyropipe/stations"])
    assert "sigma_azi" in compassed.columns and "cov_nn" not in compassed.columns
    assert list(compassed["md"]) == pytest.approx(list(frame["md"]))


def test_what_is_no_stations_is_refused(gyro: Path, tmp_path: Path) -> None:
    mcap = gyro / "processed.mcap"
    with pytest.raises(WrongKindError, match="use --kind stations"):
        gp.read_table(mcap, kind="samples")
    with pytest.raises(InputFileError, match=r"topic '/gyropipe/qc' is no survey"):
        gp.read_table(mcap, topics=["/gyropipe/qc"])
    with pytest.raises(InputFileError, match=r"options \['join'\] are for samples"):
        gp.read_table(mcap, kind="stations", join="interpolate")
    samples = gp.read_table(gyro.parent / "sim" / "samples.parquet")
    gp.write(samples, tmp_path / "samples.mcap")
    assert gp.read_table(tmp_path / "samples.mcap").num_rows == samples.num_rows  # auto: samples
    with pytest.raises(WrongKindError, match="no survey stations topic"):
        gp.read_table(tmp_path / "samples.mcap", kind="stations")

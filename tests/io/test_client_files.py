"""Files written for clients (CSV, LAS, WITSML, summary.json, MCAP) carry none of the
engine's own names: no ``source_line`` column (lines of the file read), no ``gyropipe.source``
path of an input, no engine metadata key — only gyropipe's documented names (the summary's
format, WITSML's ``gyropipe.well.*``, ``gyropipe.error_model`` and
``gyropipe.uncertainty_tie_on`` extensions, MCAP's own
topics and records). Runs of point-gyro and of survey.yaml (with an MCAP export), through
the CLI, on a stations file in a folder of its own."""

from __future__ import annotations

import re
from pathlib import Path

import pyarrow as pa
import pytest
import yaml
from mcap.reader import make_reader

from tests_support import ROOT, gyropipe_cli

PLAN = ROOT / "examples" / "plans" / "short-j-well.yaml"
TEXT_FILES = ("trajectory.csv", "trajectory.las", "trajectory.xml", "summary.json")
DOCUMENTED = re.compile(r"gyropipe\.(survey-summary|error_model|uncertainty_tie_on|well\.\w+)")
"""The gyropipe names a client file may hold: the summary's format, WITSML's extensions."""
MCAP_NAMES = re.compile(r"gyropipe\.(well|run|units/\w+|\w+)")
"""MCAP's records (``gyropipe.well``, ``gyropipe.run``, ``gyropipe.units/<role>``) and
topic schemas (``gyropipe.<role>``)."""
STATED = {
    b"unit",
    b"north_reference",
    b"description",
    b"gyropipe.error_model",
    b"gyropipe.confidence",
    b"gyropipe.confidence_dimensions",
    b"gyropipe.uncertainty_carried",
}
"""Field metadata an MCAP table may carry: what a column states of itself (an uncertainty
column's: that it came with the stations file)."""
TABLE_STATED = {
    b"gyropipe.well",
    b"gyropipe.survey_calculation",
    b"gyropipe.position_check",
    b"gyropipe.references",
    b"gyropipe.uncertainty_tie_on",
    b"gyropipe.recording_end",
    b"gyropipe.unread_stops",
}
"""Schema metadata an MCAP table may carry: the well, the calculation, the file positions'
check (the summary's and report's ``file_positions``), the QC's reference models, where the
uncertainty columns start (each survey's tie-on), the frame position the recording ended in
and the stops the tool made that gave no reading (the readings')."""


def survey_with_mcap(tmp_path: Path) -> Path:
    """survey.yaml, without its report, exporting its tables to MCAP as point-gyro does."""
    spec = yaml.safe_load((ROOT / "pipelines" / "survey.yaml").read_text())
    spec["stages"] = [s for s in spec["stages"] if s["id"] != "report"]
    spec["stages"].append(
        {
            "id": "export_mcap",
            "uses": "export",
            "inputs": {
                "trajectory": "trajectory.trajectory",
                "stations": "read.stations",
                "qc": "dls_check.results",
            },
            "with": {"writer": "mcap", "filename": "processed.mcap"},
        }
    )
    path = tmp_path / "survey-mcap.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, str]]:
    """Output folder and input file name of a point-gyro run and of survey.yaml runs on
    the bundled stations file and on point-gyro's own trajectory CSV (positions stated)."""
    root = tmp_path_factory.mktemp("client")
    gyropipe_cli("simulate", PLAN, "--out", root / "sim", check=True)
    samples = root / "sim" / "samples.parquet"
    gyropipe_cli(
        "run", ROOT / "pipelines" / "point-gyro.yaml", "--input", f"samples={samples}",
        "--out", root / "gyro", check=True,
    )  # fmt: skip
    found = {"point-gyro": (root / "gyro", samples.name)}
    pipeline = survey_with_mcap(root)
    inputs = {
        "survey": ROOT / "examples" / "stations-j-well.csv",
        "survey-trajectory": root / "gyro" / "trajectory.csv",
    }
    for name, source in inputs.items():
        given = root / f"in-{name}" / f"input-{name}.csv"
        given.parent.mkdir()
        given.write_bytes(source.read_bytes())
        gyropipe_cli("run", pipeline, "--input", given, "--out", root / name, check=True)
        found[name] = (root / name, given.name)
    return found


@pytest.mark.parametrize("run", ["point-gyro", "survey", "survey-trajectory"])
@pytest.mark.parametrize("name", TEXT_FILES)
def test_text_files_hold_no_engine_names(
    runs: dict[str, tuple[Path, str]], run: str, name: str
) -> None:
    out, given = runs[run]
    text = (out / name).read_text(encoding="utf-8")
    assert "source_line" not in text
    assert given not in text and str(out.parent) not in text  # no path of the run
    names = {m.group(0) for m in re.finditer(r"gyropipe\.[\w./-]+", text)}
    assert {n for n in names if not DOCUMENTED.fullmatch(n)} == set()


@pytest.mark.parametrize("run", ["point-gyro", "survey", "survey-trajectory"])
def test_mcap_holds_no_engine_names(runs: dict[str, tuple[Path, str]], run: str) -> None:
    out, given = runs[run]
    data = (out / "processed.mcap").read_bytes()
    assert b"source_line" not in data
    assert given.encode() not in data and str(out.parent).encode() not in data
    with (out / "processed.mcap").open("rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert summary is not None
        names = {s.name for s in summary.schemas.values()}
        names |= {m.name for m in reader.iter_metadata()}
        assert {n for n in names if not MCAP_NAMES.fullmatch(n)} == set()
        for schema in summary.schemas.values():
            arrow = pa.ipc.read_schema(pa.py_buffer(schema.data))
            assert set(arrow.metadata or {}) <= TABLE_STATED, schema.name
            for field in arrow:
                assert set(field.metadata or {}) <= STATED, (schema.name, field.name)

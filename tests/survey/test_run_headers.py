"""Several input files in one run: each run's stations take their own file's header (survey
date → geomagnetic field and declination, declination, grid convergence, datum), never the
header of the file read last. The expected values are the files' own."""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from test_magnetic_reference import method_text

import pipeline as gp
from pipeline.earth.geomagnetic import reference_field
from pipeline.stages.uncertainty import magnetic_of
from tests_support import ROOT, gyropipe_cli

RUNS = ROOT / "examples" / "definitive"
SITE = (61.25, 73.4, 54.3)  # the example runs' Latitude, Longitude, Elevation


def with_header(source: Path, directory: Path, **lines: str) -> Path:
    """``source`` with its title-block lines ``Key: value`` replaced or added (``Survey_Date``
    is ``Survey Date``), an ``Azimuth True`` column renamed as ``azimuth`` says."""
    text = source.read_text().splitlines()
    head = text.index("")
    given = {key.replace("_", " "): value for key, value in lines.items() if key != "azimuth"}
    kept = [line for line in text[:head] if line.split(":")[0] not in given]
    body = "\n".join(text[head:]).replace("Azimuth True", lines.get("azimuth", "Azimuth True"))
    path = directory / source.name
    path.write_text("\n".join([*kept, *(f"{k}: {v}" for k, v in given.items())]) + body + "\n")
    return path


def pipelines(directory: Path) -> list[Path]:
    """definitive.yaml as shipped (gyro read first) and with the MWD run read first."""
    shipped = ROOT / "pipelines" / "definitive.yaml"
    text = shipped.read_text()
    gyro = "  - id: read_gyro\n    uses: read_stations\n    with: {input: gyro}\n\n"
    mwd = "  - id: read_mwd\n    uses: read_stations\n    with: {input: mwd}\n\n"
    assert gyro + mwd in text
    swapped = directory / "mwd-first.yaml"
    swapped.write_text(text.replace(gyro + mwd, mwd + gyro))
    return [shipped, swapped]


def run(pipeline: Path, out: Path, gyro: Path, mwd: Path) -> Path:
    result = gyropipe_cli(
        "run", pipeline, "--input", f"gyro={gyro}", "--input", f"mwd={mwd}", "--out", out,
        "--set", "report.formats=[html]",
    )  # fmt: skip
    assert result.returncode == 0, result.output
    return out


@pytest.fixture
def runs(tmp_path: Path) -> tuple[Path, Path]:
    """A gyro run of 2026-11-21 stating a declination of 11.9°, an MWD run of 2025-06-05
    stating its own field and declination (12.5°)."""
    return two_runs(
        tmp_path,
        Survey_Date="2025-06-05",
        Declination="12.5",
        Magnetic_Field="58000",
        Magnetic_Dip="78.0",
    )


def two_runs(directory: Path, **mwd: str) -> tuple[Path, Path]:
    """The example gyro run stating a declination of 11.9° and the MWD run with the header
    lines ``mwd`` (``Survey_Date`` → ``Survey Date: …``), in their own folders."""
    (directory / "gyro").mkdir()
    (directory / "mwd").mkdir()
    gyro = with_header(RUNS / "gyro-run.csv", directory / "gyro", Declination="11.9")
    return gyro, with_header(RUNS / "mwd-run.csv", directory / "mwd", **mwd)


def test_each_run_takes_its_own_files_field_in_either_read_order(
    tmp_path: Path, runs: tuple[Path, Path]
) -> None:
    gyro, mwd = runs
    surveys = []
    for k, pipeline in enumerate(pipelines(tmp_path)):
        out = run(pipeline, tmp_path / f"out{k}", gyro, mwd)
        assert (
            "geomagnetic reference: total field 58,000 nT, dip 78.00°, declination 12.50° "
            "(given in the well metadata)"
        ) in method_text(out / "report.html"), pipeline.name
        surveys.append(pq.read_table(out / "definitive.survey.parquet"))
    applied = magnetic_of(surveys[1])
    assert applied is not None and applied.reference.declination == 12.5
    assert surveys[0].equals(surveys[1])  # the read order changes nothing


def test_each_run_takes_the_field_at_its_own_date(tmp_path: Path) -> None:
    """No declination in either header: the MWD run's field is the model's at its own date,
    not at the gyro's (read last in the shipped order, first in the other)."""
    (tmp_path / "mwd").mkdir()
    mwd = with_header(RUNS / "mwd-run.csv", tmp_path / "mwd", Survey_Date="2025-06-05")
    wmm = reference_field(*SITE, dt.date(2025, 6, 5)).reference()
    for k, pipeline in enumerate(pipelines(tmp_path)):
        out = run(pipeline, tmp_path / f"out{k}", RUNS / "gyro-run.csv", mwd)
        assert (
            f"declination {wmm.declination:.2f}° (WMM2025 at 61.2500° N 73.4000° E, 2025-06-05)"
        ) in method_text(out / "report.html"), pipeline.name


def test_each_run_takes_its_own_grid_convergence(tmp_path: Path) -> None:
    """MWD azimuths to grid north with the file's convergence 1.2° beside a gyro run stating
    0.8°: the definitive survey (true north) lists the MWD's at A_grid + 1.2°."""
    (tmp_path / "gyro").mkdir()
    (tmp_path / "mwd").mkdir()
    gyro = with_header(RUNS / "gyro-run.csv", tmp_path / "gyro", Grid_Convergence="0.8")
    mwd = with_header(
        RUNS / "mwd-run.csv", tmp_path / "mwd", Grid_Convergence="1.2", azimuth="Azimuth Grid"
    )
    grid = np.loadtxt(RUNS / "mwd-run.csv", delimiter=",", skiprows=10)
    for k, pipeline in enumerate(pipelines(tmp_path)):
        out = run(pipeline, tmp_path / f"out{k}", gyro, mwd)
        survey = pq.read_table(out / "definitive.survey.parquet")
        listed = np.isin(grid[:, 0], survey.column("md").to_numpy())
        mwd_md = np.isin(survey.column("md").to_numpy(), grid[listed, 0])
        assert survey.column("azi").to_numpy()[mwd_md] == pytest.approx(
            grid[listed, 2] + 1.2, abs=1e-9
        ), pipeline.name


def test_runs_from_two_datums_are_refused(tmp_path: Path) -> None:
    (tmp_path / "mwd").mkdir()
    mwd = with_header(RUNS / "mwd-run.csv", tmp_path / "mwd", Elevation="50.1")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "definitive.yaml", "--input", f"gyro={RUNS / 'gyro-run.csv'}",
        "--input", f"mwd={mwd}", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode == 1
    assert "the runs' elevation differ (GYRO-1 54.3, MWD-1 50.1)" in result.stderr
    assert not (tmp_path / "out").exists()
    # the gyro run's 54.3 m written in feet (178.15 ft = 54.30012 m) is the same datum
    mwd = with_header(RUNS / "mwd-run.csv", tmp_path / "mwd", Elevation="178.15 ft")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "definitive.yaml", "--input", f"gyro={RUNS / 'gyro-run.csv'}",
        "--input", f"mwd={mwd}", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr


def test_the_runs_well_states_only_what_the_files_agree_on(
    tmp_path: Path, runs: tuple[Path, Path]
) -> None:
    """run.json's ``well`` states the survey dates' range and no declination (the runs'
    differ: ``well_differs`` states each), the export's header no one run's declination, the
    report the range; a field one file states alone stays stated."""
    gyro, mwd = runs
    for k, pipeline in enumerate(pipelines(tmp_path)):
        out = run(pipeline, tmp_path / f"out{k}", gyro, mwd)
        manifest = json.loads((out / "run.json").read_text())
        well = manifest["well"]
        assert (well["survey_date"], well["survey_date_last"]) == ("2025-06-05", "2026-11-21")
        assert "declination" not in well and well["magnetic_field"] == 58000
        assert manifest["well_differs"]["declination"] == {"gyro": 11.9, "mwd": 12.5}
        assert manifest["well_differs"]["survey_date"] == {
            "gyro": "2026-11-21",
            "mwd": "2025-06-05",
        }
        assert "well.declination" not in (out / "definitive.csv").read_text()
        assert "2025-06-05 to 2026-11-21" in (out / "report.html").read_text()


def test_the_shipped_example_states_each_runs_tool_not_the_last_read(tmp_path: Path) -> None:
    """The example runs agree but on their tool: the definitive survey's export and run.json
    name neither as the run's (each station's tool_type column names its own)."""
    pipeline = ROOT / "pipelines" / "definitive.yaml"
    out = run(pipeline, tmp_path / "out", RUNS / "gyro-run.csv", RUNS / "mwd-run.csv")
    manifest = json.loads((out / "run.json").read_text())
    assert manifest["well_differs"] == {
        "tool_type": {"gyro": "north-seeking gyro (example)", "mwd": "MWD (example)"}
    }
    assert "tool_type" not in manifest["well"] and manifest["well"]["survey_date"] == "2026-11-21"
    assert "well.tool_type" not in (out / "definitive.csv").read_text()
    tools = pq.read_table(out / "definitive.survey.parquet").column("tool_type").to_pylist()
    assert set(tools) == {"north-seeking gyro (example)", "MWD (example)"}


def test_the_api_takes_each_runs_own_header_in_either_order(runs: tuple[Path, Path]) -> None:
    """gp.definitive_survey: the runs' order (the MWD's header given first or last) changes
    nothing: the MWD run's ellipses are those of its own field, given in its file."""
    gyro, mwd = (gp.read(path) for path in runs)
    options = {"mwd": {"model": "ISCWSA-MWD-REV5"}}
    first = gp.definitive_survey({"mwd": mwd, "gyro": gyro}, run_options=options)["survey"]
    last = gp.definitive_survey({"gyro": gyro, "mwd": mwd}, run_options=options)["survey"]
    given = gp.definitive_survey(
        {"gyro": gyro, "mwd": mwd},
        run_options=options,
        magnetic={"total_field": 58000, "dip": 78.0, "declination": 12.5},
    )["survey"]
    for survey in (first, last):
        assert survey["ellipse_major"].to_numpy() == pytest.approx(
            given["ellipse_major"].to_numpy(), rel=1e-12
        )


def test_headers_within_a_field_s_tolerance_agree(tmp_path: Path) -> None:
    """Two runs' headers stating a latitude 61.25 and 61.2500001, an elevation 54.3 and
    54.3004 m, a declination 11.9 and 11.9000004° state one value each (once unstated and
    in ``well_differs``); a longitude 1e-5° apart still differs."""
    gyro, mwd = two_runs(
        tmp_path,
        Latitude="61.2500001",
        Longitude="73.40001",
        Elevation="54.3004",
        Declination="11.9000004",
    )
    out = run(ROOT / "pipelines" / "definitive.yaml", tmp_path / "out", gyro, mwd)
    manifest = json.loads((out / "run.json").read_text())
    assert set(manifest["well_differs"]) == {"tool_type", "longitude"}
    assert manifest["well_differs"]["longitude"] == {"gyro": 73.4, "mwd": 73.40001}
    well = manifest["well"]
    assert well["latitude"] == pytest.approx(61.25, abs=1e-6)
    assert well["elevation"] == pytest.approx(54.3, abs=1e-3)
    assert well["declination"] == pytest.approx(11.9, abs=1e-6)
    assert "longitude" not in well

"""Command-line mistakes get one formatted line that says what to do (no pydantic dump, no
URL), with a suggestion where a name is misspelt."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests_support import ROOT, CliResult, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
SAMPLE = ROOT / "examples" / "stations-j-well.csv"


def run(tmp_path: Path, *extra: str) -> CliResult:
    args = ["run", str(SURVEY), "--input", str(SAMPLE), "--out", str(tmp_path / "o"), *extra]
    return gyropipe_cli(*args)


@pytest.mark.parametrize(
    ("items", "expected"),
    [
        (["latitude=161"], "error: --well latitude=161: input should be less than or equal to 90"),
        (
            ["lattitude=61"],
            "error: --well lattitude=61: unknown field 'lattitude'; did you mean 'latitude'",
        ),
        (
            ["north_reference=tru"],
            "error: --well north_reference=tru: input should be 'true', 'grid' or 'magnetic'",
        ),
        (  # contradictory: was the last, silently
            ["survey_date=2026-03-02", "survey_date=2026-03-05"],
            "error: --well survey_date=2026-03-05: survey_date given twice (also "
            "--well survey_date=2026-03-02)",
        ),
    ],
)
def test_well_overrides(tmp_path: Path, items: list[str], expected: str) -> None:
    result = run(tmp_path, *(arg for item in items for arg in ("--well", item)))
    assert result.returncode == 2
    assert result.stderr.startswith(expected), result.stderr
    assert "pydantic" not in result.stderr and "https://" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_a_reader_option_given_twice_is_refused(tmp_path: Path) -> None:
    args = ["--option", "stations=all", "--option", "stations=survey"]
    result = gyropipe_cli("convert", SAMPLE, *args, "--out", tmp_path / "o.csv")
    assert result.returncode == 2 and not (tmp_path / "o.csv").exists()
    assert "--option stations=survey: stations given twice (also --option stations=all)" in (
        result.stderr
    )
    same = ["--option", "stations=all", "--option", "stations=all"]  # one value: no conflict
    gyropipe_cli("convert", SAMPLE, *same, "--out", tmp_path / "o.csv", check=True)


TINY = {
    "name": "tiny",
    "site": {
        "latitude": 61.25,
        "longitude": 73.4,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
    },
    "well": {"sections": [{"kind": "vertical", "length": 30}]},
    "tool": {"preset": "ideal"},
    "survey": {"mode": "point", "every": 30, "dwell": 2, "move_time": 1.0, "speed": 10.0},
}


@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_raw_samples_given_to_the_survey_pipeline(tmp_path: Path, suffix: str) -> None:
    """The wrong kind of input is recognised first, and the pipelines that take it named."""
    import pipeline as gp

    samples = tmp_path / f"samples{suffix}"
    gp.write(gp.simulate(TINY).samples, samples)
    result = gyropipe_cli("run", str(SURVEY), "--input", str(samples), "--out", str(tmp_path / "o"))
    assert result.returncode == 1
    assert "a table of raw sensor samples; not survey stations (needs " in result.stderr
    assert "as in pipelines/point-gyro.yaml and pipelines/continuous-gyro.yaml" in result.stderr
    assert "strictly increasing" not in result.stderr and "bad rows" not in result.stderr


def test_stations_given_to_a_raw_samples_pipeline(tmp_path: Path) -> None:
    pipeline = ROOT / "pipelines" / "point-gyro.yaml"
    result = gyropipe_cli(
        "run", str(pipeline), "--input", str(SAMPLE), "--out", str(tmp_path / "o")
    )
    assert result.returncode == 1
    assert "a table of survey stations; not raw sensor samples" in result.stderr
    assert "survey stations are read by read_stations, as in pipelines/survey.yaml" in result.stderr


def test_a_witsml_file_given_to_a_raw_samples_pipeline(tmp_path: Path) -> None:
    """Issue 28 item 13: 'no installed reader recognises … name one with `reader:`' said
    nothing of what the file is; the WITSML reader knows it, and the stations pipeline is
    named."""
    witsml = tmp_path / "j.xml"
    assert gyropipe_cli("convert", str(SAMPLE), "--out", str(witsml)).returncode == 0
    pipeline = ROOT / "pipelines" / "point-gyro.yaml"
    result = gyropipe_cli(
        "run", str(pipeline), "--input", str(witsml), "--out", str(tmp_path / "o")
    )
    assert result.returncode == 1
    assert f"{witsml}: a witsml file of stations, not samples" in result.stderr
    assert "survey stations are read by read_stations, as in pipelines/survey.yaml" in result.stderr
    assert "name one with `reader:`" not in result.stderr


def test_a_reader_option_hint_names_a_form_that_works(tmp_path: Path) -> None:
    """Issue 28 item 13: the reader's 'set the option … md_unit' led to ``--set
    read.md_unit=ft``, which is refused; the refusal names the working form, which runs."""
    stations = tmp_path / "s.csv"
    stations.write_text("md,inc [deg],azi TN [deg]\n0,0,0\n100,1,10\n200,2,20\n")
    args = ["run", str(SURVEY), "--input", str(stations)]
    result = gyropipe_cli(*args, "--out", str(tmp_path / "a"))
    assert "no unit for this column" in result.stderr
    assert "or set the reader option units: {md: ft} or md_unit: ft" in result.stderr
    result = gyropipe_cli(*args, "--out", str(tmp_path / "b"), "--set", "read.md_unit=ft")
    assert result.returncode == 2
    hinted = re.search(r"reader options go under options: --set (\S+),", result.stderr)
    assert hinted is not None, result.stderr
    assert hinted[1] == "read.options.md_unit=ft"
    result = gyropipe_cli(*args, "--out", str(tmp_path / "c"), "--set", hinted[1])
    assert result.returncode == 0, result.stderr


def test_misspelt_names_get_a_suggestion(tmp_path: Path) -> None:
    result = gyropipe_cli("validate", str(SURVEY), "--set", "trajectory.vs_azimth=10")
    assert result.returncode == 2
    assert (
        "--set trajectory.vs_azimth=10: stage 'trajectory' (minimum_curvature): unknown field "
        "'vs_azimth'; did you mean 'vs_azimuth'?"
    ) in result.stderr
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nstagez: []\nstages:\n  - id: r\n    uzes: read_stations\n")
    result = gyropipe_cli("validate", str(bad))
    assert f"{bad}:5:5: unknown field 'stages.0.uzes'; did you mean 'uses'?" in result.stderr
    assert f"{bad}:2:1: unknown field 'stagez'; did you mean 'stages'?" in result.stderr


def test_an_option_value_is_limited_yaml(tmp_path: Path) -> None:
    option = ["--option", "delimiter=!!python/name:os.system"]
    result = gyropipe_cli("convert", str(SAMPLE), "--out", str(tmp_path / "o.csv"), *option)
    assert result.returncode == 2
    assert (
        "error: --option delimiter=!!python/name:os.system: YAML tag "
        "'tag:yaml.org,2002:python/name:os.system' is not allowed"
    ) in result.stderr
    assert "Traceback" not in result.stderr

"""A run's deliverables say one thing: the bundled survey and point-gyro pipelines, and the
listings a real job brings (a grid listing with its convergence, a magnetic one corrected
to true north by its declination, depths and datum elevation in ft in the southern and
western hemispheres tied on below surface, a listing whose own positions disagree, a
sidetrack listed beside its main bore, grid stations in Parquet whose well names no north),
each run once, every deliverable read back and compared (:mod:`agreement_support`)."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Callable
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml
from agreement_support import (
    TRAJECTORY_FILES,
    assert_deliverables_agree,
    report_blocks,
    report_fields,
)

from tests_support import ROOT, gyropipe_cli

SAMPLE = ROOT / "examples" / "stations-j-well.csv"
SURVEY = ROOT / "pipelines" / "survey.yaml"
FT = 0.3048


def listing(
    directory: Path, name: str, header: dict[str, str], columns: str, first: int = 0
) -> Path:
    """The bundled sample's stations from row ``first`` under ``header`` (its title lines
    replaced or added) and ``columns``; depths in ft where the MD column says so."""
    lines = SAMPLE.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    title = dict(line.split(": ", 1) for line in lines[:start] if line)
    rows = [line.split(",") for line in lines[start + 1 :] if line][first:]
    if "(ft)" in columns:
        rows = [[f"{float(r[0]) / FT:.2f}", *r[1:]] for r in rows]
    text = "\n".join(f"{k}: {v}" for k, v in (title | header).items())
    path = directory / f"{name}.csv"
    path.write_text(f"{text}\n\n{columns}\n" + "\n".join(",".join(r) for r in rows) + "\n")
    return path


def without_las(directory: Path) -> Path:
    """survey.yaml without its LAS export (a LAS file is one path: one of a trajectory of
    several surveys is refused)."""
    spec = yaml.safe_load(SURVEY.read_text())
    spec["stages"] = [st for st in spec["stages"] if st["id"] != "export_las"]
    path = directory / "without-las.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def to_true(directory: Path) -> Path:
    """survey.yaml with a north_reference stage converting the azimuths to true north."""
    spec = yaml.safe_load(SURVEY.read_text())
    del spec["well"]
    stages = spec["stages"]
    stages.insert(1, {"id": "north", "uses": "north_reference", "with": {"target": "true"}})
    stages[1]["inputs"] = {"stations": "read.stations"}
    stages[2]["inputs"] = {"stations": "north.stations"}
    path = directory / "to-true.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def sidetrack(directory: Path) -> Path:
    """The bundled sample as survey MAIN and, below 1200 m, a sidetrack ST1 turning 1° per
    10 m from it, in one listing with a Survey column."""
    lines = SAMPLE.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    rows = [line.split(",") for line in lines[start + 1 :] if line]
    main = [f"{md},{inc},{azi},MAIN" for md, inc, azi in rows]
    turned = [
        f"{md},{inc},{(float(azi) + (float(md) - 1200.0) / 10.0) % 360.0:.2f},ST1"
        for md, inc, azi in rows
        if float(md) >= 1200.0
    ]
    path = directory / "sidetrack.csv"
    title = "\n".join(lines[:start])
    path.write_text(f"{title}\n{lines[start]},Survey\n" + "\n".join(main + turned) + "\n")
    return path


def without_north(directory: Path, run: Path) -> Path:
    """A run's persisted trajectory as stations whose well metadata names no north (their
    azimuth column's names it)."""
    table = pq.read_table(run / "trajectory.trajectory.parquet").select(["md", "inc", "azi"])
    well = json.loads(table.schema.metadata[b"gyropipe.well"])
    del well["north_reference"]
    path = directory / "no-well-north.parquet"
    pq.write_table(table.replace_schema_metadata({b"gyropipe.well": json.dumps(well)}), path)
    return path


def own_positions(directory: Path, run: Path) -> Path:
    """The bundled sample's trajectory.csv (its own TVD, north, east) with TVD 5 m deeper
    from 2000 m MD."""
    lines = (run / "trajectory.csv").read_text().splitlines()
    for i, line in enumerate(lines):
        cells = line.split(",")
        if line[:1].isdigit() and float(cells[0]) >= 2000.0:
            cells[3] = str(float(cells[3]) + 5.0)
            lines[i] = ",".join(cells)
    path = directory / "positions.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Path]:
    """Output directory of each run, made once."""
    tmp = tmp_path_factory.mktemp("agree")
    done: dict[str, Path] = {}

    def survey(name: str, stations: Path, pipeline: Path = SURVEY) -> Path:
        out = tmp / name
        html = ["--set", "report.formats=[html]"] if name != "survey" else []
        result = gyropipe_cli("run", pipeline, "--input", stations, "--out", out, *html)
        assert result.returncode == 0, result.stderr
        return out

    def point_gyro() -> Path:
        plan = ROOT / "examples" / "plans" / "short-j-well.yaml"
        gyropipe_cli("simulate", plan, "--out", tmp / "sim", check=True)
        return survey(
            "point-gyro", tmp / "sim" / "samples.parquet", ROOT / "pipelines" / "point-gyro.yaml"
        )

    made = {
        "survey": lambda: survey("survey", SAMPLE),
        "point-gyro": point_gyro,
        "grid": lambda: survey(
            "grid",
            listing(tmp, "grid", {"Grid Convergence": "-1.8"}, "MD (m),Inc (deg),Azi Grid (deg)"),
        ),
        "magnetic": lambda: survey(
            "magnetic",
            listing(
                tmp,
                "magnetic",
                {"Magnetic Declination": "14.5 E"},
                "MD (m),Inc (deg),Azi Magnetic (deg)",
            ),
            to_true(tmp),
        ),
        "ft-south-west": lambda: survey(
            "ft-south-west",
            listing(
                tmp,
                "ft",
                {
                    "Latitude": "33.9 S",
                    "Longitude": "70.6 W",
                    "Elevation": "178 ft",
                    "Depth Reference": "KB",
                },
                "MD (ft),Inc (deg),Azimuth True (deg)",
                first=20,
            ),
        ),
        "positions": lambda: survey("positions", own_positions(tmp, done["survey"])),
        "sidetrack": lambda: survey("sidetrack", sidetrack(tmp), without_las(tmp)),
        "grid-parquet": lambda: survey("grid-parquet", without_north(tmp, get("grid"))),
    }

    def get(name: str) -> Path:
        if name == "positions":
            get("survey")
        if name not in done:
            done[name] = made[name]()
        return done[name]

    return get


@pytest.mark.parametrize(
    ("run", "trajectory"),
    [
        ("survey", "trajectory.trajectory.parquet"),
        ("point-gyro", "uncertainty.trajectory.parquet"),
        ("grid", "trajectory.trajectory.parquet"),
        ("magnetic", "trajectory.trajectory.parquet"),
        ("ft-south-west", "trajectory.trajectory.parquet"),
        ("positions", "trajectory.trajectory.parquet"),
        ("sidetrack", "trajectory.trajectory.parquet"),
        ("grid-parquet", "trajectory.trajectory.parquet"),
    ],
)
def test_every_deliverable_of_a_run_says_the_same(
    runs: Callable[[str], Path], run: str, trajectory: str
) -> None:
    # a two-survey LAS is refused (test_a_two_survey_trajectory_is_no_las_log)
    files = TRAJECTORY_FILES if run != "sidetrack" else ("trajectory.csv", "trajectory.xml")
    assert_deliverables_agree(runs(run), trajectory, files)


def test_the_report_states_each_surveys_results_and_tie_in(runs: Callable[[str], Path]) -> None:
    # the summary gave the last survey's TD, position and closure as the well's, unnamed,
    # and each survey's tie-in (ST1, its file listing no positions, begins within MAIN's
    # depths: tied on MAIN at its first MD, the report says; it was tied at TVD = MD, N = E = 0)
    out = runs("sidetrack")
    blocks = report_blocks(out / "report.html")
    main, st1 = blocks["Results, survey MAIN"], blocks["Results, survey ST1"]
    assert main["Total depth (MD)"] == st1["Total depth (MD)"] == "2520.00 m"
    assert main["TVD at TD"] != st1["TVD at TD"]
    method = blocks["Method"]
    assert (
        method["Tie-in (first station of survey MAIN)"]
        == "MD 0.00 m, TVD 0.00 m, N 0.00 m, E 0.00 m (from the pipeline)"
    )
    assert (
        method["Tie-in (first station of survey ST1)"]
        == "MD 1200.00 m, TVD 1125.50 m, N 209.47 m, E 169.12 m (on survey 'MAIN' at that MD)"
    )
    assert "Results" in report_blocks(runs("survey") / "report.html")


def test_a_two_survey_trajectory_is_no_las_log(tmp_path: Path) -> None:
    """The LAS writer wrote a main bore and its sidetrack as one log whose MD went back
    from 2520 m to 1200 m, without the survey column: read by others as one path, refused
    by gyropipe's reader. It is refused, naming where and which surveys; nothing is
    published."""
    out = tmp_path / "out"
    result = gyropipe_cli("run", SURVEY, "--input", sidetrack(tmp_path), "--out", out)
    assert result.returncode != 0 and not out.exists()
    assert "export_las" in result.stderr
    assert "md runs back from 2520 to 1200 at row" in result.stderr
    assert "(survey 'MAIN' to 'ST1'): a LAS file is one log along one path" in result.stderr


def test_the_report_states_the_sites_corrections_and_those_applied(
    runs: Callable[[str], Path],
) -> None:
    # the report said "Azimuth reference true north" of azimuths corrected from magnetic by
    # 14.5°, and grid north of a grid listing, without either angle that the CSV, LAS,
    # WITSML and summary.json state
    grid = report_fields(runs("grid") / "report.html")
    assert grid["Grid convergence"] == "1.80° W"
    assert grid["Azimuth reference"] == "grid north"
    magnetic = report_fields(runs("magnetic") / "report.html")
    assert magnetic["Magnetic declination"] == "14.50° E"
    assert magnetic["Declination applied to azimuths"] == "14.50° E"
    assert magnetic["Azimuth reference"] == "true north"
    plain = report_fields(runs("survey") / "report.html")
    assert "Magnetic declination" not in plain and "Grid convergence" not in plain


def test_the_pdf_states_what_the_html_does(runs: Callable[[str], Path]) -> None:
    out = runs("survey")
    text = " ".join(
        subprocess.run(
            ["pdftotext", "-layout", out / "report.pdf", "-"], capture_output=True, check=True
        )
        .stdout.decode()
        .split()
    )
    fields = report_fields(out / "report.html")
    for label in ("Closure at TD", "Maximum DLS", "Datum elevation", "Azimuth reference"):
        assert f"{label} {fields[label]}" in text, label
    summary = json.loads((out / "summary.json").read_text())
    assert f"Stations {summary['station_count']} (" in text


def test_a_sidetrack_listed_beside_its_main_bore_is_tied_on_it(tmp_path: Path) -> None:
    """A listing of a main bore and, from 1200 m (a main-bore station), its sidetrack: the
    sidetrack was tied at TVD = MD, N = E = 0 without a word (279 m from the main bore's
    hole at 1200 m), then with a warning; now it starts at the main bore's station there;
    a re-survey from surface is tied at the wellhead as before."""
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", without_las(tmp_path), "--input", sidetrack(tmp_path), "--out", out,
        "--set", "report.formats=[html]",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "begins at MD" not in result.stderr
    rows = pq.read_table(out / "trajectory.trajectory.parquet").to_pylist()
    (kop,) = (r for r in rows if r["survey"] == "MAIN" and r["md"] == 1200.0)
    first = next(r for r in rows if r["survey"] == "ST1")
    assert [first[c] for c in ("tvd", "north", "east")] == pytest.approx(
        [kop[c] for c in ("tvd", "north", "east")], abs=1e-9
    )
    resurvey = tmp_path / "resurvey.csv"
    text = sidetrack(tmp_path).read_text().replace(",ST1", ",RUN2")
    lines = text.splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    main = [line for line in lines[header + 1 :] if line.endswith(",MAIN")]
    rows = [*main, *(m.replace(",MAIN", ",RUN2") for m in main)]
    resurvey.write_text("\n".join([*lines[: header + 1], *rows]) + "\n")
    again = gyropipe_cli(
        "run", without_las(tmp_path), "--input", resurvey, "--out", tmp_path / "again",
        "--set", "report.formats=[html]",
    )  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert "begins at MD" not in again.stderr

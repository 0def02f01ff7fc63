"""A survey starts at its stations file's own tie-on: a file whose first row is a tie-on
point off the wellhead (MD 500 m, TVD 498.30 m, N 12.10 m, E -3.40 m) is integrated from
there — it was integrated from TVD = MD, N = E = 0 with only a warning — unless the stage
is given a tie of its own; the tie applied is recorded and stated in the report."""

from __future__ import annotations

import html
import itertools
import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import InputFileError, StageError, SurveyCheckWarning
from pipeline.survey.calculation import calculation_of
from tests_support import ROOT, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
TIE = (500.0, 498.30, 12.10, -3.40)
"""The tie-on row: MD, TVD, north, east (m)."""
STATIONS = [(500.0 + 30.0 * k, 4.0 + 1.5 * k, 310.0 + 2.0 * k) for k in range(11)]
"""MD (m), inclination, azimuth (deg, true north): a build and turn from the tie-on."""


def hand_positions(
    stations: list[tuple[float, float, float]], tvd: float, north: float, east: float
) -> list[tuple[float, float, float]]:
    """TVD, north, east of each station by minimum curvature from the given tie, course by
    course as a survey engineer's sheet does (β, RF = 2/β · tan(β/2), half-course sums)."""
    out = [(tvd, north, east)]
    for (md1, i1, a1), (md2, i2, a2) in itertools.pairwise(stations):
        i1, a1, i2, a2 = map(math.radians, (i1, a1, i2, a2))
        beta = math.acos(math.cos(i2 - i1) - math.sin(i1) * math.sin(i2) * (1 - math.cos(a2 - a1)))
        rf = 1.0 if beta < 1e-9 else 2.0 / beta * math.tan(beta / 2.0)
        half = (md2 - md1) / 2.0 * rf
        tvd += half * (math.cos(i1) + math.cos(i2))
        north += half * (math.sin(i1) * math.cos(a1) + math.sin(i2) * math.cos(a2))
        east += half * (math.sin(i1) * math.sin(a1) + math.sin(i2) * math.sin(a2))
        out.append((tvd, north, east))
    return out


LISTED = hand_positions(STATIONS, *TIE[1:])
"""The vendor's listing (from the tie-on), rounded to 0.01 m in the files."""
HEADER = """\
Well: T-7
Latitude: 61.25
Longitude: 73.4
Survey Date: 2026-11-21

MD (m),Inc (deg),Azimuth True (deg),TVD (m),North (m),East (m)
"""


def csv_listing(directory: Path) -> Path:
    path = directory / "tied-on.csv"
    rows = [
        f"{md:.2f},{inc:.2f},{azi:.2f},{tvd:.2f},{n:.2f},{e:.2f}"
        for (md, inc, azi), (tvd, n, e) in zip(STATIONS, LISTED, strict=True)
    ]
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def _trajectory_xml(uid: str, name: str, listed: bool) -> str:
    stations = []
    for k, ((md, inc, azi), (tvd, n, e)) in enumerate(zip(STATIONS, LISTED, strict=True)):
        kind = "tie in point" if k == 0 else "gyro north seeking"
        position = (
            f'<tvd uom="m">{tvd:.2f}</tvd><dispNs uom="m">{n:.2f}</dispNs>'
            f'<dispEw uom="m">{e:.2f}</dispEw>'
            if listed
            else ""
        )
        stations.append(
            f'<trajectoryStation uid="{uid}{k}"><typeTrajStation>{kind}</typeTrajStation>'
            f'<md uom="m">{md:.2f}</md>{position}<incl uom="dega">{inc:.2f}</incl>'
            f'<azi uom="dega">{azi:.2f}</azi></trajectoryStation>'
        )
    return (
        f'<trajectory uidWell="w" uidWellbore="b" uid="{uid}"><nameWell>T-7</nameWell>'
        f"<nameWellbore>T-7</nameWellbore><name>{name}</name><aziRef>true north</aziRef>"
        + "".join(stations)
        + "</trajectory>"
    )


def witsml_export(directory: Path, *, second_unlisted: bool = False) -> Path:
    """The survey as WITSML 1.4.1.1 gives it (``typeTrajStation`` ``tie in point`` first);
    with ``second_unlisted`` a second trajectory of the same stations listing no positions."""
    path = directory / "tied-on.xml"
    second = _trajectory_xml("u", "bare", listed=False) if second_unlisted else ""
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<trajectorys xmlns="http://www.witsml.org/schemas/1series" version="1.4.1.1">'
        + _trajectory_xml("t", "gyro", listed=True)
        + second
        + "</trajectorys>\n"
    )
    return path


def plain(report: Path) -> str:
    """The report's text, tags and entities undone."""
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", report.read_text())).split())


def positions(table: pa.Table) -> np.ndarray:
    return np.column_stack([table.column(c).to_numpy() for c in ("tvd", "north", "east")])


def test_a_csv_survey_is_tied_at_its_tie_on_row(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", SURVEY, "--input", csv_listing(tmp_path), "--out", out,
        "--set", "report.formats=[html]",
    )  # fmt: skip
    assert result.returncode == 0, result.output
    assert "warning:" not in result.stderr  # the listing agrees with the positions
    trajectory = pq.read_table(out / "trajectory.trajectory.parquet")
    np.testing.assert_allclose(positions(trajectory), LISTED, atol=1e-6)
    assert positions(trajectory)[-1] == pytest.approx(LISTED[-1], abs=1e-6)
    report = plain(out / "report.html")
    assert (
        "Tied at MD 500.00 m, TVD 498.30 m, N 12.10 m, E -3.40 m (from the stations file)" in report
    )
    assert (
        "Tie-in (first station) MD 500.00 m, TVD 498.30 m, N 12.10 m, E −3.40 m (from the stations file)"
        in report
    )
    (tie,) = json.loads((out / "summary.json").read_text())["calculation"]["ties"]
    assert tie == {
        "survey": None, "md": 500.0, "tvd": 498.3, "north": 12.1, "east": -3.4,
        "source": "stations file",
    }  # fmt: skip


def test_a_witsml_survey_is_tied_at_its_tie_in_point_per_survey(tmp_path: Path) -> None:
    """Two trajectories in one file: the one listing its positions starts at its tie-on,
    the one listing none below a vertical hole from the wellhead (TVD = MD)."""
    export = witsml_export(tmp_path, second_unlisted=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurveyCheckWarning)
        result = gp.run(SURVEY, export)
    trajectory = result.tables["trajectory.trajectory"]
    surveys = trajectory.column("survey").to_pylist()
    at = positions(trajectory)
    gyro = np.array([s == "gyro" for s in surveys])
    np.testing.assert_allclose(at[gyro], LISTED, atol=1e-6)
    np.testing.assert_allclose(at[~gyro], hand_positions(STATIONS, 500.0, 0.0, 0.0), atol=1e-6)
    calculation = calculation_of(trajectory)
    assert calculation is not None
    assert [(t.survey, t.source, t.tvd) for t in calculation.ties] == [
        ("gyro", "stations file", 498.3),
        ("bare", "pipeline", 500.0),
    ]
    # the Python function ties the same
    alone = gp.minimum_curvature(gp.read(witsml_export(tmp_path)))
    np.testing.assert_allclose(alone[["tvd", "north", "east"]].to_numpy(), LISTED, atol=1e-6)


def test_the_stages_own_tie_wins_and_a_different_one_is_warned(tmp_path: Path) -> None:
    listing = csv_listing(tmp_path)
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", SURVEY, "--input", listing, "--out", out, "--set", "report.formats=[html]",
        "--set", "trajectory.tie_tvd=499.0", "--set", "trajectory.tie_north=12.0",
        "--set", "trajectory.tie_east=-3.0",
    )  # fmt: skip
    assert result.returncode == 0, result.output
    trajectory = pq.read_table(out / "trajectory.trajectory.parquet")
    np.testing.assert_allclose(
        positions(trajectory), hand_positions(STATIONS, 499.0, 12.0, -3.0), atol=1e-6
    )
    gap = math.dist((499.0, 12.0, -3.0), TIE[1:])
    tie_warning = [line for line in result.stderr.splitlines() if "tie-on" in line]
    assert len(tie_warning) == 1, result.stderr
    assert f"{gap:.3f} m from the tie-on its stations file lists there" in tie_warning[0]
    assert "TVD 498.30 m, N 12.10 m, E -3.40 m" in tie_warning[0]
    report = plain(out / "report.html")
    assert "Tied at MD 500.00 m, TVD 499.00 m, N 12.00 m, E -3.00 m (from the pipeline)" in report
    # within position_tolerance of the file's: no word of it
    near = {"trajectory.tie_tvd": 498.35, "trajectory.tie_north": 12.1, "trajectory.tie_east": -3.4}
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurveyCheckWarning)
        gp.run(SURVEY, listing, set=near)


def _parquet_of(listing: Path, directory: Path, column: str, meta: dict[bytes, bytes]) -> Path:
    """The listing as a Parquet stations table whose ``column`` field states ``meta``."""
    table = gp.run(SURVEY, listing).tables["read.stations"]
    fields = [
        f.with_metadata({**(f.metadata or {}), **meta}) if f.name == column else f
        for f in table.schema
    ]
    path = directory / "listing.parquet"
    pq.write_table(pa.Table.from_arrays(table.columns, schema=pa.schema(fields)), path)
    return path


@pytest.mark.parametrize(
    ("column", "meta", "expected"),
    [
        ("north", {b"north_reference": b"grid"}, "referred to grid north but the azimuths to true"),
        ("tvd", {b"unit": b"ft"}, "the listed tvd is in 'ft', not m"),
    ],
)
def test_a_listing_in_another_north_or_unit_is_refused(
    tmp_path: Path, column: str, meta: dict[bytes, bytes], expected: str
) -> None:
    stations = _parquet_of(csv_listing(tmp_path), tmp_path, column, meta)
    result = gyropipe_cli("run", SURVEY, "--input", stations, "--out", tmp_path / "out")
    assert result.returncode != 0
    assert expected in result.stderr and str(stations) in result.stderr, result.stderr
    assert "Traceback" not in result.output
    with pytest.raises(StageError, match=expected) as raised:
        gp.minimum_curvature(gp.read(stations))
    assert isinstance(raised.value.__cause__, InputFileError)


DEFINITIVE = ROOT / "pipelines" / "definitive.yaml"
MWD = [STATIONS[-1], *((830.0 + 30.0 * k, 19.0 + 0.5 * k, 330.0 + 1.0 * k) for k in range(8))]
"""The MWD run from the gyro's last station (MD 800 m) down, listing no positions."""


def mwd_run(directory: Path) -> Path:
    path = directory / "mwd.csv"
    rows = [f"{md:.2f},{inc:.2f},{azi:.2f}" for md, inc, azi in MWD]
    header = HEADER.replace(",TVD (m),North (m),East (m)", "")
    path.write_text(header + "\n".join(rows) + "\n")
    return path


def test_the_definitive_survey_starts_at_its_top_runs_tie_on(tmp_path: Path) -> None:
    out = tmp_path / "out"
    gyro, mwd = csv_listing(tmp_path), mwd_run(tmp_path)
    result = gyropipe_cli(
        "run", DEFINITIVE, "--input", f"gyro={gyro}", "--input", f"mwd={mwd}", "--out", out,
        "--set", "report.formats=[html]",
    )  # fmt: skip
    assert result.returncode == 0, result.output
    assert "warning:" not in result.stderr
    survey = pq.read_table(out / "definitive.survey.parquet")
    np.testing.assert_allclose(
        positions(survey), hand_positions(STATIONS + MWD[1:], *TIE[1:]), atol=1e-6
    )
    words = "survey 'GYRO-1': Tied at MD 500.00 m, TVD 498.30 m, N 12.10 m, E -3.40 m (from the stations file)"
    assert words in plain(out / "report.html")
    # the stage's own tie wins, warned
    given = {"definitive.tie_tvd": 500.0, "definitive.tie_north": 0.0, "definitive.tie_east": 0.0}
    with pytest.warns(SurveyCheckWarning, match="from the tie-on its stations file lists there"):
        moved = gp.run(DEFINITIVE, {"gyro": gyro, "mwd": mwd}, set=given)
    np.testing.assert_allclose(
        positions(moved.tables["definitive.survey"]),
        hand_positions(STATIONS + MWD[1:], 500.0, 0.0, 0.0),
        atol=1e-6,
    )

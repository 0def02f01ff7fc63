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
import yaml

import pipeline as gp
from pipeline.errors import InputFileError, StageError, SurveyCheckWarning
from pipeline.survey.calculation import calculation_of
from tests_support import LISTING_HEADER, ROOT, gyropipe_cli

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
HEADER = LISTING_HEADER


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
        "source": "stations file", "parent": None,
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
    # one warning only: the tie-on's own uncertainty is not in the σ (tests/uncertainty/test_tie_on.py)
    warned = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warned) == 1 and "tie-on at 500.00 m MD" in warned[0], warned
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


MAIN = [(30.0 * k, max(0.0, 3.0 * (k - 5)), 40.0) for k in range(31)]
"""The main bore: vertical to 150 m, then building 3°/30 m at 40° azimuth to 900 m."""


def sidetrack_of(kop: float, inc: float, azi: float) -> list[tuple[float, float, float]]:
    """A sidetrack from MD ``kop`` at the main bore's ``inc``/``azi`` there (deg), dropping
    2° and turning 3° per 30 m station, eight stations."""
    return [(kop + 30.0 * j, inc - 2.0 * j, azi + 3.0 * j) for j in range(9)]


def listing(path: Path, surveys: dict[str, list[tuple[float, float, float]]]) -> Path:
    """A stations CSV (HEADER's well) of MD, inc, azi, with a Survey column where it lists
    more than one survey (a wellbore export: main bore, then sidetrack)."""
    head = HEADER.removesuffix("MD (m),Inc (deg),Azimuth True (deg),TVD (m),North (m),East (m)\n")
    named = len(surveys) > 1
    columns = ("Survey," if named else "") + "MD (m),Inc (deg),Azimuth True (deg)\n"
    rows = "".join(
        (f"{name}," if named else "") + f"{md:.4f},{i:.6f},{a:.6f}\n"
        for name, stations in surveys.items()
        for md, i, a in stations
    )
    path.write_text(head + columns + rows)
    return path


def hand_arc_point(
    station: tuple[float, float, float], below: tuple[float, float, float], md: float
) -> tuple[float, float, float, float, float]:
    """MD, inclination and azimuth (deg) on the circular arc between two stations at ``md``
    (the arc's tangent turned by the fraction f of the dogleg: slerp of the two tangents)."""
    (m1, i1, a1), (m2, i2, a2) = station, below
    t1, t2 = (
        np.array([math.sin(math.radians(i)) * math.cos(math.radians(a)),
                  math.sin(math.radians(i)) * math.sin(math.radians(a)),
                  math.cos(math.radians(i))])
        for i, a in ((i1, a1), (i2, a2))
    )  # fmt: skip
    beta = math.acos(float(np.clip(t1 @ t2, -1, 1)))
    f = (md - m1) / (m2 - m1)
    t = (math.sin((1 - f) * beta) * t1 + math.sin(f * beta) * t2) / math.sin(beta)
    inc = math.degrees(math.acos(t[2]))
    return md, inc, math.degrees(math.atan2(t[1], t[0])) % 360.0, f, beta


@pytest.mark.parametrize("kop", [600.0, 615.0], ids=["on-station", "between-stations"])
def test_a_sidetrack_listed_beside_its_main_bore_starts_on_it(tmp_path: Path, kop: float) -> None:
    """A wellbore export listing the main bore and a sidetrack kicking off at ``kop`` (no
    positions listed): the sidetrack starts where the main bore's minimum-curvature path is
    at that MD, worked out here by hand — it started at TVD = MD, N = E = 0 (a vertical hole
    from the wellhead, 100 m and more off) with only a warning; the tie is recorded and
    stated."""
    k = int(kop // 30)
    if kop % 30:
        md, inc, azi, _, _ = hand_arc_point(MAIN[k], MAIN[k + 1], kop)
        start = hand_positions(
            [MAIN[k], (md, inc, azi)], *hand_positions(MAIN[: k + 1], 0, 0, 0)[-1]
        )[-1]
    else:
        inc, azi = MAIN[k][1:]
        start = hand_positions(MAIN[: k + 1], 0.0, 0.0, 0.0)[-1]
    sidetrack = sidetrack_of(kop, inc, azi)
    path = listing(tmp_path / "wellbores.csv", {"MAIN": MAIN, "ST1": sidetrack})
    spec = yaml.safe_load(SURVEY.read_text())  # a LAS file holds one path: not written
    spec["stages"] = [st for st in spec["stages"] if st.get("with", {}).get("writer") != "las"]
    pipeline = tmp_path / "survey.yaml"
    pipeline.write_text(yaml.safe_dump(spec, sort_keys=False))
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run", pipeline, "--input", path, "--out", out, "--set", "report.formats=[html]"
    )  # fmt: skip
    assert result.returncode == 0, result.output
    assert "warning:" not in result.stderr  # (it warned that ST1 was detached from its hole)
    trajectory = pq.read_table(out / "trajectory.trajectory.parquet")
    st1 = np.asarray(trajectory.column("survey").to_pylist()) == "ST1"
    expected = hand_positions(sidetrack, *start)
    np.testing.assert_allclose(positions(trajectory)[st1], expected, atol=1e-6)
    main = hand_positions(MAIN, 0.0, 0.0, 0.0)  # the main bore as it was
    np.testing.assert_allclose(positions(trajectory)[~st1], main, atol=1e-6)
    ties = json.loads((out / "summary.json").read_text())["calculation"]["ties"]
    assert [t["source"] for t in ties] == ["pipeline", "survey"] and ties[1]["parent"] == "MAIN"
    assert (ties[1]["tvd"], ties[1]["north"], ties[1]["east"]) == pytest.approx(start, abs=1e-6)
    report = plain(out / "report.html")
    assert f"survey 'ST1': Tied at MD {kop:.2f} m, TVD {start[0]:.2f} m" in report
    assert "(on survey 'MAIN' at that MD)" in report
    table = gp.run(pipeline, {"stations": path}).tables["trajectory.trajectory"]
    np.testing.assert_allclose(positions(table)[st1], expected, atol=1e-6)


UNCERTAIN = """\
name: tied-uncertainty
version: "1.0"
inputs:
  stations: {description: stations}
stages:
  - id: read
    uses: read_stations
  - id: trajectory
    uses: minimum_curvature
    inputs: {stations: read.stations}
  - id: uncertainty
    uses: position_uncertainty
    inputs: {trajectory: trajectory.trajectory}
    with: {model: GYRO-NS}
    persist: [trajectory]
"""
COV = ["cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv"]


def test_a_sidetrack_carries_its_main_bores_uncertainty_at_the_kick_off(tmp_path: Path) -> None:
    """The sidetrack tied on its main bore at 600 m: its errors are those of the hole it
    was drilled from — the main bore's stations to the kick-off, then its own — as the
    listing of that hole alone (main bore above 600 m, sidetrack below) gives them; it was
    propagated from zero at the kick-off, as if that point were known exactly."""
    inc, azi = MAIN[20][1:]
    sidetrack = sidetrack_of(600.0, inc, azi)
    both = listing(tmp_path / "both.csv", {"MAIN": MAIN, "ST1": sidetrack})
    hole = listing(tmp_path / "hole.csv", {"HOLE": [*MAIN[:20], *sidetrack]})
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(UNCERTAIN)
    runs = {}
    for name, path in (("both", both), ("hole", hole)):
        result = gyropipe_cli("run", pipeline, "--input", path, "--out", tmp_path / name)
        assert result.returncode == 0, result.output
        runs[name] = pq.read_table(tmp_path / name / "uncertainty.trajectory.parquet").to_pylist()
    main = [r for r in runs["both"] if r["survey"] == "MAIN"]
    st1 = [r for r in runs["both"] if r["survey"] == "ST1"]
    for row, same in zip(st1, runs["hole"][20:], strict=True):
        assert row["md"] == same["md"]
        assert [row[c] for c in COV] == pytest.approx([same[c] for c in COV], rel=1e-9, abs=1e-12)
        assert [row[c] for c in ("tvd", "north", "east")] == pytest.approx(
            [same[c] for c in ("tvd", "north", "east")], abs=1e-6
        )
    (kop,) = (r for r in main if r["md"] == 600.0)
    assert st1[0]["ellipse_major"] == pytest.approx(kop["ellipse_major"], rel=1e-6)  # continuous
    assert kop["ellipse_major"] > 0.1  # m: not a point known exactly
    api = gp.run(pipeline, {"stations": both}).tables["uncertainty.trajectory"]
    assert api.column("cov_nn").to_pylist()[len(MAIN) :] == pytest.approx(
        [r["cov_nn"] for r in st1], rel=1e-12
    )

"""Cross-checks a survey engineer does by hand (issue 28, item 5): a stations file's own
TVD/north/east against the recomputed positions (a warning line, the report's method and
station flags), and courses longer than a tolerance flagged beside the short ones."""

from __future__ import annotations

import html
import json
import math
import re
import warnings
from pathlib import Path

import pytest

import pipeline as gp
from pipeline.errors import SurveyCheckWarning
from tests_support import ROOT, CliResult, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
HEADER = """\
Well: X-1
Latitude: 61.25
Longitude: 73.4
Survey Date: 2026-11-21

MD (m),Inc (deg),Azimuth True (deg),TVD (m),North (m),East (m)
"""
INC, AZI, STEP = 30.0, 45.0, 30.0
TURN = math.degrees(0.2)  # the azimuth changed by 0.2 rad


def hold_listing(directory: Path, turned_md: float | None = None) -> Path:
    """A straight hold at 30° inclination, 45° azimuth from the surface, every 30 m to
    600 m, with the vendor's positions (exact for a straight hole: TVD = MD cos I, north =
    east = MD sin I / √2), rounded to 0.01 m as a listing gives them; the azimuth of the
    station at ``turned_md`` changed by 0.2 rad (its positions kept)."""
    rows = []
    for k in range(21):
        md = k * STEP
        horizontal = md * math.sin(math.radians(INC)) / math.sqrt(2)
        azi = AZI + (TURN if md == turned_md else 0.0)
        tvd = md * math.cos(math.radians(INC))
        rows.append(f"{md:.2f},{INC:.2f},{azi:.4f},{tvd:.2f},{horizontal:.2f},{horizontal:.2f}")
    path = directory / ("turned.csv" if turned_md is not None else "hold.csv")
    path.write_text(HEADER + "\n".join(rows) + "\n")
    return path


def run(stations: Path, out: Path, *sets: str) -> CliResult:
    extra = [item for s in sets for item in ("--set", s)]
    return gyropipe_cli(
        "run", SURVEY, "--input", stations, "--out", out, "--set", "report.formats=[html]", *extra
    )


def listing_rows(report: Path) -> list[list[str]]:
    """The cells of each row of the report's survey listing, as text."""
    text = report.read_text()
    table = re.search(r'<table class="listing[^"]*">(.*?)</table>', text, re.S)
    assert table, "no survey listing in the report"
    rows = re.findall(r"<tr[^>]*>(.*?)</tr>", table.group(1), re.S)
    cells = [re.findall(r"<td[^>]*>(.*?)</td>", row, re.S) for row in rows]
    return [[html.unescape(re.sub(r"<[^>]+>", "", c)).strip() for c in row] for row in cells if row]


def plain(report: Path) -> str:
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", report.read_text())).split())


def test_a_changed_azimuth_is_caught_against_the_files_own_positions(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run(hold_listing(tmp_path, turned_md=300.0), out)
    assert result.returncode == 0, result.output
    warned = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warned) == 1, result.stderr
    # the turned course's chord swings by about half a course × sin I × 0.2 rad = 1.5 m
    first = re.search(r"first at MD (\d+\.\d+) m by (\d+\.\d+) m", warned[0])
    assert first and float(first.group(1)) == 300.0, warned[0]
    assert float(first.group(2)) == pytest.approx(0.5 * STEP * 0.5 * 0.2, rel=0.03)
    # every station below it is off by both turned courses (≈ 3.0 m): 11 of 21 stations
    worst = re.search(r"largest (\d+\.\d+) m at MD (\d+\.\d+) m", warned[0])
    assert worst and float(worst.group(1)) == pytest.approx(2 * 0.5 * STEP * 0.5 * 0.2, rel=0.03)
    assert "stage 'trajectory'" in warned[0] and "at 11 of 21 stations" in warned[0]

    report = out / "report.html"
    assert "disagree with the recomputed positions at 11 of 21 stations" in plain(report)
    flagged = {row[0] for row in listing_rows(report) if "position ≠ file" in row[-1]}
    assert flagged == {f"{k * STEP:.2f}" for k in range(10, 21)}
    assert result.stdout.splitlines()[-1] == (
        f"ok: {out / 'run.json'} — QC: 11 failed checks (file_positions: 11) at 11 stations"
    )

    with pytest.warns(SurveyCheckWarning, match="first at MD 300.00 m"):
        gp.run(SURVEY, hold_listing(tmp_path, turned_md=300.0))


def test_a_listing_that_agrees_passes_quietly_and_says_so(tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = run(hold_listing(tmp_path), out)
    assert result.returncode == 0, result.output
    assert "warning:" not in result.stderr
    text = plain(out / "report.html")
    assert "the file's own TVD/north/east at 21 stations agree with the recomputed" in text
    assert "within 0.1 m + 0.1 m per km of MD" in text
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurveyCheckWarning)
        gp.run(SURVEY, hold_listing(tmp_path))
    # a tighter tolerance than the listing's rounding is the user's to set
    strict = run(
        hold_listing(tmp_path),
        tmp_path / "strict",
        "trajectory.position_tolerance=0",
        "trajectory.position_tolerance_rel=0",
    )
    assert "warning: stage 'trajectory'" in strict.stderr


def test_a_long_first_course_is_flagged_beside_the_short_one(tmp_path: Path) -> None:
    """A 183 m first course after the tie-in and a 0.9 m course near TD."""
    stations = tmp_path / "gaps.csv"
    mds = [0.0, 183.0, *(183.0 + 30.0 * k for k in range(1, 8)), 393.9]
    rows = [f"{md:.2f},{min(md / 30.0, 12.0):.2f},120.00" for md in mds]
    stations.write_text(
        HEADER.split("MD (m)")[0] + "MD (m),Inc (deg),Azimuth True (deg)\n" + "\n".join(rows) + "\n"
    )
    out = tmp_path / "out"
    result = run(stations, out)
    assert result.returncode == 0, result.output
    rows_seen = {row[0]: row for row in listing_rows(out / "report.html")}
    assert rows_seen["183.00"][-1] == "long course"
    assert [md for md, row in rows_seen.items() if "long course" in row[-1]] == ["183.00"]
    text = plain(out / "report.html")
    assert "longer than 100 m: the hole between was not surveyed" in text
    assert "courses shorter than 10 m" in text  # the 0.9 m course, as before

    wider = run(stations, tmp_path / "wider", "report.max_course_length=200")
    assert wider.returncode == 0, wider.output
    assert "long course" not in plain(tmp_path / "wider" / "report.html")


def witsml_export(directory: Path, turned_md: float) -> Path:
    """The hold as a real export gives it: WITSML 1.4.1.1, angles in rad, the vendor's
    tvd/dispNs/dispEw, one azimuth changed by 0.2 rad."""
    stations = []
    for k in range(21):
        md = k * STEP
        horizontal = md * math.sin(math.radians(INC)) / math.sqrt(2)
        azi = math.radians(AZI) + (0.2 if md == turned_md else 0.0)
        stations.append(
            f'<trajectoryStation uid="s{k}"><md uom="m">{md}</md>'
            f'<tvd uom="m">{md * math.cos(math.radians(INC)):.2f}</tvd>'
            f'<incl uom="rad">{math.radians(INC):.10f}</incl><azi uom="rad">{azi:.10f}</azi>'
            f'<dispNs uom="m">{horizontal:.2f}</dispNs><dispEw uom="m">{horizontal:.2f}</dispEw>'
            "</trajectoryStation>"
        )
    path = directory / "export.xml"
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<trajectorys xmlns="http://www.witsml.org/schemas/1series" version="1.4.1.1">'
        '<trajectory uidWell="w" uidWellbore="b" uid="t"><nameWell>X-1</nameWell>'
        "<nameWellbore>X-1</nameWellbore><name>gyro</name><aziRef>true north</aziRef>"
        + "".join(stations)
        + "</trajectory></trajectorys>\n"
    )
    return path


def test_a_witsml_export_is_checked_against_its_own_positions(tmp_path: Path) -> None:
    export = witsml_export(tmp_path, turned_md=450.0)
    result = gyropipe_cli(
        "run",
        SURVEY,
        "--input",
        export,
        "--out",
        tmp_path / "out",
        "--set",
        "report.formats=[html]",
    )
    assert result.returncode == 0, result.output
    assert "first at MD 450.00 m by 1.4" in result.stderr
    assert "file_positions: 6" in result.stdout.splitlines()[-1]


def test_a_file_tied_elsewhere_is_tied_at_its_own_tie_on(tmp_path: Path) -> None:
    """A vertical listing from MD 500 m whose vendor placed its first station 0.5 m above
    MD, 3 m north and 2 m east: tied there, every station agrees (it was tied at TVD = MD,
    N = E = 0 and every station warned off by √(0.5² + 3² + 2²) m); the wellhead tie given
    to the stage is applied, both it and the stations off by that much warned."""
    rows = [f"{500 + 30 * k:.2f},0.00,0.00,{499.5 + 30 * k:.2f},3.00,2.00" for k in range(6)]
    listing = tmp_path / "tied.csv"
    listing.write_text(HEADER + "\n".join(rows) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", SurveyCheckWarning)
        gp.run(SURVEY, listing)
    tie = {"trajectory.tie_tvd": 500.0, "trajectory.tie_north": 0.0, "trajectory.tie_east": 0.0}
    with pytest.warns(SurveyCheckWarning) as caught:
        gp.run(SURVEY, listing, set=tie)
    gap = f"{math.sqrt(0.25 + 9 + 4):.3f} m"
    tied, check = (str(w.message) for w in caught)
    assert f"{gap} from the tie-on its stations file lists there" in tied
    assert f"first at MD 500.00 m by {gap}" in check


def test_the_summary_counts_the_file_positions_check_the_run_and_report_state(
    tmp_path: Path,
) -> None:
    # the command line and the report said 11 of 21 stations failed; summary.json said
    # "failed": 0, its one check (dls_limit) all passed
    out = tmp_path / "out"
    assert run(hold_listing(tmp_path, turned_md=300.0), out).returncode == 0
    qc = json.loads((out / "summary.json").read_text())["qc"]
    assert [c["check"] for c in qc["checks"]] == ["dls_limit", "file_positions"]
    assert qc["checks"][1] == {
        "check": "file_positions",
        "evaluated": 21,
        "passed": 10,
        "failed": 11,
        "not_evaluated": 0,
    }
    assert qc["failed"] == 11
    agreed = tmp_path / "agreed"
    assert run(hold_listing(tmp_path), agreed).returncode == 0
    checks = json.loads((agreed / "summary.json").read_text())["qc"]["checks"]
    assert checks[1] == {
        "check": "file_positions",
        "evaluated": 21,
        "passed": 21,
        "failed": 0,
        "not_evaluated": 0,
    }

"""Do a run's deliverables say the same thing? Read back every file a survey run wrote —
trajectory CSV/LAS/WITSML and persisted Parquet (``gp.read``), ``summary.json``,
``run.json``, ``processed.mcap`` (the mcap library) and the HTML report's fields — and
assert that what each states about the well, its north, its TD, its DLS, its uncertainty and
its QC is one statement."""

from __future__ import annotations

import html
import json
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
from mcap.reader import make_reader

import pipeline as gp

TRAJECTORY_FILES = ("trajectory.csv", "trajectory.las", "trajectory.xml")
NORTH_NAMES = {"true": "true north", "grid": "grid north", "magnetic": "magnetic north"}


def report_fields(report: Path) -> dict[str, str]:
    """Every ``<dt>label</dt><dd>value</dd>`` of an HTML report, text only (the first of a
    label kept), and ``verdict``: the summary's first verdict line."""
    text = report.read_text(encoding="utf-8")
    found: dict[str, str] = {}
    for label, value in re.findall(r"<dt>(.*?)</dt><dd>(.*?)</dd>", text, flags=re.S):
        found.setdefault(_plain(label), _plain(value))
    verdict = re.search(r'<p class="verdict [a-z]+">(.*?)</p>', text, flags=re.S)
    if verdict:
        found["verdict"] = _plain(verdict.group(1))
    return found


def report_blocks(report: Path) -> dict[str, dict[str, str]]:
    """The fields of each ``<h3>heading</h3><dl>…</dl>`` block of an HTML report."""
    text = report.read_text(encoding="utf-8")
    return {
        _plain(heading): {
            _plain(k): _plain(v) for k, v in re.findall(r"<dt>(.*?)</dt><dd>(.*?)</dd>", dl, re.S)
        }
        for heading, dl in re.findall(r"<h3>(.*?)</h3><dl>(.*?)</dl>", text, flags=re.S)
    }


def _plain(fragment: str) -> str:
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", "", fragment))).strip()


def _mcap(path: Path) -> tuple[dict[str, str], pa.Table | None]:
    """The well metadata record and the trajectory topic of a processed MCAP file."""
    with path.open("rb") as f:
        reader = make_reader(f)
        well = next(
            (dict(m.metadata) for m in reader.iter_metadata() if m.name == "gyropipe.well"), {}
        )
        tables = [
            pa.ipc.open_stream(schema.data + message.data).read_all()
            for schema, _, message in reader.iter_messages(topics=["/gyropipe/trajectory"])
            if schema is not None
        ]
    return well, (pa.concat_tables(tables) if tables else None)


LISTED = {
    "MD": "md",
    "INC": "inc",
    "AZI": "azi",
    "TVD": "tvd",
    "North": "north",
    "East": "east",
    "DLS": "dls",
    "VS": "vertical_section",
    "Semi-major": "ellipse_major_conf",
    "Semi-minor": "ellipse_minor_conf",
    "Major az": "ellipse_azimuth",
    "Vertical": "vertical_conf",
}
"""the survey listing's column headers → the trajectory's columns they show"""


def report_listing(report: Path) -> tuple[list[str], list[list[str]]]:
    """The survey listing's column headers (without their units) and cells, as text."""
    text = report.read_text(encoding="utf-8")
    table = re.search(r'<table class="listing">(.*?)</table>', text, flags=re.S)
    assert table, "no survey listing in the report"
    heads = re.findall(r"<th[^>]*>(.*?)<span", table.group(1), flags=re.S)
    rows = re.findall(r"<tr[^>]*>(.*?)</tr>", table.group(1).split("<tbody>")[1], flags=re.S)
    cells = [[_plain(c) for c in re.findall(r"<td[^>]*>(.*?)</td>", r, flags=re.S)] for r in rows]
    return [_plain(h) for h in heads], cells


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, float | int) and isinstance(b, float | int):
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-9)
    return str(a) == str(b)


def _number(text: str) -> float:
    return float(text.replace("−", "-").replace(",", ""))


def _at_dp(text: str, value: float, what: str) -> None:
    """``text`` is ``value`` at the decimals ``text`` shows."""
    dp = len(text.split(".")[1]) if "." in text else 0
    assert abs(_number(text) - value) <= 0.5 * 10**-dp + 1e-9, (
        f"{what}: report {text}, file {value}"
    )


def _wells(out: Path, files: tuple[str, ...]) -> Iterator[tuple[str, dict[str, Any]]]:
    """(file, the well metadata it states) for every deliverable that states one."""
    for name in files:
        if (out / name).exists():
            yield name, dict(gp.read(out / name).attrs["well"])
    for path in sorted(out.glob("*.parquet")):
        well = gp.read(path).attrs.get("well") if "trajectory" in path.name else None
        if well:
            yield path.name, dict(well)
    if (out / "summary.json").exists():
        doc = json.loads((out / "summary.json").read_text())
        yield "summary.json", {k: v for k, v in doc["well"].items() if v is not None}
    yield "run.json", json.loads((out / "run.json").read_text())["well"]
    if (out / "processed.mcap").exists():
        yield "processed.mcap", _mcap(out / "processed.mcap")[0]


def assert_wells_agree(out: Path, files: tuple[str, ...] = TRAJECTORY_FILES) -> dict[str, Any]:
    """Every deliverable states the same well metadata (a field one leaves out is not a
    disagreement; the MCAP record's strings compared as text), of the trajectory ``files``
    those read back. Returns run.json's."""
    stated = dict(_wells(out, files))
    run = stated["run.json"]
    for name, well in stated.items():
        for key in sorted(set(well) | set(run)):
            if key in well and key in run:
                mine, theirs = well[key], run[key]
                if name == "processed.mcap" and not isinstance(theirs, str):
                    theirs = json.dumps(theirs) if isinstance(theirs, bool) else str(theirs)
                assert _same(mine, theirs), f"{name} well.{key}={mine!r}, run.json {theirs!r}"
            else:
                assert name == "processed.mcap" or key not in run or key in well, (
                    f"{name} leaves out well.{key}={run[key]!r} that run.json states"
                )
    return run


def assert_north_agrees(
    out: Path, well: dict[str, Any], files: tuple[str, ...] = TRAJECTORY_FILES
) -> str:
    """Each trajectory file's azimuths, the summary and the report name the well's north."""
    north = str(well.get("north_reference"))
    for name in (*files, *(p.name for p in out.glob("*trajectory*.parquet"))):
        if (out / name).exists():
            assert gp.read(out / name).attrs["north_reference"] == north, name
    if (out / "summary.json").exists():
        assert json.loads((out / "summary.json").read_text())["north_reference"] == north
    if (out / "report.html").exists():
        assert report_fields(out / "report.html")["Azimuth reference"] == NORTH_NAMES[north]
    return north


def assert_report_agrees(out: Path, well: dict[str, Any], trajectory: str) -> None:
    """The report's well header, TD, closure, station count, maximum DLS, ellipse at TD and
    QC verdict read as the well metadata, ``trajectory`` (a persisted Parquet) and the
    summary state them, at the report's decimals."""
    fields = report_fields(out / "report.html")
    traj = gp.read(out / trajectory)
    for label, key in (("Latitude", "latitude"), ("Longitude", "longitude")):
        if key in well:
            value, hemisphere = fields[label].split("° ")
            sign = 1 if hemisphere in ("N", "E") else -1
            _at_dp(value, sign * well[key], label)  # the hemisphere letter carries the sign
    if "elevation" in well:
        _at_dp(fields["Datum elevation"].removesuffix(" m above MSL"), well["elevation"], "datum")
    if "depth_reference" in well:
        assert fields["Depth datum"] == well["depth_reference"]
    for label, key in (
        ("Magnetic declination", "declination"),
        ("Grid convergence", "grid_convergence"),
    ):
        if key in well:
            value, _, side = fields[label].partition("° ")
            _at_dp(value.rstrip("°"), -well[key] if side == "W" else well[key], label)
    assert fields["Stations"].split(" ")[0] == str(len(traj))
    blocks = report_blocks(out / "report.html")
    surveys = traj.groupby("survey", sort=False) if "survey" in traj else [(None, traj)]
    several = len(surveys) > 1
    for name, one in surveys:
        _assert_td(blocks[f"Results, survey {name}" if several else "Results"], one, well)
    heads, rows = report_listing(out / "report.html")
    assert len(rows) == len(traj), "listing rows"
    for i, head in enumerate(heads):
        if head in LISTED:
            for cell, value in zip((r[i] for r in rows), traj[LISTED[head]], strict=True):
                if cell[:1].isdigit() or cell[:1] == "−":  # not 'undefined'
                    _at_dp(cell, float(value), f"listing {head}")
    if (out / "summary.json").exists():
        doc = json.loads((out / "summary.json").read_text())
        assert doc["station_count"] == len(traj)
        assert len(doc["surveys"]) == len(surveys)
        for survey, (name, one) in zip(doc["surveys"], surveys, strict=True):
            results = blocks[f"Results, survey {name}" if several else "Results"]
            assert survey["survey"] == name and survey["station_count"] == len(one)
            _assert_summary_agrees(results, survey, one)
        _assert_qc_agrees(doc, fields.get("verdict"), len(traj))


def _assert_td(fields: dict[str, str], traj: Any, well: dict[str, Any]) -> None:
    """One survey's results at TD as its last station in the file."""
    last = traj.iloc[-1]
    _at_dp(fields["Total depth (MD)"].removesuffix(" m"), last["md"], "TD")
    _at_dp(fields["TVD at TD"].removesuffix(" m"), last["tvd"], "TVD at TD")
    north, east = fields["North / East at TD"].replace(" m", "").split(" / ")
    _at_dp(north, last["north"], "north at TD")
    _at_dp(east, last["east"], "east at TD")
    distance, direction = fields["Closure at TD"].split(" @ ")
    _at_dp(distance.removesuffix(" m"), last["closure_distance"], "closure")
    _at_dp(direction.split("°")[0], last["closure_direction"], "closure direction")
    assert direction.endswith(NORTH_NAMES[str(well["north_reference"])])


def _assert_summary_agrees(fields: dict[str, str], survey: dict[str, Any], traj: Any) -> None:
    """One survey's summary.json entry as its rows of the file and its report results."""
    final = survey["final"]
    for key in ("md", "tvd", "north", "east", "closure_distance", "closure_direction"):
        assert _same(final[key], float(traj.iloc[-1][key])), f"summary final.{key}"
    dls, at = fields["Maximum DLS"].split(" °/30 m at ")
    if "not counted" not in at:  # the report leaves short courses out, saying so
        _at_dp(dls, survey["max_dls"]["dls"], "max DLS")
        _at_dp(at.removesuffix(" m MD"), survey["max_dls"]["md"], "max DLS MD")
    td = survey["uncertainty_at_td"]
    label = next((k for k in fields if k.startswith("Ellipse semi-axes at TD")), None)
    assert (td is None) == (label is None), "ellipse at TD: stated by one of summary, report"
    if td is not None and label is not None:
        assert label == f"Ellipse semi-axes at TD ({100 * td['confidence']:.3g} %)"
        axes, vertical = fields[label].split(" m, vertical ± ")
        major, minor = axes.split(" × ")
        _at_dp(major, td["semi_major_conf"], "semi-major at TD")
        _at_dp(minor, td["semi_minor_conf"], "semi-minor at TD")
        _at_dp(vertical.removesuffix(" m"), td["vertical_conf"], "vertical at TD")


def _assert_qc_agrees(doc: dict[str, Any], verdict: str | None, stations: int) -> None:
    """summary.json's QC counts and the report's QC verdict say one thing."""
    qc = doc["qc"]
    if qc is not None and verdict is not None:
        clean = qc["failed"] == 0 and not qc.get("flagged_stations")
        assert verdict.startswith("QC: all") == clean, (verdict, qc)
        if qc.get("flagged_stations"):  # the report adds flags of its own (long course)
            count = re.search(rf"(\d+) of {stations} stations carry", verdict)
            assert count and int(count.group(1)) >= qc["flagged_stations"], (verdict, qc)


def assert_streams_agree(out: Path, trajectory: str) -> None:
    """The MCAP file's trajectory topic is the persisted ``trajectory`` Parquet, value for
    value and unit for unit; summary.json's vertical-section azimuth is the files'."""
    persisted = pq.read_table(out / trajectory)
    if (out / "processed.mcap").exists():
        streamed = _mcap(out / "processed.mcap")[1]
        assert streamed is not None, "processed.mcap has no trajectory topic"
        assert streamed.schema.equals(persisted.schema, check_metadata=True)
        for name in persisted.column_names:  # NaN (an undefined azimuth) is NaN in both
            a, b = (t.column(name).to_numpy(zero_copy_only=False) for t in (streamed, persisted))
            same = np.array_equal(a, b, equal_nan=a.dtype.kind == "f")
            assert same, f"processed.mcap trajectory.{name} ≠ {trajectory}"
    if (out / "summary.json").exists():
        stated = json.loads((out / "summary.json").read_text())["calculation"]
        recorded = (persisted.schema.metadata or {}).get(b"gyropipe.survey_calculation")
        assert stated == (json.loads(recorded) if recorded else None), "calculation"


def assert_deliverables_agree(
    out: Path, trajectory: str, files: tuple[str, ...] = TRAJECTORY_FILES
) -> dict[str, Any]:
    """Every check above on the run written to ``out``; ``trajectory``: the persisted
    Parquet the report and summary were made from; ``files``: the trajectory files read
    back. Returns the well run.json states."""
    well = assert_wells_agree(out, files)
    assert_north_agrees(out, well, files)
    assert_streams_agree(out, trajectory)
    if (out / "report.html").exists():
        assert_report_agrees(out, well, trajectory)
    return well

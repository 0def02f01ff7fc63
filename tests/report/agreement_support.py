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

import pyarrow as pa
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


def _wells(out: Path) -> Iterator[tuple[str, dict[str, Any]]]:
    """(file, the well metadata it states) for every deliverable that states one."""
    for name in TRAJECTORY_FILES:
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


def assert_wells_agree(out: Path) -> dict[str, Any]:
    """Every deliverable states the same well metadata (a field one leaves out is not a
    disagreement; the MCAP record's strings compared as text). Returns run.json's."""
    stated = dict(_wells(out))
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


def assert_north_agrees(out: Path, well: dict[str, Any]) -> str:
    """Each trajectory file's azimuths, the summary and the report name the well's north."""
    north = str(well.get("north_reference"))
    for name in (*TRAJECTORY_FILES, *(p.name for p in out.glob("*trajectory*.parquet"))):
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
    last = traj.iloc[-1]
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
            value, side = fields[label].split("° ")
            _at_dp(value, well[key] if side == "E" else -well[key], label)
    assert fields["Stations"].split(" ")[0] == str(len(traj))
    _at_dp(fields["Total depth (MD)"].removesuffix(" m"), last["md"], "TD")
    _at_dp(fields["TVD at TD"].removesuffix(" m"), last["tvd"], "TVD at TD")
    north, east = fields["North / East at TD"].replace(" m", "").split(" / ")
    _at_dp(north, last["north"], "north at TD")
    _at_dp(east, last["east"], "east at TD")
    distance, direction = fields["Closure at TD"].split(" @ ")
    _at_dp(distance.removesuffix(" m"), last["closure_distance"], "closure")
    _at_dp(direction.split("°")[0], last["closure_direction"], "closure direction")
    assert direction.endswith(NORTH_NAMES[str(well["north_reference"])])
    if (out / "summary.json").exists():
        _assert_summary_agrees(out, fields, traj)


def _assert_summary_agrees(out: Path, fields: dict[str, str], traj: Any) -> None:
    doc = json.loads((out / "summary.json").read_text())
    (survey,) = doc["surveys"]
    assert doc["station_count"] == survey["station_count"] == len(traj)
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
    qc = doc["qc"]
    if qc is not None and "verdict" in fields:
        verdict = fields["verdict"]
        clean = qc["failed"] == 0 and not qc.get("flagged_stations")
        assert verdict.startswith("QC: all") == clean, (verdict, qc)
        if qc.get("flagged_stations"):  # the report adds flags of its own (long course)
            count = re.search(r"(\d+) of \d+ stations carry", verdict)
            assert count and int(count.group(1)) >= qc["flagged_stations"], (verdict, qc)


def assert_deliverables_agree(out: Path, trajectory: str) -> dict[str, Any]:
    """Every check above on the run written to ``out``; ``trajectory``: the persisted
    Parquet the report and summary were made from. Returns the well run.json states."""
    well = assert_wells_agree(out)
    assert_north_agrees(out, well)
    if (out / "report.html").exists():
        assert_report_agrees(out, well, trajectory)
    return well

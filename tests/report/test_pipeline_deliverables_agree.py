"""Every shipped pipeline's deliverables state one survey: each pipeline is run once on its
example input (``gyropipe run`` in process), and every file it wrote is read back without
gyropipe's readers (:mod:`readback_support`: csv, a LAS line parser, xml.etree, pyarrow,
the mcap library, regular expressions over report.html, pdftotext) and compared with the
persisted Parquet table, at the precision each file prints: a machine export (CSV, LAS,
WITSML, MCAP) within half its unit's step (0.1 mm, 1e-6°, 1e-4 °/30 m, 1e-8 m²), the
report within half its last printed digit, and the report's listing printed to at least
0.01 m and 0.01°."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from agreement_support import LISTED as SURVEY_LISTED
from agreement_support import report_fields
from readback_support import (
    TO_CANONICAL,
    Column,
    Listing,
    arrow_listing,
    html_table,
    html_text,
    pdf_lines,
    pdf_text,
    read_csv,
    read_las,
    read_mcap,
    read_parquet,
    read_witsml,
)

import pipeline as gp
from tests_support import ROOT, gyropipe_cli

PIPELINES = ROOT / "pipelines"
EXAMPLES = ROOT / "examples"
STEP = {"m": 5e-5, "deg": 5e-7, "deg/30m": 5e-5, "m2": 5e-9}
"""canonical unit → the most a machine export may differ from the table (half its step)"""
LISTED = {**SURVEY_LISTED, "σ INC": "sigma_inc", "σ AZI": "sigma_azi"}
"""the report listing's column names → the table columns they show"""
LISTED_UNITS = {"m": "m", "°": "deg", "°/30 m": "deg/30m"}
"""the report listing's units (their first word) → canonical units"""
MIN_DECIMALS = {"md": 2, "tvd": 2, "north": 2, "east": 2, "vertical_section": 2, "inc": 2}
"""the fewest decimals the listing may print a column at: 1 cm, 0.01°"""
NORTH_WORDS = {"true": "true north", "grid": "grid north", "magnetic": "magnetic north"}
MIN_COURSE = 10.0
"""m: the shortest course whose DLS a maximum DLS counts (the report states the rule)"""


@dataclass(frozen=True)
class Job:
    """A shipped pipeline, its example inputs (made in ``work`` by ``inputs``) and the
    persisted table its trajectory files and report list."""

    pipeline: str
    inputs: Callable[[Path], list[str]]
    listing: str | None
    csv: str | None = "trajectory.csv"
    settings: tuple[str, ...] = ()
    status: int = 0


def _simulated(plan: str, made: str) -> Callable[[Path], list[str]]:
    def inputs(work: Path) -> list[str]:
        gyropipe_cli("simulate", EXAMPLES / "plans" / plan, "--out", work / "sim", check=True)
        return [str(work / "sim" / made)]

    return inputs


def _inout(work: Path) -> list[str]:
    from inout_support import simulated_runs

    runs = simulated_runs()
    for name in ("in", "bad"):
        gp.write(runs[name], work / f"{name}.csv")
    return [f"inrun={work / 'in.csv'}", f"outrun={work / 'bad.csv'}"]


JOBS = {
    "survey": Job(
        "survey", lambda _: [str(EXAMPLES / "stations-j-well.csv")], "trajectory.trajectory.parquet"
    ),
    "point-gyro": Job(
        "point-gyro",
        _simulated("short-j-well.yaml", "samples.parquet"),
        "uncertainty.trajectory.parquet",
    ),
    "point-gyro-readings": Job(
        "point-gyro-readings",
        lambda _: [str(EXAMPLES / "readings-j-well.csv")],
        "trajectory.trajectory.parquet",
    ),
    "continuous-gyro": Job(
        "continuous-gyro",
        _simulated("j-well-continuous.yaml", "samples.parquet"),
        "uncertainty.trajectory.parquet",
    ),
    "free-gyro": Job(
        "free-gyro",
        _simulated("j-well-free-gyro.yaml", "readings.parquet"),
        "trajectory.trajectory.parquet",
    ),
    "definitive": Job(
        "definitive",
        lambda _: [
            f"gyro={EXAMPLES / 'definitive' / 'gyro-run.csv'}",
            f"mwd={EXAMPLES / 'definitive' / 'mwd-run.csv'}",
        ],
        "definitive.survey.parquet",
        "definitive.csv",
    ),
    "inout-gyro": Job("inout-gyro", _inout, "definitive.survey.parquet", status=3),
    "clearance": Job(
        "clearance",
        lambda _: [
            f"reference={EXAMPLES / 'clearance' / 'reference.csv'}",
            f"offsets={EXAMPLES / 'clearance' / 'manifest.csv'}",
        ],
        "trajectory.trajectory.parquet",
        None,
        ("clearance.reference_model=ISCWSA-MWD-REV4", "clearance.reference_hole_diameter=0.9144"),
    ),
    "calibration": Job("calibration", lambda _: [str(EXAMPLES / "calibration-ig50.csv")], None),
}
SURVEYS = [name for name, job in JOBS.items() if job.listing]


@dataclass(frozen=True)
class Run:
    """A finished run: its output directory, what it printed, the persisted table its
    trajectory deliverables list (None: it lists none) and run.json's well."""

    out: Path
    stdout: str
    table: Path | None
    well: dict[str, Any]

    def listing(self) -> Listing:
        assert self.table is not None
        return read_parquet(self.table)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], Run]:
    """Each pipeline's run, made once when first asked for."""
    done: dict[str, Run] = {}

    def get(name: str) -> Run:
        if name not in done:
            job = JOBS[name]
            work = tmp_path_factory.mktemp(name)
            args = [a for given in job.inputs(work) for a in ("--input", given)]
            settings = [a for s in job.settings for a in ("--set", s)]
            out = work / "out"
            result = gyropipe_cli(
                "run", PIPELINES / f"{job.pipeline}.yaml", *args, "--out", out, *settings
            )
            assert result.returncode == job.status, result.stderr
            table = out / job.listing if job.listing else None
            well = json.loads((out / "run.json").read_text())["well"]
            done[name] = Run(out, result.stdout, table, well)
        return done[name]

    return get


def _close(a: float, b: float, tolerance: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= tolerance + 1e-12 * max(abs(a), abs(b))


def assert_columns_agree(reference: Listing, other: Listing, what: str) -> list[str]:
    """Every float column ``other`` shares with ``reference``, row by row, in canonical
    units, within half the step of a machine export. Returns the columns compared."""
    compared = []
    for name, column in other.columns.items():
        if name not in reference.columns or column.unit not in TO_CANONICAL:
            continue
        mine = reference.columns[name]
        unit = mine.unit
        assert TO_CANONICAL[unit] == 1.0, (name, unit)
        values = column.canonical()
        assert len(values) == len(mine.values), f"{what}: {len(values)} rows of {name}"
        for row, (a, b) in enumerate(zip(values, mine.values, strict=True)):
            assert _close(a, b, STEP[unit]), f"{what} {name} row {row}: {a} ≠ {b} {unit}"
        compared.append(name)
    return compared


def _decimals(text: str) -> int:
    return len(text.split(".")[1]) if "." in text else 0


def _at_dp(text: str, value: float, what: str) -> None:
    """``text`` states ``value`` at the decimals it prints."""
    stated = float(text.replace("−", "-").replace(",", ""))
    assert abs(stated - value) <= 0.5 * 10 ** -_decimals(text) + 1e-9, f"{what}: {text} ≠ {value}"


def report_listing(run: Run) -> dict[str, Column]:
    """The report's survey listing as columns (name → the table column it shows), each
    cell's text kept."""
    heads, rows = html_table(run.out / "report.html", "listing")
    columns = {}
    for i, (name, unit) in enumerate(heads):
        if name in LISTED:
            texts = [row[i] for row in rows]
            canonical = LISTED_UNITS.get(unit.split(",")[0].split(" ")[0].lstrip("±").strip())
            columns[LISTED[name]] = Column(canonical or unit, texts=texts)
            if LISTED[name] in ("azi", "ellipse_azimuth"):
                assert unit == f"° {run.well['north_reference']}", (name, unit)
    return columns


def _reference(run: Run, name: str) -> list[float]:
    """A column of the listed table, else of a persisted stations table beside it."""
    listing = run.listing()
    if name in listing.columns:
        return listing.columns[name].values
    for path in sorted(run.out.glob("*.stations.parquet")):
        table = read_parquet(path)
        if name in table.columns and len(table.columns[name].values) == len(
            listing.columns["md"].values
        ):
            return table.columns[name].values
    raise AssertionError(f"the report lists {name}, which no persisted table holds")


@pytest.mark.parametrize("name", SURVEYS)
def test_the_station_listings_agree(runs: Callable[[str], Run], name: str) -> None:
    run = runs(name)
    reference = run.listing()
    key = ["md", "inc", "azi", "tvd", "north", "east", "dls", "vertical_section"]
    csv = JOBS[name].csv
    if csv and (run.out / csv).exists():
        compared = assert_columns_agree(reference, read_csv(run.out / csv), csv)
        assert set(key) <= set(compared), (csv, compared)
    if (run.out / "trajectory.las").exists():
        compared = assert_columns_agree(reference, read_las(run.out / "trajectory.las"), "LAS")
        assert set(key) <= set(compared), compared
    if (run.out / "trajectory.xml").exists():
        compared = assert_columns_agree(reference, read_witsml(run.out / "trajectory.xml"), "XML")
        assert set(key) <= set(compared), compared
    if (run.out / "processed.mcap").exists():
        records, topics = read_mcap(run.out / "processed.mcap")
        streamed = arrow_listing(topics["/gyropipe/trajectory"])
        assert assert_columns_agree(reference, streamed, "MCAP") == list(reference.columns)
        units = records["gyropipe.units/trajectory"]
        assert {k: c.unit for k, c in reference.columns.items()} == {
            k: units[k] for k in reference.columns
        }
    assert_same_uncertainty_everywhere(run, csv)
    listed = report_listing(run)
    assert set(key) <= set(listed), sorted(listed)
    for column, shown in listed.items():
        values = _reference(run, column)
        assert len(shown.texts) == len(values), f"report listing: {len(shown.texts)} rows"
        for row, (text, value) in enumerate(zip(shown.texts, values, strict=True)):
            if text == "undefined":  # an azimuth NaN, its σ NaN or infinite
                assert not math.isfinite(value), f"report {column} row {row}: {value}"
                continue
            what = f"report listing {column} row {row}"
            _at_dp(text, value, what)
            assert _decimals(text) >= MIN_DECIMALS.get(column, 0), what
    assert_pdf_lists_the_html(run)


UNCERTAINTY_COLUMNS = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
"""columns that say a listing carries position uncertainty, the ones every trajectory format
holds (WITSML 1.4.1.1 has no ellipse element): a trajectory file without them beside one
with them would give a client σ in one deliverable and none in another"""


def assert_same_uncertainty_everywhere(run: Run, csv: str | None) -> None:
    """The run's trajectory files (CSV, LAS, WITSML) all carry the uncertainty columns
    the persisted listing holds, or none does."""
    held = {c for c in UNCERTAINTY_COLUMNS if c in run.listing().columns}
    files = {
        "CSV": (csv, read_csv),
        "LAS": ("trajectory.las", read_las),
        "XML": ("trajectory.xml", read_witsml),
    }
    for label, (name, read) in files.items():
        if name and (run.out / name).exists():
            found = {c for c in UNCERTAINTY_COLUMNS if c in read(run.out / name).columns}
            assert found == held, (label, sorted(found), sorted(held))


def assert_pdf_lists_the_html(run: Run) -> None:
    """Each row of the report's listing, in its numbers, is a line of the PDF (pdftotext
    keeps a table row on one line)."""
    pdf = run.out / "report.pdf"
    if not pdf.exists():
        return
    _, rows = html_table(run.out / "report.html", "listing")
    lines = [_numbers(line) for line in pdf_lines(pdf)]
    for row in rows:
        numbers = _numbers(" ".join(row))
        assert any(line[: len(numbers)] == numbers for line in lines), f"PDF lacks row {row}"


def _numbers(text: str) -> list[str]:
    return re.findall(r"(?<![\w.])[−-]?\d+(?:\.\d+)?(?![\w.])", text)


def _calculation(run: Run) -> dict[str, Any]:
    recorded = read_parquet(run.table).header.get("gyropipe.survey_calculation")
    return json.loads(recorded) if recorded else {}


def _stated(run: Run) -> Iterator[tuple[str, str, object]]:
    """(file, quantity, what it states) for the well, north and vertical-section azimuth of
    every deliverable that states them."""
    out = run.out
    for name in ("trajectory.csv", "definitive.csv", "clearance.csv"):
        if (out / name).exists():
            header = read_csv(out / name).header
            for key, value in header.items():
                if key.startswith("well."):
                    yield name, key.removeprefix("well."), value
            if "north_reference" in header:
                yield name, "north_reference", header["north_reference"]
            if "vs_azimuth" in header:
                yield name, "vs_azimuth", header["vs_azimuth"].removesuffix(" deg")
            for key in ("confidence", "error_model"):
                if key in header:
                    yield name, key, header[key]
    if (out / "trajectory.las").exists():
        las = read_las(out / "trajectory.las").header
        for mnemonic, key in (
            ("WELL", "well"),
            ("LATI", "latitude"),
            ("LONG", "longitude"),
            ("DATE", "survey_date"),
            ("EREF", "elevation"),
            ("TOOL", "tool_type"),
            ("TOOLSN", "tool_serial"),
            ("NREF", "north_reference"),
            ("DECL", "declination"),
            ("GRIDCONV", "grid_convergence"),
            ("DECLUSED", "declination_applied"),
            ("GRIDUSED", "grid_convergence_applied"),
            ("VSAZ", "vs_azimuth"),
            ("CONF", "confidence"),
            ("ERRMODEL", "error_model"),
        ):
            if las.get(mnemonic):
                yield "LAS", key, las[mnemonic]
    if (out / "trajectory.xml").exists():
        xml = read_witsml(out / "trajectory.xml").header
        yield "XML", "well", xml["nameWell"]
        yield "XML", "north_reference", xml["aziRef"].removesuffix(" north")
        yield "XML", "vs_azimuth", xml["aziVertSect"]
        yield "XML", "survey_date", xml["dTimTrajStart"][:10]
        for tag, key in (
            ("magDeclUsed", "declination_applied"),
            ("gridCorUsed", "grid_convergence_applied"),
        ):
            if tag in xml:
                yield "XML", key, xml[tag]
    if (out / "summary.json").exists():
        doc = json.loads((out / "summary.json").read_text())
        for key, value in doc["well"].items():
            if value is not None:
                yield "summary.json", key, value
        yield "summary.json", "north_reference", doc["north_reference"]
        if doc.get("calculation"):
            yield "summary.json", "vs_azimuth", doc["calculation"]["vs_azimuth"]
        if doc.get("uncertainty"):
            yield "summary.json", "error_model", doc["uncertainty"]["error_model"]
            yield "summary.json", "confidence", doc["uncertainty"]["confidence"]
    if (out / "processed.mcap").exists():
        records, _ = read_mcap(out / "processed.mcap")
        for key, value in records["gyropipe.well"].items():
            yield "MCAP", key, value
    for key, value in run.well.items():
        yield "run.json", key, value
    calculation = _calculation(run)
    if calculation:
        yield "Parquet", "vs_azimuth", calculation["vs_azimuth"]


def _same(a: object, b: object) -> bool:
    try:
        return math.isclose(float(str(a)), float(str(b)), rel_tol=1e-9, abs_tol=1e-9)
    except ValueError:
        return str(a) == str(b)


@pytest.mark.parametrize("name", SURVEYS)
def test_the_headers_agree(runs: Callable[[str], Run], name: str) -> None:
    run = runs(name)
    stated: dict[str, dict[str, object]] = {}
    for file, key, value in _stated(run):
        stated.setdefault(key, {})[file] = value
    for key, by_file in stated.items():
        values = list(by_file.values())
        assert all(_same(v, values[0]) for v in values), f"{key}: {by_file}"
    fields = report_fields(run.out / "report.html")
    well = run.well
    assert fields["Well"] == well["well"]
    for label, key in (("Latitude", "latitude"), ("Longitude", "longitude")):
        if key in well:
            value, side = fields[label].split("° ")
            _at_dp(value, well[key] * (1 if side in "NE" else -1), label)
    if "survey_date" in well:
        assert fields["Survey date"] == well["survey_date"]
    if "tool_type" in well and name != "definitive":
        assert fields["Tool type"] == well["tool_type"]
    north = pq.read_schema(run.table).field("azi").metadata[b"north_reference"].decode()
    assert all(_same(v, north) for v in stated.get("north_reference", {}).values()), north
    assert fields["Azimuth reference"] == NORTH_WORDS[north]
    vs = stated.get("vs_azimuth")
    if vs:
        value, words = fields["Vertical section azimuth"].split("° ")
        _at_dp(value, float(str(next(iter(vs.values())))), "vertical section azimuth")
        assert words == fields["Azimuth reference"]
    listing = run.listing()
    md = listing.columns["md"].values
    count, span = fields["Stations"].split(" ", 1)
    assert int(count) == len(md)
    first, last = span.strip("()").removesuffix(" m MD").split(" – ")
    _at_dp(first, md[0], "first MD")
    _at_dp(last, md[-1], "last MD")
    text = html_text(run.out / "report.html")
    for model in stated.get("error_model", {}).values():
        assert f"Error model {model}." in text, model
    for confidence in stated.get("confidence", {}).values():
        assert f"at {100 * float(str(confidence)):g} % confidence" in text


def _max_dls(md: list[float], dls: list[float]) -> tuple[float, float]:
    """(DLS, MD) of the largest DLS over the courses of at least MIN_COURSE m (the first
    of equal ones)."""
    counted = [
        (d, m) for m0, m, d in zip(md, md[1:], dls[1:], strict=False) if m - m0 >= MIN_COURSE - 1e-6
    ]
    return max(counted, key=lambda found: found[0])


@pytest.mark.parametrize("name", SURVEYS)
def test_the_results_at_td_agree(runs: Callable[[str], Run], name: str) -> None:
    run = runs(name)
    c = {k: col.values for k, col in run.listing().columns.items()}
    fields = report_fields(run.out / "report.html")
    pdf = pdf_text(run.out / "report.pdf") if (run.out / "report.pdf").exists() else None
    for label in (
        "Total depth (MD)",
        "TVD at TD",
        "North / East at TD",
        "Closure at TD",
        "Maximum DLS",
        "Vertical section at TD",
    ):
        assert pdf is None or f"{label} {fields[label]}" in pdf, label
    _at_dp(fields["Total depth (MD)"].removesuffix(" m"), c["md"][-1], "TD")
    _at_dp(fields["TVD at TD"].removesuffix(" m"), c["tvd"][-1], "TVD at TD")
    north, east = fields["North / East at TD"].replace(" m", "").split(" / ")
    _at_dp(north, c["north"][-1], "north at TD")
    _at_dp(east, c["east"][-1], "east at TD")
    closure = math.hypot(c["north"][-1], c["east"][-1])
    direction = math.degrees(math.atan2(c["east"][-1], c["north"][-1])) % 360.0
    distance, towards = fields["Closure at TD"].split(" m @ ")
    _at_dp(distance, closure, "closure")
    _at_dp(towards.split("°")[0], direction, "closure direction")
    _at_dp(fields["Vertical section at TD"].removesuffix(" m"), c["vertical_section"][-1], "VS")
    dls, at = _max_dls(c["md"], c["dls"])
    stated, where = fields["Maximum DLS"].split(" °/30 m at ")
    _at_dp(stated, dls, "max DLS")
    _at_dp(where.split(" m MD")[0], at, "max DLS MD")
    if (run.out / "summary.json").exists():
        (survey,) = json.loads((run.out / "summary.json").read_text())["surveys"]
        final = survey["final"]
        for key, value in (("md", c["md"][-1]), ("tvd", c["tvd"][-1]), ("north", c["north"][-1])):
            assert _same(final[key], value), key
        assert final["closure_distance"] == pytest.approx(closure, abs=1e-9)
        assert final["closure_direction"] == pytest.approx(direction, abs=1e-9)
        assert (survey["max_dls"]["dls"], survey["max_dls"]["md"]) == (dls, at)
        assert survey["max_dls"]["min_course_length"] == MIN_COURSE
    assert_uncertainty_agrees(run, c, fields)


def assert_uncertainty_agrees(run: Run, c: dict[str, list[float]], fields: dict[str, str]) -> None:
    """The ellipse at TD and the largest, as the table, summary.json and report state them."""
    if "ellipse_major_conf" not in c:
        return
    text = html_text(run.out / "report.html")
    major, one = c["ellipse_major_conf"], c["ellipse_major"]
    largest = int(np.nanargmax(major))
    found = re.search(
        r"Largest horizontal semi-major axis: ([\d.]+) m at ([\d.]+) % confidence, ([\d.]+) m at "
        r"1σ, at ([\d.]+) m MD; at TD: ([\d.]+) m at [\d.]+ % confidence, ([\d.]+) m at 1σ, at "
        r"([\d.]+) m MD",
        text,
    )
    assert found, "the report states no largest ellipse"
    for text_, value in zip(
        found.groups(),
        [major[largest], math.nan, one[largest], c["md"][largest], major[-1], one[-1], c["md"][-1]],
        strict=True,
    ):
        if not math.isnan(value):
            _at_dp(text_, value, "largest / TD ellipse")
    label = next(k for k in fields if k.startswith("Ellipse semi-axes at TD"))
    axes, vertical = fields[label].split(" m, vertical ± ")
    a, b = axes.split(" × ")
    _at_dp(a, major[-1], "semi-major at TD")
    _at_dp(b, c["ellipse_minor_conf"][-1], "semi-minor at TD")
    _at_dp(vertical.removesuffix(" m"), c["vertical_conf"][-1], "vertical at TD")
    if (run.out / "summary.json").exists():
        doc = json.loads((run.out / "summary.json").read_text())
        confidence = doc["uncertainty"]["confidence"]
        assert label == f"Ellipse semi-axes at TD ({100 * confidence:g} %)"
        assert f"{found.group(2)} %" == f"{100 * confidence:g} %"
        big = doc["uncertainty"]["largest"]
        assert (big["md"], big["semi_major_conf"]) == (c["md"][largest], major[largest])
        td = doc["surveys"][0]["uncertainty_at_td"]
        assert (td["semi_major_conf"], td["semi_major"]) == (major[-1], one[-1])


@pytest.mark.parametrize("name", ["survey", "point-gyro", "continuous-gyro", "free-gyro"])
def test_the_qc_verdicts_agree(runs: Callable[[str], Run], name: str) -> None:
    """The command line's ``QC:`` line, summary.json's counts and the report's verdict and
    QC tables."""
    run = runs(name)
    qc = json.loads((run.out / "summary.json").read_text())["qc"]
    text = html_text(run.out / "report.html")
    verdict = re.search(r"QC: (.*?\.) ", text)
    assert verdict, "the report states no QC verdict"
    last = run.stdout.strip().splitlines()[-1]
    said = re.search(r"QC: (all (\d+) checks passed|(\d+) failed checks)", last)
    evaluated = sum(check["evaluated"] for check in qc["checks"]) if qc else 0
    assert (said is None) == (evaluated == 0), last  # the line counts checks, not flags
    assert qc is not None, "summary.json states no QC"
    if said and said.group(2):
        assert int(said.group(2)) == evaluated and qc["failed"] == 0
    elif said:
        assert int(said.group(3)) == qc["failed"] > 0
    assert verdict.group(1).startswith(("all", "no station failed")) == (qc["failed"] == 0)
    flagged = re.search(r"(\d+) of (\d+) stations carry processing flags", verdict.group(1))
    if name == "free-gyro":  # the report flags each station read once: not compared in/out
        stations = json.loads((run.out / "summary.json").read_text())["surveys"][0]["station_count"]
        compared = {c["check"]: c for c in qc["checks"]}["in_out_inclination"]["evaluated"]
        assert flagged and int(flagged.group(1)) == stations - compared > 0, verdict.group(1)
    else:
        assert (flagged is None) == (not qc["flagged_stations"]), (verdict.group(1), qc)
    if flagged and qc["flagged_stations"]:  # the report adds flags of its own (long course)
        assert int(flagged.group(1)) >= qc["flagged_stations"]
    table = {check["check"]: check for check in qc["checks"] if check["evaluated"]}
    if not table:
        return
    _, rows = html_table(run.out / "report.html", "qc")
    assert len(rows) == len(table), (rows, sorted(table))
    assert sorted(tuple(map(int, r[2:5])) for r in rows) == sorted(
        (c["evaluated"], c["passed"], c["failed"]) for c in table.values()
    )


def test_the_drift_applied_agrees(runs: Callable[[str], Run]) -> None:
    """free-gyro: the rate summary.json states, the one the corrected readings record and
    apply, and the report's."""
    run = runs("free-gyro")
    drift = json.loads((run.out / "summary.json").read_text())["drift"]
    readings = pq.read_table(run.out / "drift.readings.parquet").to_pydict()
    assert set(readings["drift_rate"]) == {drift["rate"]}
    assert set(readings["sigma_drift_rate"]) == {drift["sigma"]}
    hours = [(t - readings["time"][0]) / 3600.0 for t in readings["time"]]
    for raw, corrected, h in zip(readings["azi_raw"], readings["azi"], hours, strict=True):
        assert (raw - drift["rate"] * h - corrected + 180.0) % 360.0 - 180.0 == pytest.approx(
            0.0, abs=1e-6
        )
    text = html_text(run.out / "report.html")
    found = re.search(r"drift rate ([\d.]+) °/h, σ ([\d.]+) °/h", text)
    assert found, "the report states no drift rate"
    _at_dp(found.group(1), drift["rate"], "drift rate")
    _at_dp(found.group(2), drift["sigma"], "drift σ")
    assert "misclosure at the tie-in station" in text and drift["source"] == "tie_in"


def test_the_separation_factors_agree(runs: Callable[[str], Run]) -> None:
    """clearance: each offset's least SF (at stations and between them) and where, in the
    Parquet table, clearance.csv and the report; the summary sentence names the least."""
    run = runs("clearance")
    table = pq.read_table(run.out / "clearance.clearance.parquet").to_pylist()
    written = read_csv(run.out / "clearance.csv")
    assert [float(t) for t in written.columns["sf"].texts] == pytest.approx(
        [r["sf"] for r in table], rel=1e-12
    )
    _, rows = html_table(run.out / "report.html", "clearance")
    least: tuple[float, str, float] | None = None
    for row in rows:
        mine = [r for r in table if r["offset"] == row[0]]
        at = min(mine, key=lambda r: r["sf"])
        between = min(mine, key=lambda r: r["sf_between"])
        _at_dp(row[3], at["sf"], f"{row[0]} SF")
        _at_dp(row[4], at["md"], f"{row[0]} reference MD")
        _at_dp(row[5], at["offset_md"], f"{row[0]} offset MD")
        _at_dp(row[6], at["distance"], f"{row[0]} distance")
        _at_dp(row[7], between["sf_between"], f"{row[0]} SF between")
        _at_dp(row[8], between["md_between"], f"{row[0]} MD between")
        if least is None or between["sf_between"] < least[0]:
            least = (between["sf_between"], row[0], between["md_between"])
    assert least is not None and len(rows) == len({r["offset"] for r in table})
    sentence = re.search(
        r"minimum separation factor ([\d.]+) against (\S+) at ([\d.]+) m MD",
        html_text(run.out / "report.html"),
    )
    assert sentence, "the report states no minimum SF"
    _at_dp(sentence.group(1), least[0], "minimum SF")
    assert sentence.group(2) == least[1]
    _at_dp(sentence.group(3), least[2], "minimum SF MD")


def test_the_calibration_estimates_agree(runs: Callable[[str], Run]) -> None:
    """calibration: every estimate's rate, σ, interval and the one used, in the Parquet
    table, drift-calibration.csv and the report."""
    run = runs("calibration")
    table = pq.read_table(run.out / "drift.result.parquet").to_pylist()
    written = read_csv(run.out / "drift-calibration.csv").columns
    for key in ("drift_deg_h", "sigma_deg_h", "drift_deg_min", "interval"):
        for row, (text, r) in enumerate(zip(written[key].texts, table, strict=True)):
            assert _close(float(text), r[key], 5e-7), (key, row)
    _, rows = html_table(run.out / "report.html", "estimates")
    assert len(rows) == len(table)
    for row, r in zip(rows, table, strict=True):
        assert row[:2] == [r["method"], r["label"]]
        for text, value in zip(
            row[2:7],
            [
                r["drift_deg_h"],
                r["sigma_deg_h"],
                r["drift_deg_min"],
                r["sigma_deg_min"],
                r["interval"] / 60,
            ],
            strict=True,
        ):
            _at_dp(text, value, f"{r['method']} {r['label']}")
        assert (row[8] == "selected") == r["selected"]
    (used,) = [r for r in table if r["selected"]]
    text = html_text(run.out / "report.html")
    found = re.search(r"Drift \((\w+)\) ([\d.]+) ± ([\d.]+) °/h", text)
    assert found and found.group(1) == used["method"]
    _at_dp(found.group(2), used["drift_deg_h"], "drift used")
    _at_dp(found.group(3), used["sigma_deg_h"], "σ used")


def test_the_acceptance_gates_agree(runs: Callable[[str], Run]) -> None:
    """inout-gyro: each gate's status and value in the Parquet table, run.json, the command
    line and the report."""
    run = runs("inout-gyro")
    gates = pq.read_table(run.out / "gates.gates.parquet").to_pylist()
    recorded = {
        g["gate"]: g for g in json.loads((run.out / "run.json").read_text())["acceptance"]["gates"]
    }
    printed = {
        line.split()[0]: line.split()
        for line in run.stdout.splitlines()
        if line.strip().startswith("gates.")
    }
    text = html_text(run.out / "report.html")
    for gate in gates:
        stated = recorded[gate["gate"]]
        assert stated["status"] == gate["status"]
        assert _same(stated["value"] if stated["value"] is not None else "nan", gate["value"]) or (
            stated["value"] is None and math.isnan(gate["value"])
        )
        assert printed[f"gates.{gate['gate']}"][1] == gate["status"]
    failed = [g for g in gates if g["status"] == "fail"]
    assert failed and ("FAIL" in text or "fail" in text)

"""The fleet page (``OUT/fleet.html`` of every batch, ``gyropipe status DIR --html``,
``gp.fleet_page``): a 40-well batch with failed and rejected wells, rendered in headless
Chromium and screenshotted; its figures checked against the published tables read here
with pyarrow, its links against the files on disk."""

from __future__ import annotations

import csv
import html
import json
import re
import shutil
import urllib.parse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
from report_support import DICHROMACY, closest_colours

import pipeline as gp
from tests_support import ROOT, gyropipe_cli, stage, without_report, write_pipeline

STATIONS = ROOT / "examples" / "stations-j-well.csv"
WELLS = [f"W-{k:02d}" for k in range(40)]
BROKEN = {"W-07": "broken.csv", "W-20": "x<b>&y.csv", "W-33": "missing.csv"}
"""wells whose in-run file lost a cell of its 15th station (or does not exist)"""
REJECTED = {"W-04", "W-13", "W-22", "W-31"}
"""wells whose out-run azimuths are 2.5° off: the azimuth gate fails"""
KINKED = {"W-03", "W-15"}
"""wells with a 12° inclination kink at one station (in both runs): dogleg checks fail"""
DLS_LIMIT = 10.0
ROW_CELLS = """() => Array.from(document.querySelectorAll('table.wells tbody tr')).map(r => ({
  cls: r.className,
  cells: Array.from(r.cells).map(c => c.innerText.trim()),
  links: Array.from(r.querySelectorAll('a')).map(a => a.getAttribute('href')),
}))"""
COLOURS = """() => ['done', 'rejected', 'failed', 'interrupted', 'skipped', 'not-run'].map(s => {
  const probe = document.createElement('span');
  probe.className = 's-' + s;
  document.querySelector('.bar').appendChild(probe);
  return getComputedStyle(probe).backgroundColor;
})"""
"""the bar's colour of each status (a probe segment of each)"""
HEADS = """() => Array.from(document.querySelectorAll('table.wells thead th'))
  .map(c => c.innerText.trim())"""


def fleet_pipeline(directory: Path) -> Path:
    """In-run and out-run of a well and its offset wells: acceptance gates, definitive
    survey, dogleg check, clearance and an HTML report."""
    stages = [
        stage("read_in", "read_stations", input="inrun"),
        stage("read_out", "read_stations", input="outrun"),
        stage("offsets", "read_offsets", input="offsets"),
        stage(
            "gates",
            "acceptance_gates",
            {"inrun": "read_in.stations", "outrun": "read_out.stations"},
            ["gates"],
        ),
        stage(
            "definitive",
            "definitive_survey",
            {"run1": "read_in.stations", "run2": "read_out.stations"},
            ["survey"],
            runs={
                "run1": {"name": "in-run", "priority": 1},
                "run2": {"name": "out", "priority": 0},
            },
        ),
        stage(
            "dls",
            "check",
            {"table": "definitive.survey"},
            ["results"],
            check="dls_limit",
            params={"limit": DLS_LIMIT},
        ),
        stage(
            "clearance",
            "clearance",
            {
                "reference": "read_in.stations",
                "offsets": "offsets.stations",
                "wells": "offsets.wells",
            },
            ["clearance"],
            reference_hole_diameter=0.3112,
        ),
        stage(
            "report",
            "report",
            {
                "trajectory": "definitive.survey",
                "gates": "gates.gates",
                "clearance": "clearance.clearance",
                "checks": "dls.results",
            },
            formats=["html"],
        ),
    ]
    return write_pipeline(directory, stages, name="fleet", inputs=("inrun", "outrun", "offsets"))


def station_files(directory: Path) -> None:
    """in.csv, its kinked copy, out-runs of both (0.3° off, 2.5° off), a broken in-run."""
    lines = STATIONS.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))

    def write(name: str, rows: list[str]) -> None:
        (directory / name).write_text("\n".join(rows) + "\n")

    def shifted(rows: list[str], degrees: float) -> list[str]:
        out = rows[: header + 1]
        for row in rows[header + 1 :]:
            md, inc, azi = row.split(",")
            out.append(f"{md},{inc},{(float(azi) + degrees) % 360:.2f}")
        return out

    kinked = list(lines)
    md, inc, azi = kinked[header + 40].split(",")
    kinked[header + 40] = f"{md},{float(inc) + 12:.2f},{azi}"
    broken = list(lines)
    broken[header + 15] = ",".join(broken[header + 15].split(",")[:2])
    write("in.csv", lines)
    write("in-kinked.csv", kinked)
    write("out.csv", shifted(lines, 0.3))
    write("out-kinked.csv", shifted(kinked, 0.3))
    write("out-off.csv", shifted(lines, 2.5))
    write("broken.csv", broken)
    write("x<b>&y.csv", broken)


def manifest(directory: Path, wells: list[str]) -> Path:
    """The batch manifest; each well's offset manifest: one offset well (the same survey)
    at its own distance north of the slot (40 m + 12 m per well number)."""
    rows = ["well_id,inrun,outrun,offsets"]
    for well in wells:
        k = int(well[2:])
        offsets = directory / f"offsets-{well}.csv"
        offsets.write_text(
            "well_id,file,model,hole_diameter (in),north (m),east (m)\n"
            f"N-{k},in.csv,GYRO-NS,12.25,{40 + 12 * k},0\n"
        )
        kink = "-kinked" if well in KINKED else ""
        inrun = BROKEN.get(well, f"in{kink}.csv")
        outrun = "out-off.csv" if well in REJECTED else f"out{kink}.csv"
        rows.append(f"{well},{inrun},{outrun},{offsets.name}")
    path = directory / "wells.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


@dataclass
class Batch:
    out: Path
    stdout: str
    page: Path
    rows: list[dict[str, Any]]
    heads: list[str]
    requests: list[str]
    errors: list[str]
    screenshot: Path


def render(browser: Any, page_file: Path, screenshot: Path) -> tuple[Any, ...]:
    page = browser.new_page()
    page.set_viewport_size({"width": 1400, "height": 900})
    requests: list[str] = []
    errors: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(page_file.resolve().as_uri(), wait_until="load")
    rows, heads = page.evaluate(ROW_CELLS), page.evaluate(HEADS)
    page.screenshot(path=str(screenshot), full_page=True)
    page.close()
    return rows, heads, requests, errors


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory, browser: Any) -> Batch:
    """The 40-well batch (2 workers) and its fleet page as Chromium shows it."""
    root = tmp_path_factory.mktemp("fleet")
    wells = root / "wells"
    wells.mkdir()
    station_files(wells)
    pipeline = fleet_pipeline(root)
    out = root / "out"
    args = ["batch", pipeline, "--manifest", manifest(wells, WELLS), "--out", out]
    result = gyropipe_cli(*args, "--workers", "2")
    assert result.returncode == 1, result.stderr  # some wells failed
    screenshot = root / "fleet.png"
    rows, heads, requests, errors = render(browser, out / "fleet.html", screenshot)
    return Batch(out, result.stdout, out / "fleet.html", rows, heads, requests, errors, screenshot)


def by_well(batch: Batch) -> dict[str, dict[str, str]]:
    return {r["cells"][0]: dict(zip(batch.heads, r["cells"], strict=True)) for r in batch.rows}


def test_the_batch_writes_the_page_beside_its_summary(batch: Batch) -> None:
    assert batch.page.is_file()
    assert str(batch.page) in batch.stdout  # listed with the summary files
    assert batch.errors == []
    assert batch.requests == [batch.page.resolve().as_uri()]  # nothing fetched: offline
    source = batch.page.read_text(encoding="utf-8")
    assert "<script" not in source and "<img" not in source and "url(" not in source
    assert batch.screenshot.stat().st_size > 10_000
    assert len(batch.rows) == 40


def test_failing_wells_come_first(batch: Batch) -> None:
    statuses = [r["cls"].removeprefix("s-") for r in batch.rows]
    assert statuses == ["failed"] * 3 + ["rejected"] * 4 + ["done"] * 33
    wells = [r["cells"][0] for r in batch.rows]
    assert wells[:3] == sorted(BROKEN) and wells[3:7] == sorted(REJECTED)
    assert wells[7:] == sorted(set(WELLS) - set(BROKEN) - REJECTED)
    for row in batch.rows[:7]:  # the status in words, not only in colour
        assert row["cells"][1].split()[1] in ("Failed", "Rejected")


def test_the_counts_are_the_batch_s(batch: Batch) -> None:
    source = batch.page.read_text(encoding="utf-8")
    summary = json.loads((batch.out / "summary.json").read_text())["counts"]
    assert summary == {"done": 33, "rejected": 4, "failed": 3, "skipped": 0, "interrupted": 0}
    for word, n in [("Done", 33), ("Rejected", 4), ("Failed", 3), ("Interrupted", 0),
                    ("Skipped", 0), ("Not run", 0)]:  # fmt: skip
        assert f"</span> {word} <b>{n}</b></li>" in source
    assert "Batch 1: 40 wells" in source
    assert 'aria-label="3 failed, 4 rejected, 33 done"' in source


def test_the_status_colours_are_told_apart_by_colour_blind_readers(
    batch: Batch, browser: Any
) -> None:
    page = browser.new_page()
    page.goto(batch.page.resolve().as_uri(), wait_until="load")
    rgb = page.evaluate(COLOURS)
    page.close()
    colours = ["#" + "".join(f"{int(c):02x}" for c in re.findall(r"\d+", v)) for v in rgb]
    assert len(set(colours)) == 6
    for vision in DICHROMACY:
        assert closest_colours(colours, vision) > (25 if vision == "normal" else 12), vision


def test_failed_wells_say_why_in_words_and_have_no_figures(batch: Batch) -> None:
    rows = by_well(batch)
    assert "broken.csv:25: expected 3 cells" in rows["W-07"]["Status"]
    assert "x<b>&y.csv:25: expected 3 cells" in rows["W-20"]["Status"]
    assert "missing.csv" in rows["W-33"]["Status"]
    for well in BROKEN:
        status = rows[well]["Status"]
        assert "stage" not in status and "InputFileError" not in status  # no internal words
        for head in [*batch.heads[2:9], "Report"]:
            assert rows[well][head] == "—", (well, head)


def test_text_from_the_wells_is_escaped(batch: Batch) -> None:
    source = batch.page.read_text(encoding="utf-8")
    assert html.escape("x<b>&y.csv", quote=True) in source
    assert "x<b>&y" not in source
    row = next(r for r in batch.rows if r["cells"][0] == "W-20")
    assert "x<b>&y.csv" in row["cells"][1]  # shown as typed, not as markup


def test_the_figures_are_those_of_the_published_tables(batch: Batch) -> None:
    rows = by_well(batch)
    for well in set(WELLS) - set(BROKEN):
        row, well_dir = rows[well], batch.out / well
        survey = pq.read_table(well_dir / "definitive.survey.parquet")
        assert row["TD MD m"] == f"{survey['md'][-1].as_py():.1f}" == "2520.0"
        assert row["TD TVD m"] == f"{survey['tvd'][-1].as_py():.1f}"
        md, dls = survey["md"].to_pylist(), survey["dls"].to_pylist()
        counted = [d for k, d in enumerate(dls) if k and md[k] - md[k - 1] >= 10.0]
        assert row["Max DLS °/30 m"] == f"{max(counted):.2f}\ncourses ≥ 10 m, as its report"
        failing = pc.sum(pc.greater(survey["dls"], DLS_LIMIT)).as_py()
        if well in KINKED:
            assert failing > 0
            assert row["QC checks"] == f"✖ {failing} of 85 failed\nDogleg severity {failing}"
        else:
            assert failing == 0 and row["QC checks"] == "✔ 85 passed"
        if well in REJECTED:
            assert row["Acceptance"] == "✖ failed: azimuth"
            assert row["Status"] == "▲ Rejected\nsurvey not accepted"
        else:
            # stations, inclination, azimuth, azimuth_low, depth, coverage (every 30 m)
            assert row["Acceptance"] == "✔ 6 passed" and row["Status"] == "✔ Done"
        clearance = pq.read_table(well_dir / "clearance.clearance.parquet")
        k = pc.index(clearance["sf_between"], pc.min(clearance["sf_between"])).as_py()
        sf = clearance["sf_between"][k].as_py()
        level = {"pass": "pass", "warn": "caution", "fail": "stop"}[
            max(clearance["level"].to_pylist(), key=["pass", "warn", "fail"].index)
        ]
        md = clearance["md_between"][k].as_py()
        assert row["Clearance: least SF"].split("\n")[0].endswith(f"{sf:.2f} ({level})")
        assert row["Clearance: least SF"].split("\n")[1] == (
            f"against {clearance['offset'][k].as_py()} at {md:.1f} m MD"
        )
        assert row["Drift"] == "—"  # no drift in this pipeline: shown as such, never 0
    shown = [rows[w]["Clearance: least SF"] for w in sorted(set(WELLS) - set(BROKEN))]
    levels = {cell.split(")")[0].split("(")[1] for cell in shown}
    assert levels == {"stop", "caution", "pass"}  # the offsets' distances span them


def test_each_report_link_opens_the_well_s_report(batch: Batch) -> None:
    for row in batch.rows:
        well = row["cells"][0]
        if well in BROKEN:
            assert row["links"] == []
            continue
        (link,) = row["links"]
        target = (batch.page.parent / urllib.parse.unquote(link)).resolve()
        assert target == (batch.out / well / "report.html").resolve() and target.is_file()


@pytest.fixture
def small_batch(tmp_path: Path) -> Path:
    """Three wells of the fleet pipeline, done."""
    wells = tmp_path / "wells"
    wells.mkdir()
    station_files(wells)
    out = tmp_path / "out"
    listed = manifest(wells, ["W-01", "W-02", "W-03"])
    gyropipe_cli("batch", fleet_pipeline(tmp_path), "--manifest", listed, "--out", out, check=True)
    return out


def test_status_html_says_which_outputs_are_missing(
    small_batch: Path, tmp_path: Path, browser: Any
) -> None:
    """A damaged or missing output is told in its own well's row; the figures its worker
    recorded as the run ended stand (they are the run's). A well published before figures
    were recorded (its ``batch.json`` without them) has them read from its tables: a
    damaged one spoils only its own cells."""
    (small_batch / "W-01" / "clearance.clearance.parquet").unlink()
    (small_batch / "W-02" / "run.json").write_text("{not json")
    (small_batch / "W-03" / "definitive.survey.parquet").write_bytes(b"PAR1 not a table")
    marker = small_batch / "W-01" / "batch.json"
    recorded = json.loads(marker.read_text())["figures"]
    older = small_batch / "W-03" / "batch.json"
    older.write_text(
        json.dumps({k: v for k, v in json.loads(older.read_text()).items() if k != "figures"})
    )
    result = gyropipe_cli("status", small_batch, "--html", check=True)
    page = small_batch / "fleet.html"
    assert result.stdout.strip() == str(page)
    rows, heads, _, errors = render(browser, page, tmp_path / "status.png")
    assert errors == []
    cells = {r["cells"][0]: r["cells"] for r in rows}
    assert "Output: clearance.clearance.parquet is missing" in cells["W-01"][1]
    least = cells["W-01"][heads.index("Clearance: least SF")]
    assert f"{recorded['clearance']['sf']:.2f}" in least  # the run's, as recorded
    assert cells["W-01"][heads.index("TD MD m")] == "2520.0"
    assert "run.json is damaged (not JSON)" in cells["W-02"]
    assert "Output: definitive.survey.parquet cannot be read (" in cells["W-03"][1]
    for head in ("TD MD m", "TD TVD m", "Max DLS °/30 m"):
        assert cells["W-03"][heads.index(head)] == "—"
    assert cells["W-03"][heads.index("Clearance: least SF")] != "—"
    assert "Wells in out: 3 wells" in page.read_text(encoding="utf-8")


def test_status_html_writes_the_file_given(small_batch: Path, tmp_path: Path) -> None:
    page = tmp_path / "pages" / "fleet of out.html"
    page.parent.mkdir()
    result = gyropipe_cli("status", small_batch, "--html", page, check=True)
    assert result.stdout.strip() == str(page)
    source = page.read_text(encoding="utf-8")
    links = [html.unescape(h) for h in source.split('href="')[1:]]
    for link in (h.split('"')[0] for h in links):  # relative to where the page is
        assert (page.parent / urllib.parse.unquote(link)).resolve().is_file()
    assert len(links) == 3


def unstamped(page: Path) -> str:
    """The page's source without the minute it was written."""
    return re.sub(r"Page written [^<]*", "Page written", page.read_text(encoding="utf-8"))


def test_the_api_writes_the_same_page(small_batch: Path, tmp_path: Path) -> None:
    gyropipe_cli("status", small_batch, "--html", check=True)
    by_cli = unstamped(small_batch / "fleet.html")
    path = gp.fleet_page(small_batch)
    assert path == small_batch / "fleet.html"
    assert unstamped(path) == by_cli
    other = gp.fleet_page(small_batch, tmp_path / "page.html")
    for page in (path, other):  # the three wells' reports linked from where each page is
        links = [h.split('"')[0] for h in page.read_text().split('href="')[1:]]
        assert len(links) == 3
        assert all((page.parent / urllib.parse.unquote(h)).resolve().is_file() for h in links)
    with pytest.raises(gp.GyropipeError, match="no ledger at"):
        gp.fleet_page(tmp_path / "nowhere")


def test_no_ledger_is_one_line(tmp_path: Path) -> None:
    result = gyropipe_cli("status", tmp_path, "--html")
    assert result.returncode == 2
    assert result.stderr.strip() == f"error: no ledger at {tmp_path / 'ledger.sqlite'}"


def test_the_drift_of_a_calibration_is_shown_with_its_units(tmp_path: Path) -> None:
    """A drift calibration's selected estimate, as its own export lists it."""
    wells = tmp_path / "in"
    wells.mkdir()
    shutil.copyfile(ROOT / "examples" / "calibration-ig50.csv", wells / "IG-1.csv")
    pipeline = without_report("calibration", tmp_path)
    out = tmp_path / "out"
    gyropipe_cli("batch", pipeline, "--inputs", f"{wells}/*.csv", "--out", out, check=True)
    lines = (out / "IG-1" / "drift-calibration.csv").read_text().splitlines()
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    (chosen,) = [r for r in rows if r["selected"] == "true"]
    source = (out / "fleet.html").read_text(encoding="utf-8")
    rate, sigma = float(chosen["drift_deg_h[deg/h]"]), float(chosen["sigma_deg_h[deg/h]"])
    assert abs(rate - 4.0) < 3 * sigma  # the simulated drift: 4 °/h
    shown = source.split(f"{chosen['instrument']}: ")[1].split(" °/h")[0]
    value, shown_sigma = (float(x) for x in shown.split(" ± "))
    assert value == pytest.approx(rate, abs=5e-4) and shown_sigma == pytest.approx(sigma, rel=0.05)


def test_status_html_and_json_together_are_refused(small_batch: Path) -> None:
    result = gyropipe_cli("status", small_batch, "--json", "--html")
    assert result.returncode == 2
    assert "--html writes the fleet page, --json prints JSON: give one" in result.stderr
    assert result.stdout == ""  # nothing written, nothing printed

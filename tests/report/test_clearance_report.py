"""Clearance end to end through `gyropipe run pipelines/clearance.yaml` on the bundled ISCWSA
example (reference and six offset wells from a manifest): the table against the set's
separation factors, and the report's clearance section in headless Chromium and in the PDF."""

from __future__ import annotations

import hashlib
import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from report_support import (
    assert_self_contained,
    assert_signoff_before_appendix,
    colour,
    figure_regions,
    figure_svg,
    ink,
    inspect,
    marks,
    pdf_pages,
    svg_texts,
)

from tests_support import ROOT

sys.path.insert(0, str(ROOT / "tests" / "clearance"))
from iscwsa_support import OFFSETS, expected_sf, run_clearance

EXAMPLE = ROOT / "examples" / "clearance"
MANIFEST = "examples/clearance/manifest.csv"
NAMES = {f"offset-0{k}": OFFSETS[k - 1] for k in range(1, 7)}


@pytest.fixture(scope="module")
def clearance_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("clearance") / "out"
    # the set's reference well: its model and hole (its field is in its header)
    run_clearance(MANIFEST, out, "clearance.reference_model=ISCWSA-MWD-REV4", check=True)
    return out


def test_cli_table_reproduces_the_iscwsa_set(clearance_run: Path):
    table = pq.read_table(clearance_run / "clearance.clearance.parquet")
    assert table.num_rows == 600
    units = {f.name: (f.metadata or {}).get(b"unit", b"").decode() for f in table.schema}
    assert units["md"] == units["offset_md"] == units["distance"] == units["sigma_s"] == "m"
    assert units["toolface"] == "deg"
    offsets = np.array(table.column("offset").to_pylist())
    sf = table.column("sf").to_numpy()
    for ours, theirs in NAMES.items():
        assert np.abs(sf[offsets == ours] / expected_sf(theirs) - 1.0).max() < 0.005, ours
    manifest = json.loads((clearance_run / "run.json").read_text())
    assert set(manifest["inputs"]) == {"reference", "offsets"}
    offset_files = [e for e in manifest["parameter_inputs"] if e["what"] == "offset file"]
    assert [(e["path"], e["sha256"], e["stage"], e["param"]) for e in offset_files] == [
        (str(path), hashlib.sha256(path.read_bytes()).hexdigest(), "offsets", "input")
        for path in (EXAMPLE / "offsets" / f"offset-0{k}.csv" for k in range(1, 7))
    ]
    assert (clearance_run / "clearance.csv").is_file()


def test_clearance_section_in_chromium(clearance_run: Path, browser: Any):
    html = clearance_run / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    assert {"fig-sf", "fig-cylinder"} <= set(page.figures)
    table = pq.read_table(clearance_run / "clearance.clearance.parquet").to_pandas()
    worst = table.loc[table.groupby("offset").sf.idxmin()].set_index("offset")
    least = table.loc[table.groupby("offset").sf_between.idxmin()].set_index("offset")
    worst_level = table.groupby("offset")["level"].agg(
        lambda x: max(x, key=["pass", "warn", "fail"].index)
    )
    rows = page.tables["clearance"]
    assert [r[0] for r in rows] == list(NAMES)
    assert page.headers["clearance"][:4] == ["Offset well", "Tool model", "Hole", "Minimum SF"]
    assert page.headers["clearance"][7:9] == ["Least SF between stations", "at reference MD"]
    for row in rows:
        best = worst.loc[row[0]]
        assert row[1] == "ISCWSA-MWD-REV4"
        assert row[2] == "24"  # in, as the industry writes a hole size
        assert float(row[3]) == pytest.approx(best.sf, abs=0.005)
        assert float(row[4]) == pytest.approx(best.md, abs=0.005)
        assert float(row[7]) == pytest.approx(least.sf_between[row[0]], abs=0.005)
        assert float(row[8]) == pytest.approx(least.md_between[row[0]], abs=0.005)
        assert row[-1] == {"pass": "pass", "warn": "caution", "fail": "stop"}[worst_level[row[0]]]
    stops = [k for k, r in enumerate(rows) if r[-1] == "stop"]
    assert stops == [2, 3]  # offsets 03 and 04 come within SF 1
    shown = marks(browser, html)["clearance"]
    assert [k for k, m in enumerate(shown) if m.row] == stops
    text = page.text
    for k in range(1, 7):  # each offset survey named with its file's hash
        data = (EXAMPLE / "offsets" / f"offset-0{k}.csv").read_bytes()
        assert f"offset-0{k}.csv · sha256 {hashlib.sha256(data).hexdigest()}" in text
    verdict = "Clearance: stop — minimum separation factor"
    assert text.count(verdict) == 2  # in the summary on page 1, and atop the section
    summary = text.index("Total depth (MD)")
    assert verdict in text[summary : text.index("Method and reference models", summary)]
    assert "ISCWSA-MWD-REV4, hole 36 in (0.9144 m)" in text
    assert "the least SF along each reference course, between stations included" in text
    assert "SPE-187073" in text and "SPE 67616" in text
    for internal in ("anticollision", "sigma_pa", "surface_margin", "read_offsets"):
        assert internal not in text.split("Appendix: provenance")[0], internal
    appendix = text.split("Appendix: provenance")[-1]  # the files pinned, as run.json has them
    recorded = json.loads((clearance_run / "run.json").read_text())["parameter_inputs"]
    assert len(recorded) == 6
    for entry in recorded:
        assert f"{entry['path']} (offset file)" in appendix and entry["sha256"] in appendix


SLOTS = {  # examples/clearance/manifest.csv: north, east (m); every hole 24 in
    "offset-01": ("0.00", "100.00"),
    "offset-02": ("100.00", "0.00"),
    "offset-03": ("0.00", "10.00"),
    "offset-04": ("0.00", "20.00"),
    "offset-05": ("−50.00", "−500.00"),
    "offset-06": ("−2300.00", "100.00"),
}


def test_clearance_report_states_the_wells_it_scanned(clearance_run: Path, browser: Any):
    page = inspect(browser, clearance_run / "report.html")
    assert page.text.startswith("GYROPIPE\nClearance report\n")
    assert "Gyro survey report" not in page.text
    headers = page.headers["clearance-wells"]
    assert headers == [
        "Well",
        "Slot north",
        "Slot east",
        "Tie-on its file lists",
        "First-station TVD",
        "Hole diameter",
        "Hole diameter",
        "Tool model",
    ]
    assert page.units["clearance-wells"] == [
        "",
        "m",
        "m",
        "m",
        "m below the reference datum",
        "in",
        "m",
        "",
    ]
    title = "ISCWSA MWD (fixed rig), Rev 4"  # the title in the ISCWSA-MWD-REV4 model file
    reference, *offsets = page.tables["clearance-wells"]
    assert reference == [
        "Reference well",
        "0.00",
        "0.00",
        "none listed",  # the set's files list no positions
        "its first MD",
        "36",
        "0.9144",
        title,
    ]
    assert [r[0] for r in offsets] == list(SLOTS)
    for row in offsets:
        assert row[1:] == [*SLOTS[row[0]], "none listed", "its first MD", "24", "0.6096", title], (
            row[0]
        )
    assert "SPE 90408" not in page.text  # no gyro model in this scan


def test_clearance_report_has_a_signoff_block(clearance_run: Path, browser: Any):
    """A clearance report is signed like a survey report (#28 item 9)."""
    assert_signoff_before_appendix(browser, clearance_run)


def test_gyro_reference_cites_the_gyro_error_model(tmp_path: Path):
    """A gyro reference model against the set's MWD offsets. The pipeline's own, GYRO-NS,
    holds to 89° and the reference reaches 90° at MD 2850 m: refused there (issue 29; it
    gave σL 39.1 m, an artefact of tan 90°); GYRO-NS-CT holds to 150°."""
    refused = run_clearance(MANIFEST, tmp_path / "refused", "report.formats=[html]")
    assert refused.returncode != 0 and "Traceback" not in refused.output
    assert (
        "the reference: tool model GYRO-NS holds for inclinations 0–89°: the station at MD "
        "2850 m has 90°" in refused.stderr
    )
    settings = ("report.formats=[html]", "clearance.reference_model=GYRO-NS-CT")
    result = run_clearance(MANIFEST, tmp_path, *settings, check=True)
    assert "Traceback" not in result.output
    text = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert "<h1>Clearance report</h1>" in text
    assert "ISCWSA error models [2] with the gyro terms of [3]" in text
    assert "Prediction of wellbore position accuracy when surveyed with gyroscopic tools" in text


def _cylinder_md_labels(texts: list[str]) -> list[float]:
    return [float(m[1]) for t in texts if (m := re.fullmatch(r"MD (\d+)", t))]


def test_travelling_cylinder_traces_carry_md_labels(clearance_run: Path, browser: Any):
    """Each offset's trace on the travelling cylinder is labelled with reference MDs (#28
    item 9), each the MD of one of its points inside the plotted reach, a few per trace."""
    html = clearance_run / "report.html"
    table = pq.read_table(clearance_run / "clearance.clearance.parquet").to_pandas()
    reach = float(re.search(r"within (\d+) m; labels", inspect(browser, html).text)[1])
    near = table[table.distance <= reach]
    labels = _cylinder_md_labels(svg_texts(browser, figure_svg(html, "cylinder"), "text"))
    assert len(labels) >= 2 * near.offset.nunique()
    assert len(labels) <= 6 * near.offset.nunique()
    assert all(np.min(np.abs(near.md.to_numpy() - md)) < 0.5 for md in labels)
    assert max(labels) - min(labels) > 0.5 * (near.md.max() - near.md.min())  # along the trace


def test_clearance_figures_drawn_in_the_pdf(clearance_run: Path, tmp_path: Path):
    pages = pdf_pages(clearance_run / "report.pdf", tmp_path)
    words = " ".join(w[0] for p in pages for w in p.words)
    assert "Travelling cylinder" in words and "Separation factor against MD" in words
    assert len(re.findall(r"MD \d+", words)) >= 6  # the cylinder's MD labels
    regions = figure_regions(pages)
    assert len(regions) >= 6
    sf_chart, cylinder = sorted(regions)[-2:]
    assert ink(regions[sf_chart]) > 0.02 and colour(regions[sf_chart]) > 0.001
    # the band above the caption holds the cylinder's low side: sparse, but drawn
    assert ink(regions[cylinder]) > 0.005 and colour(regions[cylinder]) > 0.0005

"""Chart text a survey engineer can read: tick labels of tiny or huge values are short
mantissas with a power of ten shown once at the axis end, and the HTML report draws its
figures in the font their text was measured with (embedded in the page). Checked on the
calibration report of an instrument whose azimuth errors are of order 1e-6° (headless
Chromium, the PDF through poppler) and on a chart of UTM coordinates."""

from __future__ import annotations

import ast
import base64
import io
import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from report_support import (
    figure_svg,
    inspect,
    overlap,
    pdf_pages,
    svg_boxes,
    svg_texts,
)

from pipeline.reports.charts.drawing import Drawing
from pipeline.reports.charts.model import Axis, Chart, Line, Marker, Panel, grid
from pipeline.reports.charts.scene import text_width
from pipeline.reports.pdf_fonts import pdf_font
from pipeline.sim.calibration import CalibrationPlan, Harmonic, simulate_calibration
from pipeline.sim.spec import Drift
from tests_support import ROOT, gyropipe_cli

TINY = CalibrationPlan(
    series=4,
    reading_noise=2e-6,
    systematic=(Harmonic(order=1, amplitude=3e-6, phase=20.0),),
    drift=Drift(rate=4e-6),
    seed=3,
)
"""Azimuth errors of a few 1e-6° (noise 2e-6°, pattern 3e-6°, drift 4e-6 °/h for an hour)."""
NUMBER = re.compile(r"−?\d+(\.\d+)?")


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    work = tmp_path_factory.mktemp("tiny")
    pq.write_table(simulate_calibration(TINY), work / "cal.parquet")
    out = work / "out"
    readings = str(work / "cal.parquet")
    gyropipe_cli(
        "run", "pipelines/calibration.yaml", "--input", readings, "--out", str(out), check=True
    )
    return out


def value(label: str) -> float:
    return float(label.replace("−", "-"))


def test_tiny_azimuth_errors_are_labelled_as_mantissas_times_ten_to_the_minus_six(
    browser: Any, tiny_run: Path
):
    """The y axis of azimuth errors reads −4 … 8 with ×10⁻⁶ once above it (was 0.000008):
    the labels, the note and the panel's other text do not overlap (as Chromium lays the
    report's SVG out), and the series means lie within the labelled range × 10⁻⁶."""
    svg = figure_svg(tiny_run / "report.html", "series")
    ticks, notes, texts = svg_boxes(browser, svg, ["g.ytick text", "g.ynote text", "text"])
    labels = svg_texts(browser, svg, "g.ytick text")
    numeric = [(b, t) for b, t in zip(ticks, labels, strict=True) if NUMBER.fullmatch(t)]
    assert len(numeric) >= 4
    assert all(len(t) <= 4 for _, t in numeric), labels
    assert svg_texts(browser, svg, "g.ynote text") == ["×10⁻⁶"]
    values = np.array([value(t) for _, t in numeric]) * 1e-6
    step = float(np.diff(values)[0])
    assert np.diff(values) == pytest.approx(step)
    means = pq.read_table(tiny_run / "drift.series.parquet").column("mean_error").to_numpy()
    assert values.min() - step <= means.min() and means.max() <= values.max() + step
    assert step < np.ptp(means)  # the labels count millionths, not thousandths
    for k, (box, _) in enumerate(numeric):
        for other, _ in numeric[k + 1 :]:
            assert not overlap(box, other)
    (note,) = notes
    others = [b for b in texts if b != note]
    assert not any(overlap(note, b) for b in others)
    top = min(numeric, key=lambda n: n[0]["y0"])[0]
    assert note["y1"] <= top["y0"] and abs(note["x1"] - top["x1"]) < 1.0  # over the column


def test_drift_rate_axis_note_is_clear_of_its_label(browser: Any, tiny_run: Path):
    """The estimates' x axis (drift rates of a few 1e-6 °/h) shows its power of ten under
    its right end, clear of the axis label and of the tick labels."""
    svg = figure_svg(tiny_run / "report.html", "series")
    (note,) = svg_texts(browser, svg, "g.xnote text")
    assert re.fullmatch("×10⁻[⁵⁶]", note)
    ticks, (box,), texts = svg_boxes(browser, svg, ["g.xtick text", "g.xnote text", "text"])
    contents = svg_texts(browser, svg, "text")
    (label,) = [b for b, t in zip(texts, contents, strict=True) if t.startswith("Drift rate")]
    assert not overlap(box, label) and not any(overlap(box, t) for t in ticks)
    assert all(len(t) <= 4 for t in svg_texts(browser, svg, "g.xtick text"))


MEASURE = """async family => {
  if (family) document.querySelectorAll('figure svg').forEach(
    s => s.setAttribute('font-family', family));
  await document.fonts.ready;
  return {
    faces: Array.from(document.fonts).map(f => [f.family, f.weight, f.status]),
    family: getComputedStyle(document.querySelector('figure svg text')).fontFamily,
    texts: Array.from(document.querySelectorAll('figure svg text')).map(t => [
      t.textContent, parseFloat(t.getAttribute('font-size')),
      t.getAttribute('font-weight') === 'bold', t.getComputedTextLength()]),
  };
}"""


def drawn_widths(browser: Any, html: Path, family: str | None) -> dict[str, Any]:
    """Chromium's fonts of the report and the advance (pt) of each figure text, with the
    figures' font family set to ``family`` (None: as written)."""
    page = browser.new_page()
    page.goto(html.resolve().as_uri(), wait_until="load")
    found: dict[str, Any] = page.evaluate(MEASURE, family)
    page.close()
    return found


def test_figures_are_drawn_in_the_embedded_font_they_were_measured_with(
    browser: Any, tiny_run: Path
):
    """Each figure text is as wide in Chromium as the layout measured it (DejaVu Sans with
    its kerning), with only the embedded font and a monospaced fallback named: the page's
    own font is used, whatever the machine has installed. Monospace alone is far off."""
    html = tiny_run / "report.html"
    shipped = drawn_widths(browser, html, None)
    assert shipped["family"].startswith("gyropipe-dejavu-sans")
    found = drawn_widths(browser, html, "gyropipe-dejavu-sans, monospace")
    assert {(f, w, s) for f, w, s in found["faces"]} == {
        ("gyropipe-dejavu-sans", "400", "loaded"),
        ("gyropipe-dejavu-sans", "700", "loaded"),
    }
    kerned = 0
    for text, size, bold, width in found["texts"]:
        measured = text_width(text, size, bold)
        assert width == pytest.approx(measured, abs=0.15), text
        unkerned = sum(pdf_font("DejaVu Sans", bold).width(c, size) for c in text)
        kerned += abs(unkerned - measured) > 0.2
    assert kerned >= 2  # the kerning pairs are applied, as measured
    assert any(bold for _, _, bold, _ in found["texts"])  # the S1 … S4 labels
    mono = drawn_widths(browser, html, "monospace")
    misses = [abs(w - text_width(t, s, b)) > 0.15 for t, s, b, w in mono["texts"]]
    assert sum(misses) > len(misses) / 2  # the check tells fonts apart


def test_pdf_prints_the_power_of_ten_over_the_tick_labels(tiny_run: Path, tmp_path: Path):
    """poppler finds '×10⁻⁶' once, right-aligned over a column of short tick labels."""
    words = [w for p in pdf_pages(tiny_run / "report.pdf", tmp_path) for w in p.words]
    (note,) = [w for w in words if w[0] == "×10⁻⁶"]
    column = [
        w
        for w in words
        if NUMBER.fullmatch(w[0]) and abs(w[3] - note[3]) < 1.0 and 0 < w[2] - note[4] < 200
    ]
    assert len(column) >= 4 and all(len(w[0]) <= 4 for w in column)


def chart_literals() -> set[str]:
    """Every character of the string literals (docstrings, bare string statements, left
    out) of the report code:
    the chart titles, axis and legend labels, units and tick symbols it can write."""
    chars: set[str] = set()
    for source in sorted((ROOT / "src" / "pipeline" / "reports").rglob("*.py")):
        tree = ast.parse(source.read_text(encoding="utf-8"))
        docs = {id(node.value) for node in ast.walk(tree) if isinstance(node, ast.Expr)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                chars |= set() if id(node) in docs else set(node.value)
    return chars - set("\n\t\r")


def test_embedded_fonts_hold_every_character_the_charts_write(tiny_run: Path):
    """The two fonts inline in the HTML (regular, bold) map every character of the report
    code's literal text; the power-of-ten characters among them."""
    from fontTools.ttLib import TTFont  # type: ignore[import-untyped]

    source = (tiny_run / "report.html").read_text(encoding="utf-8")
    fonts = re.findall(r"url\(data:font/ttf;base64,([A-Za-z0-9+/=]+)\)", source)
    assert len(fonts) == 2
    needed = chart_literals()
    assert set("×⁻⁰¹²³⁴⁵⁶⁷⁸⁹−°σ±") <= needed
    for data in fonts:
        cmap = TTFont(io.BytesIO(base64.b64decode(data))).getBestCmap()
        assert sorted(c for c in needed if ord(c) not in cmap) == []


def test_embedded_fonts_kern_as_the_whole_fonts_do(tiny_run: Path):
    """The browser kerns only as the font's ``kern`` table says: each inline font holds
    the whole shipped font's kerning pairs between the characters it maps (read from both
    fonts by fontTools)."""
    from fontTools.ttLib import TTFont

    source = (tiny_run / "report.html").read_text(encoding="utf-8")
    fonts = re.findall(r"url\(data:font/ttf;base64,([A-Za-z0-9+/=]+)\)", source)
    for data, bold in zip(fonts, (False, True), strict=True):
        inline = TTFont(io.BytesIO(base64.b64decode(data)))
        whole = TTFont(pdf_font("DejaVu Sans", bold).path)
        chars = {chr(c) for c in inline.getBestCmap()}

        def pairs(font: Any, chars: set[str] = chars) -> dict[tuple[str, str], int]:
            by_glyph = {g: c for c, g in ((chr(k), g) for k, g in font.getBestCmap().items())}
            table = font["kern"].kernTables[0].kernTable
            return {
                (by_glyph[a], by_glyph[b]): v
                for (a, b), v in table.items()
                if by_glyph.get(a) in chars and by_glyph.get(b) in chars
            }

        expected = pairs(whole)
        assert len(expected) > 500 and pairs(inline) == expected


def test_tiny_drift_prints_down_to_its_sigma_not_as_zero(browser: Any, tiny_run: Path):
    """A drift of a few 1e-6 °/h known to ≈ 1e-7 °/h: the summary, the estimates table and
    the series table print it to the σ's last digit (was 0.000 ± 0.000), matching the
    result tables; the figure's legend too."""
    page = inspect(browser, tiny_run / "report.html")
    result = pq.read_table(tiny_run / "drift.result.parquet").to_pylist()
    fit = next(r for r in result if r["method"] == "fit")
    shown = re.search(r"Drift \(fit\)\s+(−?[\d.]+) ± (\S+) °/h", page.text)
    assert shown is not None, page.text
    drift, sigma = value(shown.group(1)), value(shown.group(2))
    assert drift != 0 and drift == pytest.approx(fit["drift_deg_h"], rel=0.05)
    assert sigma == pytest.approx(fit["sigma_deg_h"], rel=0.05)
    reading = re.search(r"Reading σ\s+(\S+)°", page.text)
    assert reading is not None and value(reading.group(1)) == pytest.approx(
        fit["reading_sigma"], rel=0.05
    )
    rows = {r[0]: r for r in page.tables["estimates"]}
    assert value(rows["fit"][2]) == pytest.approx(fit["drift_deg_h"], rel=0.05)
    series = pq.read_table(tiny_run / "drift.series.parquet").to_pylist()
    means = [value(r[3]) for r in page.tables["series"]]
    assert means == pytest.approx([s["mean_error"] for s in series], rel=0.05)
    legend = svg_texts(browser, figure_svg(tiny_run / "report.html", "series"), "text")
    (label,) = [t for t in legend if t.startswith("fitted drift")]
    assert value(label.split()[2]) == pytest.approx(fit["drift_deg_h"], rel=0.05)


def test_utm_coordinates_are_labelled_in_millions_clear_of_a_long_axis_label(browser: Any):
    """Eastings of 6.1e6 m in a narrow panel: ticks 6.100 … ×10⁶, the note under the axis's
    right end and the long axis label moved left of it, nothing overlapping."""
    (box,) = grid((2.6, 2.2), left=0.7)
    panel = Panel(box, Axis("Easting (m, UTM zone 31N)"), Axis("Northing (m)"))
    east = np.linspace(6.10e6, 6.16e6, 7)
    panel.add(Line(east, np.linspace(10.0, 70.0, 7), "#2f6fb0", marker=Marker("o")))
    svg = Drawing(Chart((2.6, 2.2), [panel])).svg()
    assert svg_texts(browser, svg, "g.xnote text") == ["×10⁶"]
    labels = svg_texts(browser, svg, "g.xtick text")
    assert all(re.fullmatch(r"6\.\d+", t) for t in labels) and len(labels) >= 2
    ticks, (note,), texts = svg_boxes(browser, svg, ["g.xtick text", "g.xnote text", "text"])
    contents = svg_texts(browser, svg, "text")
    (label,) = [b for b, t in zip(texts, contents, strict=True) if t.startswith("Easting")]
    assert not overlap(note, label) and not any(overlap(note, t) for t in ticks)
    for k, tick in enumerate(ticks):
        assert not any(overlap(tick, other) for other in ticks[k + 1 :])

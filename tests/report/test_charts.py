"""The report's chart renderer: nice ticks, log decades, data placed where the axes say,
well-formed SVG and a PDF poppler reads — checked on figures of known data."""

from __future__ import annotations

import base64
import io
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from report_support import svg_boxes, svg_texts

from pipeline.reports import plots
from pipeline.reports.charts import ticks
from pipeline.reports.charts.drawing import Drawing
from pipeline.reports.charts.model import Axis, Chart, Line, Marker, Panel, grid

SVG = "{http://www.w3.org/2000/svg}"


@pytest.mark.parametrize(
    ("lo", "hi", "most", "expected"),
    [
        (0.0, 10.0, 5, ["0", "2", "4", "6", "8", "10"]),
        (-0.013, 0.013, 6, ["−0.010", "−0.005", "0.000", "0.005", "0.010"]),
        (-47.0, 1290.0, 9, ["0", "200", "400", "600", "800", "1000", "1200"]),
        (0.3, 2.2, 5, ["0.5", "1.0", "1.5", "2.0"]),
        (11.4, 12.6, 6, ["11.4", "11.6", "11.8", "12.0", "12.2", "12.4", "12.6"]),
        (11.4, 12.6, 4, ["11.5", "12.0", "12.5"]),
        (0.2, 1.3, 5, ["0.25", "0.50", "0.75", "1.00", "1.25"]),
    ],
)
def test_linear_ticks_are_nice_numbers(lo: float, hi: float, most: int, expected: list[str]):
    values, step = ticks.linear_ticks(lo, hi, most)
    assert [ticks.label(v, step) for v in values] == expected


@pytest.mark.parametrize(
    ("lo", "hi", "most", "expected", "note"),
    [
        # ordinary ranges: in full, as before
        (0.0, 3000.0, 6, ["0", "500", "1000", "1500", "2000", "2500", "3000"], ""),
        (0.0, 90.0, 6, ["0", "20", "40", "60", "80"], ""),
        (-0.013, 0.013, 6, ["−0.010", "−0.005", "0.000", "0.005", "0.010"], ""),
        (0.0, 12000.0, 6, ["0", "2000", "4000", "6000", "8000", "10000", "12000"], ""),
        (2500.0, 2500.5, 5, ["2500.0", "2500.1", "2500.2", "2500.3", "2500.4", "2500.5"], ""),
        # gyro drift in deg/s, residuals: a shared power of ten
        (-5e-6, 8e-6, 6, ["−5.0", "−2.5", "0.0", "2.5", "5.0", "7.5"], "×10⁻⁶"),
        (-3e-9, 4e-9, 6, ["−2", "0", "2", "4"], "×10⁻⁹"),
        (0.0, 8e-4, 4, ["0", "2", "4", "6", "8"], "×10⁻⁴"),
        # coordinates of 1e6 m
        (6.1e6, 6.2e6, 5, ["6.10", "6.12", "6.14", "6.16", "6.18", "6.20"], "×10⁶"),
        (0.0, 1.2e5, 6, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0", "1.2"], "×10⁵"),
        # values differing only in far decimals: an offset
        (10000.001, 10000.004, 3, ["0.001", "0.002", "0.003", "0.004"], "+10000"),
        (-10000.004, -10000.001, 3, ["−0.004", "−0.003", "−0.002", "−0.001"], "−10000"),
        (6123456.001, 6123456.004, 3, ["0.001", "0.002", "0.003", "0.004"], "+6123456"),
        (10000.0001, 10000.0004, 4, ["1", "2", "3", "4"], "×10⁻⁴ +10000"),
    ],
)
def test_linear_labels_of_huge_tiny_and_offset_ranges(
    lo: float, hi: float, most: int, expected: list[str], note: str
):
    """tick value = label × 10ⁿ + offset, the note '×10ⁿ +offset' shown once."""
    values, step = ticks.linear_ticks(lo, hi, most)
    assert ticks.linear_labels(values, step) == (expected, note)


def test_log_ticks_are_decades_and_their_labels_read_plainly():
    major, minor = ticks.log_ticks(2e-6, 3e-2)
    assert major == pytest.approx([1e-5, 1e-4, 1e-3, 1e-2])
    assert [ticks.log_label(v) for v in major] == ["10⁻⁵", "10⁻⁴", "0.001", "0.01"]
    assert minor[:3] == pytest.approx([2e-6, 3e-6, 4e-6])
    major, _ = ticks.log_ticks(0.7, 3.0)  # less than a decade: 1 with 2 and 5 × it
    assert major == pytest.approx([1.0, 2.0])


def well() -> plots.Path3:
    """A J-shaped path: 300 m vertical, then 40 stations heading 060°, positions in m."""
    md = np.linspace(0.0, 1200.0, 41)
    horizontal = np.clip(md - 300.0, 0.0, None) * 0.6
    north, east = horizontal * np.cos(np.radians(60)), horizontal * np.sin(np.radians(60))
    tvd = np.minimum(md, 300.0) + np.clip(md - 300.0, 0.0, None) * 0.8
    return plots.Path3(md, north, east, tvd, (0, 41), "true north")


def tick_map(root: ET.Element, kind: str, axis: int) -> tuple[float, float]:
    """(scale, offset) of the tick marks: point = scale × value + offset, fitted from each
    tick group's mark position and its label."""
    positions, values = [], []
    for group in root.iter(f"{SVG}g"):
        if group.get("class") != kind:
            continue
        mark = group.find(f"{SVG}path")
        label = group.find(f"{SVG}text")
        assert mark is not None and label is not None and label.text
        first = re.findall(r"-?[\d.]+", mark.get("d", ""))
        positions.append(float(first[axis]))
        values.append(float(label.text.replace("−", "-")))
    assert len(values) >= 3
    scale, offset = np.polyfit(values, positions, 1)
    residual = np.abs(np.polyval((scale, offset), values) - positions).max()
    assert residual < 0.1  # the ticks are evenly spaced: a linear axis
    return float(scale), float(offset)


def test_plan_view_puts_each_station_where_the_ticks_say(tmp_path: Path):
    path = well()
    svg = Drawing(plots.plan_view((6.9, 4.0), path)).svg()
    root = ET.fromstring(svg)  # well-formed
    assert root.get("width") == "496.8pt" and root.get("height") == "288pt"
    sx, ox = tick_map(root, "xtick", 0)
    sy, oy = tick_map(root, "ytick", 1)
    assert sx == pytest.approx(-sy, rel=1e-3)  # equal scales, north up
    stations = next(
        p
        for p in root.iter(f"{SVG}path")
        if p.get("stroke") == plots.BLUE and "L" in p.get("d", "")
    )
    points = np.array(
        [[float(v) for v in xy.split(",")] for xy in re.split(r"[ML ]+", stations.get("d", ""))[1:]]
    )
    expected = np.column_stack([sx * path.east + ox, sy * path.north + oy])
    assert points == pytest.approx(expected, abs=0.11)  # written to 0.1 pt
    texts = [t.text for t in root.iter(f"{SVG}text")]
    assert "East (m)" in texts and "North (m, true north)" in texts
    assert any(t and t.startswith("closure 540.0 m @ 60.00°") for t in texts)


def test_log_axes_tick_at_decades():
    tau = np.logspace(-1, 3, 20)
    chart = plots.allan_deviation(
        (6.9, 3.4),
        tau,
        {"gyro_x": 0.05 / np.sqrt(tau), "acc_x": 2e-4 / np.sqrt(tau)},
        {"gyro_x": "deg/h", "acc_x": "m/s2"},
    )
    root = ET.fromstring(Drawing(chart).svg())
    labels = ["".join(g.itertext()) for g in root.iter(f"{SVG}g") if g.get("class") == "xtick"]
    assert labels == ["0.1", "1", "10", "100", "1000"] * 2  # gyro and accelerometer panels


def test_chart_saved_as_pdf_is_vector_and_readable(tmp_path: Path):
    for tool in ("pdftotext", "pdfimages"):
        if shutil.which(tool) is None:
            pytest.skip(f"{tool} not found: apt-get install poppler-utils")
    (box,) = grid((4.0, 3.0))
    panel = Panel(box, Axis("Time (s)", limits=(0, 10)), Axis("Signal (V)", limits=(-1, 1)))
    panel.add(Line(np.arange(11.0), np.sin(np.arange(11.0)), plots.BLUE, marker=Marker("o")))
    pdf = Drawing(Chart((4.0, 3.0), [panel])).save(tmp_path / "chart.pdf")
    text = subprocess.run(
        ["pdftotext", "-layout", str(pdf), "-"], check=True, capture_output=True, text=True
    ).stdout
    for word in ("Time (s)", "0.5", "−1.0", "10"):
        assert word in text
    images = subprocess.run(
        ["pdfimages", "-list", str(pdf)], check=True, capture_output=True, text=True
    ).stdout
    assert len(images.strip().splitlines()) == 2  # the header only: nothing rasterised
    with pytest.raises(ValueError, match=r"chart\.png: a chart is saved as \.svg or \.pdf"):
        Drawing(Chart((4.0, 3.0), [panel])).save(tmp_path / "chart.png")


def test_chart_saved_as_svg_carries_its_fonts(tmp_path: Path):
    """A chart saved alone embeds the fonts its text was measured with (regular and bold,
    TrueType, under the family the drawing names first); the notebook view does not."""
    from fontTools.ttLib import TTFont  # type: ignore[import-untyped]

    (box,) = grid((4.0, 3.0))
    panel = Panel(box, Axis("Time (s)", limits=(0, 10)), Axis("Signal (V)", limits=(-1, 1)))
    panel.add(Line(np.arange(11.0), np.cos(np.arange(11.0)), plots.BLUE))
    drawing = Drawing(Chart((4.0, 3.0), [panel]))
    saved = drawing.save(tmp_path / "chart.svg").read_text(encoding="utf-8")
    root = ET.fromstring(saved)
    (style,) = root.iter(f"{SVG}style")
    faces = re.findall(r"font-family: ([\w-]+); font-weight: (\d+).*?base64,([^)]+)\)", style.text)
    assert [(family, weight) for family, weight, _ in faces] == [
        ("gyropipe-dejavu-sans", "400"),
        ("gyropipe-dejavu-sans", "700"),
    ]
    for _, _, data in faces:
        assert TTFont(io.BytesIO(base64.b64decode(data)))["name"].getDebugName(1) == "DejaVu Sans"
    assert root.get("font-family", "").startswith("gyropipe-dejavu-sans,")
    assert "<style>" not in drawing._repr_svg_()


@pytest.mark.parametrize("azimuth", [45.0, 225.0, 315.0])
def test_plan_view_td_label_clears_the_path(azimuth: float, browser: Any):
    """The TD label sits beside TD where no station is, inside the axes (its boxes as
    Chromium lays the SVG out; the figure drawn 1:1, one CSS px = 0.75 pt)."""
    md = np.linspace(0.0, 2000.0, 41)
    reach = np.clip(md - 300.0, 0.0, None) * 0.7
    a = np.radians(azimuth)
    path = plots.Path3(
        md,
        reach * np.cos(a),
        reach * np.sin(a),
        np.minimum(md, 300.0) + reach,
        (0, 41),
        "grid north",
    )
    svg = Drawing(plots.plan_view((6.9, 4.0), path)).svg()
    root = ET.fromstring(svg)
    stations = next(
        p
        for p in root.iter(f"{SVG}path")
        if p.get("stroke") == plots.BLUE and "L" in p.get("d", "")
    )
    points = (
        np.array(
            [
                [float(v) for v in xy.split(",")]
                for xy in re.split(r"[ML ]+", stations.get("d", ""))[1:]
            ]
        )
        / 0.75
    )
    frame = next(
        p for p in root.iter(f"{SVG}path") if p.get("stroke") == "#9aa5b1" and "Z" in p.get("d", "")
    )
    corners = (
        np.array(
            [
                [float(v) for v in xy.split(",")]
                for xy in re.split(r"[MLZ ]+", frame.get("d", ""))[1:-1]
            ]
        )
        / 0.75
    )
    texts, (origin,) = svg_boxes(browser, svg, ["text", "svg"])
    shift = np.array([origin["x0"], origin["y0"]])  # where the page put the SVG
    points, corners = points + shift, corners + shift
    contents = svg_texts(browser, svg, "text")
    label = [b for b, t in zip(texts, contents, strict=True) if t.startswith(("TD ", "closure"))]
    assert len(label) == 2
    for box in label:
        inside = (
            (points[:, 0] >= box["x0"] - 2)
            & (points[:, 0] <= box["x1"] + 2)
            & (points[:, 1] >= box["y0"] - 2)
            & (points[:, 1] <= box["y1"] + 2)
        )
        assert not inside.any(), (box, points[inside])
        assert corners[:, 0].min() <= box["x0"] and box["x1"] <= corners[:, 0].max()
        assert corners[:, 1].min() <= box["y0"] and box["y1"] <= corners[:, 1].max()


def test_pdf_and_svg_place_the_labels_alike(tmp_path: Path):
    """One layout, two writers: each x tick label is centred on the same point in the PDF
    (words' boxes from pdftotext) as in the SVG (its middle-anchored x)."""
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext not found: apt-get install poppler-utils")
    drawing = Drawing(plots.plan_view((6.9, 4.0), well()))
    root = ET.fromstring(drawing.svg())
    svg_x = {}
    for group in root.iter(f"{SVG}g"):
        label = group.find(f"{SVG}text")
        if group.get("class") == "xtick" and label is not None and label.text:
            svg_x[label.text] = float(label.get("x", "nan"))
    bbox = subprocess.run(
        ["pdftotext", "-bbox", str(drawing.save(tmp_path / "plan.pdf")), "-"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    words = re.findall(
        r'<word xMin="([\d.]+)" yMin="[\d.]+" xMax="([\d.]+)"[^>]*>([^<]*)</word>', bbox
    )
    centres: dict[str, list[float]] = {}
    for a, b, w in words:
        centres.setdefault(w, []).append((float(a) + float(b)) / 2)
    assert len(svg_x) >= 5
    for text, x in svg_x.items():
        assert min(abs(c - x) for c in centres[text]) < 0.5, (text, x, centres[text])

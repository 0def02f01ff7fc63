"""Survey reports of simulated runs with everything wired: validity QC charts, compassing σ
and flags, error ellipses (point-gyro.yaml), drift correction and in/out-run QC
(free-gyro.yaml), Allan deviation and noise terms (an allan stage on a static record)."""

from __future__ import annotations

import re
import shutil
import subprocess
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from report_support import (
    DICHROMACY,
    assert_self_contained,
    closest_colours,
    colour,
    figure_regions,
    figure_svg,
    flagged_share,
    html_figure_sizes,
    ink,
    inspect,
    line_words,
    marks,
    pdf_images,
    pdf_pages,
    svg_texts,
)

from pipeline.continuous.tables import (
    FLAG_AFTER_VERTICAL,
    FLAG_AZIMUTH_UNDEFINED,
    FLAG_LARGE_MISALIGNMENT,
    FLAG_NEAR_VERTICAL,
    FLAG_NO_CLOSURE,
    describe_flags,
)
from pipeline.earth.frames import OMEGA_EARTH
from pipeline.io.mcap.tables import read_tables
from pipeline.reports.flags import COMPASS, CONTINUOUS
from pipeline.sim.sensors import measure, tool_preset
from pipeline.tables import RawSamples
from tests_support import ROOT, gyropipe_cli

POINT_PLAN = """
name: report-point
seed: 3
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 300}
    - {kind: build, dls: 3.0, inc: 40, azi: 120}
    - {kind: hold, to_md: 1500}
tool: {preset: mems-vrg}
survey: {mode: point, every: 150, positions: [0, 90, 180, 270, 0], dwell: 12}
"""


CLIENT_TITLES = {
    "earth_rate_fit": "Earth rate fitted over the positions",
    "rest_gyro": "Tool at rest: gyros",
    "rest_acc": "Tool at rest: accelerometers",
}
"""Checks of the point-gyro run → the title its QC chart and summary row carry."""


def number(cell: str) -> float:
    return float(cell.replace("−", "-"))


@pytest.fixture(scope="module")
def point_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    work = tmp_path_factory.mktemp("point")
    (work / "plan.yaml").write_text(POINT_PLAN)
    gyropipe_cli("simulate", str(work / "plan.yaml"), "--out", str(work / "sim"), check=True)
    out = work / "out"
    gyropipe_cli(
        "run",
        "pipelines/point-gyro.yaml",
        "--input",
        str(work / "sim" / "samples.parquet"),
        "--out",
        str(out),
        "--set",  # stations every 150 m, on purpose: not flagged as long courses here
        "report.max_course_length=200",
        check=True,
    )
    return out


def test_point_gyro_report_has_qc_sigma_and_ellipses(point_run: Path, browser: Any):
    html = point_run / "report.html"
    page = inspect(browser, html)
    assert_self_contained(page, html)
    assert {"fig-ellipses", "fig-qc-0"} <= set(page.figures)

    header = page.headers["listing"]
    for name in ("σ INC", "σ AZI", "Semi-major", "Semi-minor", "QC"):
        assert name in header
    listing = page.tables["listing"]
    stations = pq.read_table(point_run / "compass.stations.parquet")
    assert len(listing) == stations.num_rows
    for name, sigma in (("σ INC", "sigma_inc"), ("σ AZI", "sigma_azi")):
        # two significant digits however small (σ INC is ~4e−5°: not 0.000)
        column = header.index(name)
        values = stations.column(sigma).to_numpy()
        defined = np.isfinite(values)  # σ AZI of a vertical station: undefined, in words
        cells = [r[column] for r in listing]
        assert all(c == "undefined" for c, d in zip(cells, defined, strict=True) if not d)
        cells = [c for c, d in zip(cells, defined, strict=True) if d]
        assert all(re.fullmatch(r"\d\.\de−\d|0\.0*[1-9]\d|[1-9]\.\d|[1-9]\d", c) for c in cells), (
            cells
        )
        assert [number(c) for c in cells] == pytest.approx(values[defined], rel=0.05)
    trajectory = pq.read_table(point_run / "uncertainty.trajectory.parquet")
    column = header.index("Semi-major")
    assert [number(r[column]) for r in listing] == pytest.approx(
        trajectory.column("ellipse_major_conf").to_numpy(), abs=5e-3
    )
    flags = stations.column("flags").to_pylist()
    for row, flag in zip(listing, flags, strict=True):
        assert (row[-1] == "ok") == (not flag and True)
        for word in filter(None, (flag or "").split(",")):
            assert COMPASS[word].label in row[-1]
    assert "WGS84 normal gravity" in page.text and "GYRO-NS" in page.text

    qc = pq.read_table(point_run / "validity.qc.parquet").to_pylist()
    summary = {r[0]: r for r in page.tables["qc"]}
    assert set(CLIENT_TITLES) <= {r["check"] for r in qc if r["passed"] is not None}
    for check, title in CLIENT_TITLES.items():  # the summary names each check for a client
        evaluated = [r for r in qc if r["check"] == check and r["passed"] is not None]
        assert int(summary[title][2]) == len(evaluated)
        assert int(summary[title][4]) == sum(not r["passed"] for r in evaluated)


def test_ellipse_columns_name_axes_model_and_confidence(point_run: Path, browser: Any):
    """Beside the listing, in the HTML and the PDF: the ellipse columns are semi-axes, at the
    pipeline's 95 % confidence, of the GYRO-NS error model (its title)."""
    note = (
        "Ellipse columns: semi-major and semi-minor axes of the horizontal error ellipse, "
        "azimuth of its major axis and vertical half-interval; confidence level 95 %; "
        "error model OWSG north-seeking gyro, stationary (GYRO-NS, A020Gb)."
    )
    text = inspect(browser, point_run / "report.html").text
    assert text.index("Semi-major") < text.index(note)  # right after the listing's table
    if shutil.which("pdftotext") is None:
        pytest.skip("pdftotext not found: apt-get install poppler-utils")
    pdf = subprocess.run(
        ["pdftotext", str(point_run / "report.pdf"), "-"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert note in " ".join(pdf.split())


def test_point_gyro_pdf_draws_every_figure(point_run: Path, tmp_path: Path):
    """Every figure is on its page as vector graphics (the PDF embeds no image), and it is
    the figure of the HTML: the same drawing, so the same words (tick labels, axis names)
    on the PDF page as in the HTML's SVG."""
    pages = pdf_pages(point_run / "report.pdf", tmp_path)
    regions = figure_regions(pages)
    assert sorted(regions) == list(range(1, 7))  # plan, section, 3-D, profiles, ellipses, QC
    for k, region in regions.items():
        assert ink(region) > 0.02 and colour(region) > 0.002, k
    assert pdf_images(point_run / "report.pdf") == []
    assert len(html_figure_sizes(point_run / "report.html")) == 6
    svg = figure_svg(point_run / "report.html", "profiles")
    labels = [t for t in re.findall(r"<text[^>]*>([^<]*)</text>", svg)]
    words = {w[0] for p in pages for w in p.words}
    assert "Inclination" in words and {"0", "90", "180", "270", "360"} <= words
    assert {w for label in labels for w in label.split()} <= words


def test_qc_chart_axes_fit_their_data(point_run: Path, browser: Any):
    """rest_gyro's values (~12 °/h) against a ±100 °/h band: its axis is scaled to the values
    and the legend gives the band; earth_rate_fit's band is not much wider than its values
    and is drawn in full (#18 item 8)."""
    qc = [r for r in pq.read_table(point_run / "validity.qc.parquet").to_pylist() if r["passed"]]
    svg = figure_svg(point_run / "report.html", "qc-0")

    def ticks(panel: str) -> list[float]:
        return [number(t) for t in svg_texts(browser, svg, f"#{panel} g.ytick text")]

    def legend(panel: str) -> list[str]:
        return svg_texts(browser, svg, f"#{panel} g.legend text")

    rest = [r["measured"] for r in qc if r["check"] == "rest_gyro"]
    limit = max(r["tolerance"] for r in qc if r["check"] == "rest_gyro")
    assert limit == 100 and 5 < max(rest) < limit / 5
    shown = ticks("qc-rest_gyro")
    assert max(rest) <= max(shown) + 2.5 and max(shown) < limit / 4  # ~0…14, not ±100
    assert legend("qc-rest_gyro") == ["tolerance 0 to 100 °/h (beyond the axis)"]

    fit = min(r["tolerance"] for r in qc if r["check"] == "earth_rate_fit")
    assert max(ticks("qc-earth_rate_fit")) >= fit * 0.8 and legend("qc-earth_rate_fit") == []


def test_qc_charts_are_titled_for_a_client(point_run: Path, browser: Any, tmp_path: Path):
    """Each QC chart has a plain title, not the check's internal name, and its y axis says
    what is plotted with its unit: rest_gyro plots the largest per-axis standard deviation
    of the gyros (°/h), not "measured − reference" (#28 item 9); the PDF says the same."""
    svg = figure_svg(point_run / "report.html", "qc-0")
    texts = svg_texts(browser, svg, "text")
    rest = svg_texts(browser, svg, "#qc-rest_gyro text")
    assert "Tool at rest: gyros" in rest
    assert "largest gyro-axis std. deviation (°/h)" in rest
    assert "largest accelerometer-axis std. deviation (m/s²)" in svg_texts(
        browser, svg, "#qc-rest_acc text"
    )
    assert set(CLIENT_TITLES.values()) <= set(texts)
    assert not [t for t in texts if any(name in t for name in CLIENT_TITLES)]  # no rest_gyro
    assert not [t for t in texts if "deg/h" in t or "m/s2" in t]
    words = " ".join(
        w[0] for page in pdf_pages(point_run / "report.pdf", tmp_path) for w in page.words
    )
    assert all(title in words for title in CLIENT_TITLES.values())
    assert "largest gyro-axis std. deviation (°/h)" in words


def test_ellipse_plot_colours_are_told_apart(point_run: Path):
    """The ellipses of the stations drawn (one colour each, as in their legend) differ
    clearly to normal and to colour-blind eyes: no two near-identical oranges (#28 item 9)."""
    svg = figure_svg(point_run / "report.html", "ellipses")
    shapes = svg[svg.index('<g id="ellipse-shapes"') :]
    legend = shapes[shapes.index('<g class="legend"') :]
    colours = re.findall(r'stroke="(#[0-9a-f]{6})"', legend.split("</g>")[0])
    assert len(colours) == 6 and len(set(colours)) == 6
    for vision in DICHROMACY:
        assert closest_colours(colours, vision) > (25 if vision == "normal" else 12), vision


def test_free_gyro_report_shows_drift_and_in_out_qc(browser: Any, tmp_path: Path):
    plan = ROOT / "examples" / "plans" / "j-well-free-gyro.yaml"
    gyropipe_cli("simulate", str(plan), "--out", str(tmp_path / "sim"), check=True)
    out = tmp_path / "out"
    gyropipe_cli(
        "run",
        "pipelines/free-gyro.yaml",
        "--input",
        str(tmp_path / "sim" / "readings.parquet"),
        "--out",
        str(out),
        check=True,
    )
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    assert {"fig-drift", "fig-qc-0"} <= set(page.figures)
    inout = pq.read_table(out / "drift.qc.parquet")
    rows = {r[0]: r for r in page.tables["qc"]}
    assert int(rows["In-run − out-run azimuth"][2]) == inout.num_rows
    assert int(rows["In-run − out-run azimuth"][4]) == sum(
        not p for p in inout.column("passed").to_pylist()
    )
    # the plan drifts 3 °/h; the report quotes the rate the correction applied and its σ
    # (tests/report/test_fleet_figures.py computes the σ from the readings)
    readings = pq.read_table(out / "drift.readings.parquet")
    slope = np.polyfit(
        readings.column("time").to_numpy() / 3600, readings.column("correction").to_numpy(), 1
    )[0]
    assert slope == pytest.approx(3.0, abs=0.3)
    sigma = readings.column("sigma_drift_rate")[0].as_py()
    assert f"drift rate {slope:.3f} °/h, σ {sigma:.2f} °/h" in page.text
    pages = pdf_pages(out / "report.pdf", tmp_path)
    assert all(ink(r) > 0.02 for r in figure_regions(pages).values())


def static_record(path: Path, hours: float = 0.5, rate: float = 20.0) -> None:
    """A tool at rest, vertical, frame x north, sampled at ``rate`` Hz through the
    simulator's sensor model (mems-vrg preset)."""
    tool = tool_preset("mems-vrg")
    rng = np.random.default_rng(11)
    t = np.arange(int(hours * 3600 * rate)) / rate
    lat = np.radians(61.25)
    omega = np.degrees(OMEGA_EARTH) * 3600 * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    g = np.array([0.0, 0.0, 9.81998])
    gyro = measure(
        np.tile(omega, (t.size, 1)), tool.gyro, t, rng, specific_force=np.tile(g, (t.size, 1))
    )
    acc = measure(np.tile(g, (t.size, 1)), tool.accelerometer, t, rng)
    columns: dict[str, Any] = {"time": t}
    columns.update({f"gyro_{a}": gyro[:, i] for i, a in enumerate("xyz")})
    columns.update({f"acc_{a}": acc[:, i] for i, a in enumerate("xyz")})
    pq.write_table(RawSamples.compiled().make_table(columns), path)


ALLAN_PIPELINE = """
name: survey-with-noise
version: "1.0"
inputs:
  stations: {description: survey stations}
  static: {description: static record of the tool}
well: {north_reference: "true"}
stages:
  - {id: read, uses: read_stations, with: {input: stations}}
  - {id: static, uses: read_samples, with: {input: static}}
  - {id: trajectory, uses: minimum_curvature, inputs: {stations: read.stations}}
  - {id: noise, uses: allan, inputs: {samples: static.samples}, persist: [noise]}
  - id: report
    uses: report
    with: {formats: [html]}
    inputs: {trajectory: trajectory.trajectory, allan: noise.allan, noise: noise.noise}
"""


def test_allan_section_from_a_static_record(browser: Any, tmp_path: Path):
    static_record(tmp_path / "static.parquet")
    (tmp_path / "p.yaml").write_text(textwrap.dedent(ALLAN_PIPELINE))
    out = tmp_path / "out"
    gyropipe_cli(
        "run",
        str(tmp_path / "p.yaml"),
        "--input",
        "stations=examples/stations-j-well.csv",
        "--input",
        f"static={tmp_path / 'static.parquet'}",
        "--out",
        str(out),
        check=True,
    )
    assert not (out / "report.pdf").exists()
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    assert "fig-allan" in page.figures
    svg = figure_svg(out / "report.html", "allan")
    assert "10⁻" in svg or "0.0" in svg  # decade labels of the log axes
    noise = pq.read_table(out / "noise.noise.parquet").to_pylist()
    shown = page.tables["noise"]
    assert [r[0] for r in shown] == ["gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z"]
    for row, expected in zip(shown, noise, strict=True):
        value, unit = row[1].split(" ", 1)
        assert number(value) == pytest.approx(expected["arw"], rel=5e-3)
        assert unit == expected["arw_unit"]


CONTINUOUS_PLAN = """
name: report-continuous
seed: 4
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 400}
    - {kind: build, dls: 3.0, inc: 30, azi: 60}
    - {kind: hold, to_md: 900}
tool: {preset: mems-vrg, overrides: {sample_rate: 20}}
survey: {mode: continuous, start_md: 350, end_md: 800, speed: 2.0}
"""


@pytest.fixture(scope="module")
def continuous_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """continuous-gyro.yaml on a simulated run that starts near vertical (so it is integrated
    from the end stop alone: no closure) and ends 0.2 m past the last 10 m station."""
    work = tmp_path_factory.mktemp("continuous")
    (work / "plan.yaml").write_text(CONTINUOUS_PLAN)
    gyropipe_cli("simulate", str(work / "plan.yaml"), "--out", str(work / "sim"), check=True)
    out = work / "out"
    samples = str(work / "sim" / "samples.parquet")
    gyropipe_cli(
        "run", "pipelines/continuous-gyro.yaml", "--input", samples, "--out", str(out), check=True
    )
    return out


def test_continuous_report_names_the_integration_flags(continuous_run: Path, browser: Any):
    out = continuous_run
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    assert "GYRO-NS-CT" in page.text
    stations = pq.read_table(out / "continuous.stations.parquet")
    listing = page.tables["listing"]
    assert len(listing) == stations.num_rows
    flags = stations.column("flags").to_pylist()
    assert any(flags) and not all(f & FLAG_NEAR_VERTICAL for f in flags)  # starts vertical
    for row, flag in zip(listing, flags, strict=True):
        assert (row[-1] == "ok") == (flag == 0)
        if flag:
            assert describe_flags(flag) in row[-1]
    header = page.headers["listing"]
    trajectory = pq.read_table(out / "uncertainty.trajectory.parquet")
    column = header.index("Semi-major")
    assert [number(r[column]) for r in listing] == pytest.approx(
        trajectory.column("ellipse_major_conf").to_numpy(), abs=5e-3
    )


def test_short_last_course_is_not_the_maximum_dls(continuous_run: Path, browser: Any, tmp_path):
    """The last course ends 0.2 m after the previous station: its DLS spike is marked in
    the listing, left out of the summary's maximum and counted there in words (#18 item 4)."""
    trajectory = pq.read_table(continuous_run / "uncertainty.trajectory.parquet")
    md, dls = trajectory.column("md").to_numpy(), trajectory.column("dls").to_numpy()
    course = np.diff(md)
    assert course[-1] < 1.0 and (course[:-1] > 9.99).all()
    assert dls[-1] > 2 * dls[:-1].max()  # the spike the old summary headlined (8.3 vs 3.5)
    worst = int(np.argmax(dls[:-1]))
    expected = (
        f"Maximum DLS {dls[worst]:.2f} °/30 m at {md[worst]:.2f} m MD "
        "(courses shorter than 10 m not counted: 1)"
    )
    page = inspect(browser, continuous_run / "report.html")
    assert expected in " ".join(page.text.split())
    column = page.headers["listing"].index("DLS")
    rows = marks(browser, continuous_run / "report.html")["listing"]
    assert [r.cells[column] for r in rows] == [False] * (len(rows) - 1) + [True]
    assert "DLS over courses shorter than 10 m (left out of the maximum DLS)" in page.text

    pages = pdf_pages(continuous_run / "report.pdf", tmp_path)
    words = " ".join(w[0] for p in pages for w in p.words)
    assert expected.removeprefix("Maximum DLS ") in words  # labels and values drawn apart
    last = f"{md[-1]:.2f}"
    page_of_last = next(p for p in pages if any(w[0] == last and w[1] < 80 for w in p.words))
    line = line_words(page_of_last, last)
    cell = next(w for w in line if w[0] == f"{dls[-1]:.2f}")
    assert (
        flagged_share(page_of_last.region(cell[1] - 1, cell[2] - 1, cell[3] + 1, cell[4] + 1)) > 0.3
    )
    first = line[0]  # the MD cell of the same row is not highlighted
    assert (
        flagged_share(page_of_last.region(first[1] - 1, first[2] - 1, first[3] + 1, first[4] + 1))
        < 0.05
    )


def test_min_course_length_zero_counts_every_course(continuous_run: Path, tmp_path: Path):
    out = tmp_path / "out"
    samples = continuous_run.parent / "sim" / "samples.parquet"
    gyropipe_cli(
        "run",
        "pipelines/continuous-gyro.yaml",
        "--input",
        str(samples),
        "--out",
        str(out),
        "--set",
        "report.min_course_length=0",
        "--set",
        "report.formats=[html]",
        check=True,
    )
    trajectory = pq.read_table(out / "uncertainty.trajectory.parquet")
    md, dls = trajectory.column("md").to_numpy(), trajectory.column("dls").to_numpy()
    html = (out / "report.html").read_text(encoding="utf-8")
    assert f"<dd>{dls[-1]:.2f} °/30 m at {md[-1]:.2f} m MD</dd>" in html
    assert "not counted" not in html


def test_sigma_azimuth_near_vertical_is_undefined_and_said_why(continuous_run: Path, browser: Any):
    """σ AZI is infinite at the near-vertical stations: the cell says 'undefined' and a
    note says why, once (#18 item 5)."""
    stations = pq.read_table(continuous_run / "continuous.stations.parquet")
    sigma = stations.column("sigma_azi").to_numpy()
    assert np.isinf(sigma).any() and np.isfinite(sigma).any()
    page = inspect(browser, continuous_run / "report.html")
    column = page.headers["listing"].index("σ AZI")
    cells = [r[column] for r in page.tables["listing"]]
    assert [c == "undefined" for c in cells] == list(np.isinf(sigma))
    assert "∞" not in page.text
    why = "σ AZI undefined: near vertical the inclination does not define an azimuth"
    assert page.text.count(why) == 1
    assert all(
        number(c) == pytest.approx(v, rel=0.05)
        for c, v in zip(cells, sigma, strict=True)
        if np.isfinite(v)
    )


def test_each_flag_is_explained_once_and_marks_its_cells(
    continuous_run: Path, browser: Any, tmp_path: Path
):
    """Every flag in the listing has one sentence in the QC section; a processing flag
    highlights the QC cell and the values it applies to, never a whole row; no internal
    names in the text (#18 item 7)."""
    html = continuous_run / "report.html"
    page = inspect(browser, html)
    stations = pq.read_table(continuous_run / "continuous.stations.parquet")
    bits = stations.column("flags").to_pylist()
    present = [flag for bit, flag in CONTINUOUS.items() if any(b & bit for b in bits)]
    assert CONTINUOUS[FLAG_NO_CLOSURE] in present and all(b & FLAG_NO_CLOSURE for b in bits)
    explained = page.tables["flags"]
    assert [r[0] for r in explained] == [f.label for f in present]
    for row, flag in zip(explained, present, strict=True):
        assert row[1] == "processing flag"
        assert int(row[2]) == sum(
            1 for b in bits if b & next(k for k, v in CONTINUOUS.items() if v == flag)
        )
        assert row[3].lower() == flag.meaning.lower()
        assert page.text.count(flag.meaning[1:]) == 1  # once, in the QC section
    closure = next(r for r in explained if r[0] == "no closure")
    assert closure[3].startswith("The run was integrated from one stop only")
    assert "no station failed a check" in page.text and "seed" not in page.text.lower()

    header = page.headers["listing"]
    rows = marks(browser, html)["listing"]
    qc, azi, sigma_azi = header.index("QC"), header.index("AZI"), header.index("σ AZI")
    assert not any(r.row for r in rows)  # nobody failed QC: no row turns colour
    for r, b in zip(rows, bits, strict=True):
        assert r.cells[qc]
        assert r.cells[azi] == bool(b & AZIMUTH_FLAGS)
        assert r.cells[sigma_azi] == bool(b & (FLAG_NEAR_VERTICAL | FLAG_AZIMUTH_UNDEFINED))
        assert not all(r.cells)
        assert len(set(r.colours)) == 2  # highlighted cells one colour, the others another

    pages = pdf_pages(continuous_run / "report.pdf", tmp_path)
    words = " ".join(w[0] for p in pages for w in p.words)
    assert "Flags in the listing" in words
    assert "The run was integrated from one stop only" in words


AZIMUTH_FLAGS = (
    FLAG_NEAR_VERTICAL | FLAG_AFTER_VERTICAL | FLAG_LARGE_MISALIGNMENT | FLAG_AZIMUTH_UNDEFINED
)
"""Continuous-mode flags that qualify the azimuth."""


def test_continuous_report_draws_every_sample_from_the_streamed_series(
    continuous_run: Path, browser: Any
):
    """The report's `series` port is streamed: the full-rate series is reduced batch by
    batch and drawn as one figure whose caption counts every sample of the run."""
    series = read_tables(continuous_run / "processed.mcap")[0]["series"]
    page = inspect(browser, continuous_run / "report.html")
    assert "fig-fullrate" in page.figures
    assert f"the {series.num_rows:,} samples of the run" in page.text
    shown = next(s for s in page.svgs if s["figure"] == "fig-fullrate")
    assert shown["shown"] > 500 and shown["texts"] > 10

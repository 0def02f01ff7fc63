"""Survey reports of simulated runs with everything wired: validity QC charts, compassing σ
and flags, error ellipses (point-gyro.yaml), drift correction and in/out-run QC
(free-gyro.yaml), Allan deviation and noise terms (an allan stage on a static record)."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from report_support import (
    assert_self_contained,
    colour,
    figure_regions,
    ink,
    inspect,
    pdf_pages,
    run_ok,
)

from pipeline.continuous.tables import FLAG_NEAR_VERTICAL, describe_flags
from pipeline.earth.frames import OMEGA_EARTH
from pipeline.sim.sensors import measure, tool_preset
from pipeline.tables import RawSamples
from tests_support import ROOT

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


def number(cell: str) -> float:
    return float(cell.replace("−", "-"))


@pytest.fixture(scope="module")
def point_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    work = tmp_path_factory.mktemp("point")
    (work / "plan.yaml").write_text(POINT_PLAN)
    run_ok("simulate", str(work / "plan.yaml"), "--out", str(work / "sim"))
    out = work / "out"
    run_ok(
        "run",
        "pipelines/point-gyro.yaml",
        "--input",
        str(work / "sim" / "samples.parquet"),
        "--out",
        str(out),
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
    column = header.index("σ AZI")
    assert [number(r[column]) for r in listing] == pytest.approx(
        stations.column("sigma_azi").to_numpy(), abs=5e-4
    )
    trajectory = pq.read_table(point_run / "uncertainty.trajectory.parquet")
    column = header.index("Semi-major")
    assert [number(r[column]) for r in listing] == pytest.approx(
        trajectory.column("ellipse_major_conf").to_numpy(), abs=5e-3
    )
    flags = stations.column("flags").to_pylist()
    for row, flag in zip(listing, flags, strict=True):
        assert (row[-1] == "ok") == (not flag and True)
        for word in filter(None, (flag or "").split(",")):
            assert word in row[-1]
    assert "WGS84 normal gravity" in page.text and "GYRO-NS" in page.text

    qc = pq.read_table(point_run / "validity.qc.parquet").to_pylist()
    summary = {r[0]: r for r in page.tables["qc"]}
    for check in {r["check"] for r in qc if r["passed"] is not None}:
        evaluated = [r for r in qc if r["check"] == check and r["passed"] is not None]
        assert int(summary[check][2]) == len(evaluated)
        assert int(summary[check][4]) == sum(not r["passed"] for r in evaluated)


def test_point_gyro_pdf_draws_every_figure(point_run: Path, tmp_path: Path):
    pages = pdf_pages(point_run / "report.pdf", tmp_path)
    regions = figure_regions(pages)
    assert sorted(regions) == list(range(1, 7))  # plan, section, 3-D, profiles, ellipses, QC
    for k, region in regions.items():
        assert ink(region) > 0.02 and colour(region) > 0.002, k


def test_free_gyro_report_shows_drift_and_in_out_qc(browser: Any, tmp_path: Path):
    plan = ROOT / "examples" / "plans" / "j-well-free-gyro.yaml"
    run_ok("simulate", str(plan), "--out", str(tmp_path / "sim"))
    out = tmp_path / "out"
    run_ok(
        "run",
        "pipelines/free-gyro.yaml",
        "--input",
        str(tmp_path / "sim" / "readings.parquet"),
        "--out",
        str(out),
    )
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    assert {"fig-drift", "fig-qc-0"} <= set(page.figures)
    inout = pq.read_table(out / "drift.qc.parquet")
    rows = {r[0]: r for r in page.tables["qc"]}
    assert int(rows["in/out azimuth"][2]) == inout.num_rows
    assert int(rows["in/out azimuth"][4]) == sum(not p for p in inout.column("passed").to_pylist())
    # the plan drifts 3 °/h; the report quotes the rate the correction applied
    readings = pq.read_table(out / "drift.readings.parquet")
    slope = np.polyfit(
        readings.column("time").to_numpy() / 3600, readings.column("correction").to_numpy(), 1
    )[0]
    assert slope == pytest.approx(3.0, abs=0.3)
    assert f"grows at {slope:.3g} °/h" in page.text
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
    with: {formats: [html], image_format: svg}
    inputs: {trajectory: trajectory.trajectory, allan: noise.allan, noise: noise.noise}
"""


def test_allan_section_from_a_static_record(browser: Any, tmp_path: Path):
    static_record(tmp_path / "static.parquet")
    (tmp_path / "p.yaml").write_text(textwrap.dedent(ALLAN_PIPELINE))
    out = tmp_path / "out"
    run_ok(
        "run",
        str(tmp_path / "p.yaml"),
        "--input",
        "stations=examples/stations-j-well.csv",
        "--input",
        f"static={tmp_path / 'static.parquet'}",
        "--out",
        str(out),
    )
    assert not (out / "report.pdf").exists()
    page = inspect(browser, out / "report.html")
    assert_self_contained(page, out / "report.html")
    assert "fig-allan" in page.figures
    assert all(i["src"].startswith("data:image/svg+xml") for i in page.images)
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


def test_continuous_report_names_the_integration_flags(browser: Any, tmp_path: Path):
    (tmp_path / "plan.yaml").write_text(CONTINUOUS_PLAN)
    run_ok("simulate", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "sim"))
    out = tmp_path / "out"
    samples = str(tmp_path / "sim" / "samples.parquet")
    run_ok("run", "pipelines/continuous-gyro.yaml", "--input", samples, "--out", str(out))
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

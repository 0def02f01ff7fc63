"""The fleet page's figures are the well's documents' own: the largest DLS by the rule of
the run's survey report (the same number as the report), figures of a run persisted as CSV,
and a free-gyro survey's drift rate with its σ — each checked against what the test
computes itself from the files (the CLI in process; ``gp.fleet_page`` for the API)."""

from __future__ import annotations

import contextlib
import csv
import html
import json
import math
import re
import shutil
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml

import pipeline as gp
from pipeline.batch import filestate
from tests_support import ROOT, gyropipe_cli, pipeline_yaml, stage, survey_stages

STATIONS = ROOT / "examples" / "stations-j-well.csv"


def page_rows(page: Path) -> dict[str, list[str]]:
    """Per well (its row's header cell), the text of each cell, tags dropped."""
    rows = re.findall(r'<tr class="s-[a-z]+">(.*?)</tr>', page.read_text(encoding="utf-8"))
    found = {}
    for row in rows:
        cells = re.findall(r"<t[hd][^>]*>(.*?)</t[hd]>", row)
        text = [
            html.unescape(re.sub(r"<div[^>]*>", " | ", re.sub(r"</div>", "", c))) for c in cells
        ]
        found[text[0]] = [re.sub(r"<[^>]+>", "", t).strip() for t in text]
    return found


HEADS = ["well", "status", "qc", "acceptance", "clearance", "drift", "td_md", "td_tvd", "dls"]


def cell(rows: dict[str, list[str]], well: str, head: str) -> str:
    return rows[well][HEADS.index(head)]


def with_short_courses(path: Path) -> None:
    """The J well with a 7 m course of 2° more inclination (1980 → 1987 m MD, then back) and
    a 2 m course of 4° more at the bottom: spikes of DLS over short courses."""
    lines = STATIONS.read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("MD (m)"))
    rows = [line.split(",") for line in lines[header + 1 :]]
    out = lines[: header + 1]
    for md, inc, azi in rows:
        out.append(f"{md},{inc},{azi}")
        if float(md) == 1980.0:
            out.append(f"1987.00,{float(inc) + 2.0:.2f},{azi}")
    md, inc, azi = rows[-1]
    out.append(f"{float(md) + 2.0:.2f},{float(inc) + 4.0:.2f},{azi}")
    path.write_text("\n".join(out) + "\n")


def short_well_batch(tmp_path: Path) -> tuple[list[Any], Path]:
    """The arguments of a batch of the short-course well SHORT through the survey stages
    without a report, and its output directory."""
    wells = tmp_path / "in"
    wells.mkdir()
    with_short_courses(wells / "SHORT.csv")
    pipeline = tmp_path / "bare.yaml"
    pipeline.write_text(pipeline_yaml(survey_stages(), name="bare"))
    out = tmp_path / "out"
    return ["batch", pipeline, "--inputs", f"{wells}/*.csv", "--out", out], out


def largest(md: list[float], dls: list[float], shortest: float) -> float:
    """The largest DLS over courses at least ``shortest`` m long (the first station ends
    no course)."""
    return max(d for k, d in enumerate(dls) if k and md[k] - md[k - 1] >= shortest)


def report_max_dls(report: Path) -> str:
    """The summary's 'Maximum DLS' value of a survey report (HTML)."""
    text = html.unescape(re.sub(r"<[^>]+>", "\n", report.read_text(encoding="utf-8")))
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[lines.index("Maximum DLS") + 1]


def test_the_fleet_states_the_max_dls_of_the_well_s_report(tmp_path: Path) -> None:
    """A report counting courses ≥ 5 m: the fleet page shows its number (the 7 m course's
    spike counted, the 2 m one's not); a run without a report: the report's default, 10 m,
    said so under the figure."""
    wells = tmp_path / "in"
    wells.mkdir()
    with_short_courses(wells / "SHORT.csv")
    report = stage(
        "report",
        "report",
        {"trajectory": "trajectory.trajectory"},
        formats=["html"],
        min_course_length=5.0,
    )
    reported = tmp_path / "reported.yaml"
    reported.write_text(pipeline_yaml([*survey_stages(), report], name="reported"))
    bare = tmp_path / "bare.yaml"
    bare.write_text(pipeline_yaml(survey_stages(), name="bare"))
    pages = {}
    for pipeline in (reported, bare):
        out = tmp_path / pipeline.stem
        args = ["batch", pipeline, "--inputs", f"{wells}/*.csv", "--out", out]
        gyropipe_cli(*args, check=True)
        pages[pipeline.stem] = page_rows(out / "fleet.html")
    trajectory = pq.read_table(tmp_path / "reported" / "SHORT" / "trajectory.trajectory.parquet")
    md, dls = trajectory["md"].to_pylist(), trajectory["dls"].to_pylist()
    by_report, by_default = largest(md, dls, 5.0), largest(md, dls, 10.0)
    assert max(dls) > 50 > by_report > by_default + 3  # the rules tell the spikes apart
    shown = cell(pages["reported"], "SHORT", "dls")
    assert shown == f"{by_report:.2f} | courses ≥ 5 m, as its report"
    stated = report_max_dls(tmp_path / "reported" / "SHORT" / "report.html")
    k = dls.index(by_report)
    assert stated == (
        f"{by_report:.2f} °/30 m at {md[k]:.2f} m MD (courses shorter than 5 m not counted: 1)"
    )
    assert cell(pages["bare"], "SHORT", "dls") == (
        f"{by_default:.2f} | courses ≥ 10 m (no survey report: its default)"
    )
    # published by an earlier version (batch.json without figures): read back from the
    # tables by the report's default, which the page says is not the run's own
    marker = tmp_path / "reported" / "SHORT" / "batch.json"
    marker.write_text(json.dumps({**json.loads(marker.read_text()), "figures": None}))
    gyropipe_cli("status", tmp_path / "reported", "--html", check=True)
    assert cell(page_rows(tmp_path / "reported" / "fleet.html"), "SHORT", "dls") == (
        f"{by_default:.2f} | courses ≥ 10 m (the report's default: the run's own not recorded)"
    )


def csv_pipeline(directory: Path) -> Path:
    """The survey pipeline, its trajectory and a dogleg check persisted as CSV."""
    stages = [
        *survey_stages(),
        stage(
            "dls",
            "check",
            {"table": "trajectory.trajectory"},
            ["results"],
            check="dls_limit",
            params={"limit": 1.5},
        ),
    ]
    spec = yaml.safe_load(pipeline_yaml(stages, name="as-csv"))
    spec["defaults"] = {"persist_format": "csv"}
    path = directory / "as-csv.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def csv_table(path: Path) -> dict[str, list[str]]:
    """A persisted CSV table's columns by name (units in brackets dropped), as text."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    rows = list(csv.DictReader(lines))
    return {name.split("[")[0]: [r[name] for r in rows] for name in rows[0]}


def parquet_and_csv_batches(directory: Path, out: Path) -> Iterator[str]:
    """The J well as well PQ, then as well CSV, each batched into ``out`` (the survey
    stages, persisted as Parquet, then the CSV pipeline's): each well's name once its
    batch is done."""
    for well in ("PQ", "CSV"):
        (directory / well).mkdir()
        shutil.copyfile(STATIONS, directory / well / f"{well}.csv")
    parquet = directory / "as-parquet.yaml"
    parquet.write_text(pipeline_yaml(survey_stages(), name="as-parquet"))
    for well, pipeline in (("PQ", parquet), ("CSV", csv_pipeline(directory))):
        args = ["batch", pipeline, "--inputs", f"{directory / well}/*.csv", "--out", out]
        gyropipe_cli(*args, check=True)
        yield well


def test_a_run_persisted_as_csv_shows_its_figures(tmp_path: Path) -> None:
    """Two wells in one output directory, one persisted as Parquet, one as CSV: the page of
    ``gyropipe status --html`` (and ``gp.fleet_page``) and of each batch show both wells'
    figures, as the test reads them from each well's own tables."""
    out = tmp_path / "out"
    for well in parquet_and_csv_batches(tmp_path, out):
        assert cell(page_rows(out / "fleet.html"), well, "td_md") == "2520.0"
    csv_traj = csv_table(out / "CSV" / "trajectory.trajectory.csv")
    checks = csv_table(out / "CSV" / "dls.results.csv")
    failed = checks["passed"].count("false")
    assert failed and len(checks["passed"]) == len(csv_traj["md"])
    pq_traj = pq.read_table(out / "PQ" / "trajectory.trajectory.parquet")
    gyropipe_cli("status", out, "--html", check=True)
    for page in (out / "fleet.html", gp.fleet_page(out, tmp_path / "api.html")):
        rows = page_rows(page)
        for well, md, tvd, dls in (
            ("CSV", *([float(v) for v in csv_traj[c]] for c in ("md", "tvd", "dls"))),
            ("PQ", *(pq_traj[c].to_pylist() for c in ("md", "tvd", "dls"))),
        ):
            assert cell(rows, well, "td_md") == f"{md[-1]:.1f}"
            assert cell(rows, well, "td_tvd") == f"{tvd[-1]:.1f}"
            assert cell(rows, well, "dls") == (
                f"{largest(md, dls, 10.0):.2f} | courses ≥ 10 m (no survey report: its default)"
            )
        n = len(csv_traj["md"])
        assert cell(rows, "CSV", "qc").startswith(f"✖ {failed} of {n} failed")
        assert cell(rows, "PQ", "qc") == "—"


def test_an_earlier_version_s_csv_tables_are_not_guessed_from(tmp_path: Path) -> None:
    """A well published before figures were recorded (no figures in its ``batch.json``)
    whose tables were persisted as CSV: CSV keeps no table metadata (a clearance rule, a
    file-position check), so the page shows no figure read from them and says why; the
    same well persisted as Parquet has its figures read back from its tables."""
    out = tmp_path / "out"
    for well in parquet_and_csv_batches(tmp_path, out):
        marker = out / well / "batch.json"
        record = json.loads(marker.read_text())
        del record["figures"]  # as an earlier version wrote it
        marker.write_text(json.dumps(record))
    gyropipe_cli("status", out, "--html", check=True)
    rows = page_rows(out / "fleet.html")
    assert (
        "Output: figures not recorded by the version that ran it, and its tables are CSV, "
        "which keep no table metadata (a clearance rule, a file-position check): not read "
        "(trajectory.trajectory.csv, dls.results.csv); run the well again to show them"
    ) in cell(rows, "CSV", "status")
    assert [cell(rows, "CSV", h) for h in ("qc", "td_md", "td_tvd", "dls")] == ["—"] * 4
    pq_traj = pq.read_table(out / "PQ" / "trajectory.trajectory.parquet")
    assert cell(rows, "PQ", "td_md") == f"{pq_traj['md'].to_pylist()[-1]:.1f}"
    assert "Output:" not in cell(rows, "PQ", "status")


def chi2_sample_median_mean(n: int) -> float:
    """E of the sample median of n χ²₁ values (the mean of the middle two for even n), from
    the order statistics' laws: X₍ⱼ₎ = F⁻¹(U₍ⱼ₎), U₍ⱼ₎ ~ Beta(j, n + 1 − j)."""
    from scipy import integrate, stats

    def order(j: int) -> float:
        law = stats.beta(j, n + 1 - j)
        return integrate.quad(lambda u: stats.chi2.ppf(u, 1) * law.pdf(u), 0, 1, limit=200)[0]

    return float(np.mean([order(j) for j in sorted({(n + 1) // 2, n // 2 + 1})]))


def tie_in_rate(readings: list[dict[str, Any]], tie: int = 0) -> tuple[float, float]:
    """The drift rate (°/h) of a free-gyro survey from its tie station's misclosure and its
    σ, computed here from the readings: the rate's error is that of the two tie readings,
    √2·σ_r over the time between them. σ_r from the in/out differences d_k of the other
    stations: a rate error (the tie-in's) adds to d_k in proportion to the time Δτ_k
    between its readings, so the least-squares line in Δτ is removed, leaving r_k of
    variance 2σ_r²(1 − h_k), h_k = Δτ_k²/ΣΔτ²; σ_r² = median(r_k²/(2(1 − h_k))) over the
    expected sample median of as many χ²₁ values (no pair is an outlier: asserted)."""
    time = np.array([r["time"] for r in readings], float)
    azi = np.array([r["azi"] for r in readings], float)
    first = next(i for i, r in enumerate(readings) if r["station"] == tie and r["run"] == "in")
    last = [i for i, r in enumerate(readings) if r["station"] == tie and r["run"] == "out"][-1]
    span_h = (time[last] - time[first]) / 3600.0
    rate = ((azi[last] - azi[first] + 180.0) % 360.0 - 180.0) / span_h
    runs: dict[str, dict[int, int]] = {"in": {}, "out": {}}
    for i, r in enumerate(readings):
        runs[r["run"]][r["station"]] = i
    both = sorted((set(runs["in"]) & set(runs["out"])) - {tie})
    a, b = (np.array([runs[run][s] for s in both]) for run in ("in", "out"))
    d = (azi[a] - azi[b] + 180.0) % 360.0 - 180.0  # raw: the whole drift is a rate
    gap = (time[a] - time[b]) / 3600.0
    residual = d - gap * (gap @ d) / (gap @ gap)
    ratios = residual**2 / (2.0 * (1.0 - gap**2 / (gap @ gap)))
    variance = float(np.median(ratios)) / chi2_sample_median_mean(len(ratios))
    assert ratios.max() < 25.0 * variance  # within 5 σ: none left out
    return rate, math.sqrt(2.0) * math.sqrt(variance) / span_h


def test_a_free_gyro_survey_s_drift_sigma_is_persisted_and_shown(tmp_path: Path) -> None:
    """pipelines/free-gyro.yaml over a simulated well drifting 3 °/h: the corrected
    readings carry the rate and its σ (deg/h in their fields), the fleet page and the
    report state them — the σ the one of the tie-in misclosure, computed here."""
    plan = ROOT / "examples" / "plans" / "j-well-free-gyro.yaml"
    gyropipe_cli("simulate", plan, "--out", tmp_path / "sim", check=True)
    wells = tmp_path / "in"
    wells.mkdir()
    shutil.copyfile(tmp_path / "sim" / "readings.parquet", wells / "FG-1.parquet")
    out = tmp_path / "out"
    pipeline = ROOT / "pipelines" / "free-gyro.yaml"
    args = ["batch", pipeline, "--inputs", f"{wells}/*.parquet", "--out", out]
    gyropipe_cli(*args, "--well", "latitude=61.25", check=True)
    rate, sigma = tie_in_rate(pq.read_table(wells / "FG-1.parquet").to_pylist())
    assert abs(rate - 3.0) < 4 * sigma and 0 < sigma < 0.3  # the simulated drift
    corrected = pq.read_table(out / "FG-1" / "drift.readings.parquet")
    for name, value in (("drift_rate", rate), ("sigma_drift_rate", sigma)):
        assert corrected.schema.field(name).metadata[b"unit"] == b"deg/h"
        assert corrected[name].to_pylist() == [pytest.approx(value, rel=1e-9)] * len(corrected)
    shown = cell(page_rows(out / "fleet.html"), "FG-1", "drift")
    value, shown_sigma = shown.removesuffix(" °/h").split(" ± ")
    assert float(value) == pytest.approx(rate, abs=5e-4)
    assert float(shown_sigma) == pytest.approx(sigma, rel=0.05)
    report = html.unescape(re.sub(r"<[^>]+>", "", (out / "FG-1" / "report.html").read_text()))
    assert f"drift rate {value} °/h, σ {shown_sigma} °/h" in report
    summary = json.loads((out / "FG-1" / "summary.json").read_text())
    assert summary["units"]["drift_rate"] == "deg/h"
    drift = summary["drift"]
    assert (drift["source"], drift["instrument"], drift["caveats"]) == ("tie_in", None, [])
    assert (drift["rate"], drift["sigma"]) == (
        pytest.approx(rate, rel=1e-9),
        pytest.approx(sigma, rel=1e-9),
    )


def test_figures_an_earlier_version_put_in_the_ledger_read_as_computed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A ledger's figures without the DLS rule (an earlier version's: DLS over every
    course): an ``--only-changed`` batch that skips the well from the ledger alone shows
    them, said so."""
    monkeypatch.setattr(filestate, "SETTLED_S", 0.0)
    args, out = short_well_batch(tmp_path)
    gyropipe_cli(*args, check=True)
    gyropipe_cli(*args, "--only-changed", check=True)  # a worker looks at the publication
    with contextlib.closing(sqlite3.connect(out / "ledger.sqlite")) as db, db:
        (text,) = db.execute("SELECT figures FROM publications").fetchone()
        older = {k: v for k, v in json.loads(text).items() if not k.startswith("dls_")}
        older["max_dls"] = 99.0  # what it said, whatever the tables say now
        db.execute("UPDATE publications SET figures = ?", (json.dumps(older),))
    gyropipe_cli(*args, "--only-changed", check=True)  # known unchanged from the stat alone
    rows = page_rows(out / "fleet.html")
    assert rows["SHORT"][HEADS.index("status")].startswith("○ Skipped")
    assert cell(rows, "SHORT", "dls") == "99.00 | every course"


def test_figures_edited_in_batch_json_are_not_shown(tmp_path: Path) -> None:
    """A ``batch.json`` whose figures hold text where numbers belong (edited by hand): the
    page says so and reads the well's tables instead, saying the rule is not the run's own."""
    args, out = short_well_batch(tmp_path)
    gyropipe_cli(*args, check=True)
    marker = out / "SHORT" / "batch.json"
    record = json.loads(marker.read_text())
    record["figures"]["max_dls"] = "<b>huge</b>"
    marker.write_text(json.dumps(record))
    gyropipe_cli("status", out, "--html", check=True)
    trajectory = pq.read_table(out / "SHORT" / "trajectory.trajectory.parquet")
    md, dls = trajectory["md"].to_pylist(), trajectory["dls"].to_pylist()
    rows = page_rows(out / "fleet.html")
    assert "Output: batch.json: the figures recorded are damaged (read from the tables)" in (
        cell(rows, "SHORT", "status")
    )
    assert cell(rows, "SHORT", "dls") == (
        f"{largest(md, dls, 10.0):.2f} | courses ≥ 10 m (the report's default: the run's own "
        "not recorded)"
    )


DROPPED = {"md": 1234.5, "station": 7, "by": "validity", "checks": ["gravity_total"]}
"""A station dropped, as a worker records it in ``batch.json``."""
EDITED_FIGURES = {
    "a clearance level of markup": {
        "clearance": {"sf": 1.0, "offset": "X", "md": 1.0, "level": "<script>x</script>"}
    },
    "a report outside the well": {"reports": ["../../../elsewhere/report.html"]},
    "a report by an absolute path": {"reports": ["/tmp/report.html"]},
    "a gate named by a number": {"gates": [{"name": 5, "status": "fail", "description": ""}]},
    "a clearance level not text": {
        "clearance": {"sf": 1.0, "offset": "X", "md": 1.0, "level": ["fail"]}
    },
    "a pipeline not text": {"pipeline": {"name": "bare"}},
    "an instrument not text": {
        "drift": [{"rate_deg_h": 0.1, "sigma_deg_h": 0.01, "instrument": ["<i>g</i>"]}]
    },
    **{
        f"QC: {what}": {
            "qc": {"evaluated": 10, "failed": {}, "stations": [], "windows": 0, "dropped": []} | qc
        }
        for what, qc in {
            "a dropped station at MD NaN": {"dropped": [{**DROPPED, "md": math.nan}]},
            "a dropped station at MD inf": {"dropped": [{**DROPPED, "md": math.inf}]},
            "a station index of 7.5": {"dropped": [{**DROPPED, "station": 7.5}]},
            "checks a text (its letters read as checks)": {
                "dropped": [{**DROPPED, "checks": "gravity_total"}]
            },
            "dropped by no stage that drops": {"dropped": [{**DROPPED, "by": "me"}]},
            "a negative count": {"evaluated": -4},
            "a count of NaN": {"failed": {"gravity_total": math.nan}},
            "stations a text": {"stations": "abc"},
        }.items()
    },
}


def test_figures_of_the_wrong_kinds_in_batch_json_are_not_shown(tmp_path: Path) -> None:
    """A ``batch.json`` whose figures hold markup or a path where the page shows a word or
    links a report, or a value of the wrong kind (edited by hand): the page is written, says
    the figures are damaged and shows none of them (no markup, no link out of OUT)."""
    args, out = short_well_batch(tmp_path)
    gyropipe_cli(*args, check=True)
    marker = out / "SHORT" / "batch.json"
    text = marker.read_text()
    for what, edit in EDITED_FIGURES.items():
        record = json.loads(text)
        record["figures"].update(edit)
        marker.write_text(json.dumps(record))
        gyropipe_cli("status", out, "--html", check=True)
        page = (out / "fleet.html").read_text(encoding="utf-8")
        rows = page_rows(out / "fleet.html")
        assert "the figures recorded are damaged" in cell(rows, "SHORT", "status"), what
        assert "<script>" not in page and "<i>" not in page, what
        assert "href=" not in page, what  # the well has no report: nothing is linked
        assert cell(rows, "SHORT", "clearance") == "—", what


def _unrecorded_short_well(tmp_path: Path) -> tuple[Path, Path]:
    """A batch of the short well published as before figures were recorded (its batch.json
    holds none): the batch directory and the well's run.json."""
    args, out = short_well_batch(tmp_path)
    gyropipe_cli(*args, check=True)
    marker = out / "SHORT" / "batch.json"
    record = json.loads(marker.read_text())
    del record["figures"]  # as an earlier version wrote it
    marker.write_text(json.dumps(record))
    return out, out / "SHORT" / "run.json"


def test_a_published_rejects_table_of_a_null_md_is_named_not_a_traceback(
    tmp_path: Path,
) -> None:
    """A well published before figures were recorded, whose compassing rejects (Parquet)
    hold a station of no MD (a table edited, or another writer's): the page is written and
    names the table it could not read — before, ``gyropipe status --html`` died of a
    TypeError; a NaN MD was shown as 'MD nan m'."""
    out, manifest = _unrecorded_short_well(tmp_path)
    run = json.loads(manifest.read_text())
    run["outputs"].append({"file": "compass.rejects.parquet"})
    manifest.write_text(json.dumps(run))
    for md, said in ((None, "md None"), (math.nan, "md nan")):
        rejects = {"station": [3], "md": pa.array([md], pa.float64()), "reason": ["no fix"]}
        pq.write_table(pa.table(rejects), out / "SHORT" / "compass.rejects.parquet")
        gyropipe_cli("status", out, "--html", check=True)
        rows = page_rows(out / "fleet.html")
        assert (
            f"compass.rejects.parquet cannot be read (row 0: {said}, expected a finite MD (m))"
        ) in cell(rows, "SHORT", "status"), said
        assert cell(rows, "SHORT", "qc") == "—", said


def test_a_damaged_run_json_of_a_well_without_recorded_figures_is_shown(
    tmp_path: Path,
) -> None:
    """A well published before figures were recorded whose ``run.json`` lists its stages as
    something other than a list (damaged): the page is written, the figures read back from
    the well's Parquet tables."""
    out, manifest = _unrecorded_short_well(tmp_path)
    run = json.loads(manifest.read_text())
    run["stages"] = 5
    manifest.write_text(json.dumps(run))
    gyropipe_cli("status", out, "--html", check=True)
    trajectory = pq.read_table(out / "SHORT" / "trajectory.trajectory.parquet")
    rows = page_rows(out / "fleet.html")
    assert cell(rows, "SHORT", "td_md") == f"{trajectory['md'].to_pylist()[-1]:.1f}"

"""A station recorded but dropped by a check never vanishes from the QC verdict: a simulated
point survey (stations at MD 0, 100, 200 and 300 m by its plan) with the stop at 200 m
disturbed on disk (pyarrow) — the accelerometers vibrating through one frame position, or
two of its five positions removed from the readings — run through the CLI; the report's
summary and QC section, summary.json and the command line's QC line must each name it.

The vibration is a 0.06 m/s² sine at 7.3 Hz plus white noise of σ 0.03 m/s² on every
accelerometer axis, a sample standard deviation of about √(0.06²/2 + 0.03²) ≈ 0.052 m/s²,
2.6 times the default at-rest limit of 0.02 m/s²."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
from qc_support import FOUR_STOPS

from tests_support import ROOT, gyropipe_cli, tables_of

PLAN = FOUR_STOPS.format(name="dropped-stop")
DISTURBED, POSITION = 2, 1
"""the station (MD 200 m by the plan) and the frame position (the 2nd) made to vibrate"""
PLAN_MD = 200.0
ODOMETER = 0.5
"""m: how far the survey's MD of a station may be from the plan's (odometer errors)"""


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> pa.Table:
    root = tmp_path_factory.mktemp("sim")
    (root / "plan.yaml").write_text(PLAN)
    gyropipe_cli("simulate", root / "plan.yaml", "--out", root / "sim", check=True)
    return pq.read_table(root / "sim" / "samples.parquet")


def _vibrating(samples: pa.Table) -> pa.Table:
    """``samples`` with the accelerometers vibrating through the marked position."""
    marked = pc.and_(
        pc.equal(samples.column("station"), DISTURBED),
        pc.equal(samples.column("position"), POSITION),
    )
    shaken = pc.fill_null(marked, False).to_numpy(zero_copy_only=False)
    t = samples.column("time").to_numpy()[shaken]
    rng = np.random.default_rng(0)
    for axis in ("acc_x", "acc_y", "acc_z"):
        values = samples.column(axis).to_numpy().copy()
        values[shaken] += 0.06 * np.sin(2 * np.pi * 7.3 * t) + rng.normal(0.0, 0.03, t.size)
        i = samples.schema.get_field_index(axis)
        samples = samples.set_column(i, samples.schema.field(axis), pa.array(values))
    return samples


def _run(root: Path, table: pa.Table, pipeline: str, port: str) -> tuple[Path, str]:
    """The shipped ``pipeline`` on ``table`` written to disk; its output directory and the
    command's last line (the run must succeed)."""
    root.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, root / "input.parquet")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / pipeline, "--input", f"{port}={root / 'input.parquet'}",
        "--out", root / "out", check=True,
    )  # fmt: skip
    return root / "out", result.output.strip().splitlines()[-1]


def _summary_verdict(out: Path) -> str:
    """The summary section's QC verdict (the HTML paragraph)."""
    html = (out / "report.html").read_text(encoding="utf-8")
    (verdict,) = re.findall(r'<p class="verdict (\w+)">(QC: [^<]*)</p>', html)
    return f"{verdict[0]}: {verdict[1]}"


def _pdf_text(out: Path) -> str:
    pdf = subprocess.run(
        ["pdftotext", str(out / "report.pdf"), "-"], capture_output=True, text=True, check=True
    )
    return " ".join(pdf.stdout.split())


def _qc(out: Path) -> dict[str, Any]:
    qc: dict[str, Any] = json.loads((out / "summary.json").read_text())["qc"]
    return qc


def _dropped_md(text: str) -> float:
    """The MD (m) a verdict names as dropped."""
    (md,) = re.findall(r"trajectory — MD (\d+\.\d\d) m \(", text)
    return float(md)


def test_a_clean_survey_says_nothing_of_dropped_stations(tmp_path: Path, samples: pa.Table):
    """Undisturbed, every stop is a station: no station dropped anywhere."""
    out, line = _run(tmp_path, samples, "point-gyro.yaml", "samples")
    assert "dropped" not in line and line.startswith("ok: ")
    assert "dropped" not in _summary_verdict(out)
    assert "Stations dropped" not in (out / "report.html").read_text(encoding="utf-8")
    assert _qc(out)["dropped_stations"] == 0 and _qc(out)["dropped"] == []
    assert pq.read_table(out / "trajectory.trajectory.parquet").num_rows == 4


@pytest.mark.parametrize("markers", [True, False], ids=["marked", "detected"])
def test_a_stop_not_at_rest_is_named_where_the_qc_is_stated(
    tmp_path: Path, samples: pa.Table, markers: bool
):
    """The vibrating stop (dwells marked, or found from the signals) fails the at-rest
    check and is dropped: the report warns and names it (never "no station failed a
    check"), its QC section says why, summary.json counts and names it, the command line's
    QC line names it."""
    table = _vibrating(samples)
    if not markers:
        table = table.drop_columns(["station", "position"])
    out, line = _run(tmp_path, table, "point-gyro.yaml", "samples")
    assert pq.read_table(out / "trajectory.trajectory.parquet").num_rows == 3

    verdict = _summary_verdict(out)
    assert verdict.startswith("warn: QC: 1 station recorded was dropped")
    assert "(tool at rest: accelerometers)" in verdict
    assert _dropped_md(verdict) == pytest.approx(PLAN_MD, abs=ODOMETER)
    assert "no station failed a check" not in verdict
    ((md, by, why),) = tables_of(out / "report.html")["dropped"][1:]
    assert (
        float(md) == pytest.approx(PLAN_MD, abs=ODOMETER) and by == "Tool at rest: accelerometers"
    )
    assert "the tool was not at rest" in why and f"frame position {POSITION + 1}" in why
    std = float(re.findall(r"std\. deviation (\d\.\d+) m/s²", why)[0])
    assert 0.03 < std < 0.08  # ≈ 0.052 m/s² by construction (module docstring)
    assert "rest_acc" not in verdict + why  # the check's internal name stays out
    pdf = _pdf_text(out)
    assert "1 station recorded was dropped" in pdf and "Stations dropped" in pdf

    qc = _qc(out)
    assert qc["dropped_stations"] == 1
    ((dropped),) = qc["dropped"]
    assert dropped["dropped_by"] == "validity" and dropped["checks"] == ["rest_acc"]
    assert dropped["md"] == pytest.approx(PLAN_MD, abs=ODOMETER)

    assert line.startswith("ok: ") and "1 station dropped (MD 200." in line
    assert line.endswith(": rest_acc)")


def test_a_stop_compassing_cannot_solve_is_named_in_the_readings_pipeline(
    tmp_path: Path, samples: pa.Table
):
    """Pre-averaged readings whose stop at 200 m kept 3 of its 5 positions: compassing
    cannot solve it (bias and trend need 4), and the report and the command line name it."""
    clean, _ = _run(tmp_path / "clean", samples, "point-gyro.yaml", "samples")
    readings = pq.read_table(clean / "readings.readings.parquet")
    short = pc.and_(
        pc.equal(readings.column("station"), DISTURBED),
        pc.greater_equal(readings.column("position"), 3),
    )
    out, line = _run(tmp_path / "short", readings.filter(pc.invert(short)),
                     "point-gyro-readings.yaml", "readings")  # fmt: skip
    assert pq.read_table(out / "trajectory.trajectory.parquet").num_rows == 3
    verdict = _summary_verdict(out)
    assert verdict.startswith("warn: QC: 1 station recorded was dropped")
    assert "(gyrocompassing)" in verdict and "no station failed a check" not in verdict
    assert _dropped_md(verdict) == pytest.approx(PLAN_MD, abs=ODOMETER)
    ((md, by, why),) = tables_of(out / "report.html")["dropped"][1:]
    assert float(md) == pytest.approx(PLAN_MD, abs=ODOMETER) and by == "Gyrocompassing"
    assert "3 position(s) cannot resolve 4 unknowns" in why
    assert re.fullmatch(r"ok: .* — QC: 1 station dropped \(MD 200\.\d\d m: compassing\)", line)


def test_the_fleet_page_names_a_well_s_dropped_station(tmp_path: Path, samples: pa.Table):
    """A batch of a clean well and one whose stop at 200 m vibrates: the fleet page's QC
    cell of the vibrating well names the station dropped, its MD and the check (as the
    worker recorded it, and as read back from the published tables when batch.json holds
    no figures); the clean well's says nothing of a dropped station."""
    folder = tmp_path / "wells"
    folder.mkdir()
    pq.write_table(samples, folder / "CLEAN.parquet")
    pq.write_table(_vibrating(samples), folder / "SHAKEN.parquet")
    batch = tmp_path / "batch"
    gyropipe_cli(
        "batch", ROOT / "pipelines" / "point-gyro.yaml", "--inputs", f"{folder}/*.parquet",
        "--out", batch, check=True,
    )  # fmt: skip

    def qc_cells() -> dict[str, str]:
        page = (batch / "fleet.html").read_text(encoding="utf-8")
        rows = dict(re.findall(r'<tr class="s-[a-z]+"><th[^>]*>(.*?)</th>(.*?)</tr>', page))
        assert set(rows) == {"CLEAN", "SHAKEN"}, sorted(rows)
        return {w: re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)[1] for w, row in rows.items()}

    def md_named(cell: str) -> float:
        found = r"1 station dropped \(MD (\d+\.\d\d) m: Tool at rest: accelerometers\)"
        (md,) = re.findall(found, cell)
        return float(md)

    cells = qc_cells()
    assert md_named(cells["SHAKEN"]) == pytest.approx(PLAN_MD, abs=ODOMETER)
    assert "dropped" not in cells["CLEAN"], cells["CLEAN"]

    marker = batch / "SHAKEN" / "batch.json"
    record = json.loads(marker.read_text(encoding="utf-8"))
    record.pop("figures")  # as an earlier version published it: read from the tables
    marker.write_text(json.dumps(record), encoding="utf-8")
    gyropipe_cli("status", batch, "--html", check=True)
    cells = qc_cells()
    assert md_named(cells["SHAKEN"]) == pytest.approx(PLAN_MD, abs=ODOMETER)

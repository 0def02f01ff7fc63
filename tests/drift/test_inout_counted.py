"""A free gyro's in-run/out-run comparison is QC like any other check: the command line's
``QC:`` line, summary.json's counts and the fleet page count it (``in_out_inclination``,
``in_out_azimuth``), so an out-run reading off by more than its tolerance fails the run's
verdict everywhere, not only in the report (before: ``ok: …/run.json`` with no QC, and
summary.json's ``qc`` null). The expected counts are taken from the readings file."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tests_support import ROOT, gyropipe_cli

PIPELINE = ROOT / "pipelines" / "free-gyro.yaml"
BUMP_DEG = 8.0
"""added to one out-run azimuth: far beyond the in/out azimuth tolerance (5° at most)"""


@pytest.fixture(scope="module")
def wells(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float, int]:
    """GOOD (the simulated readings) and BAD (one mid-hole out-run azimuth off by
    BUMP_DEG) in one folder; the MD of the bumped reading and the stations read twice."""
    root = tmp_path_factory.mktemp("inout")
    plan = ROOT / "examples" / "plans" / "j-well-free-gyro.yaml"
    gyropipe_cli("simulate", plan, "--out", root / "sim", check=True)
    folder = root / "wells"
    folder.mkdir()
    shutil.copyfile(root / "sim" / "readings.parquet", folder / "GOOD.parquet")
    table = pq.read_table(folder / "GOOD.parquet")
    runs = np.array(table.column("run").to_pylist())
    stations = table.column("station").to_numpy()
    twice = len(set(stations[runs == "in"].tolist()) & set(stations[runs == "out"].tolist()))
    row = int(np.flatnonzero(runs == "out")[(runs == "out").sum() // 2])
    azi = table.column("azi").to_numpy().copy()
    azi[row] += BUMP_DEG
    index = table.schema.get_field_index("azi")
    pq.write_table(
        table.set_column(index, table.schema.field("azi"), pa.array(azi)), folder / "BAD.parquet"
    )
    return folder, float(table.column("md")[row].as_py()), twice


def checks(summary: Path) -> dict[str, dict[str, int]]:
    qc = json.loads(summary.read_text())["qc"]
    assert qc is not None, "summary.json states no QC"
    return {c["check"]: c for c in qc["checks"]}


def test_a_clean_survey_passes_both_in_out_checks(tmp_path: Path, wells) -> None:
    folder, _, twice = wells
    out = tmp_path / "out"
    done = gyropipe_cli("run", PIPELINE, "--input", folder / "GOOD.parquet", "--out", out)
    assert done.returncode == 0, done.stderr
    found = checks(out / "summary.json")
    assert set(found) == {"in_out_inclination", "in_out_azimuth"}
    inc, azi = found["in_out_inclination"], found["in_out_azimuth"]
    assert (inc["evaluated"], inc["failed"], inc["not_evaluated"]) == (twice, 0, 0)
    assert azi["evaluated"] + azi["not_evaluated"] == twice and azi["failed"] == 0
    evaluated = inc["evaluated"] + azi["evaluated"]
    assert done.stdout.strip().splitlines()[-1].endswith(f"QC: all {evaluated} checks passed")


def test_an_out_run_reading_beyond_tolerance_fails_the_verdict_everywhere(
    tmp_path: Path, wells
) -> None:
    folder, md, twice = wells
    out = tmp_path / "out"
    done = gyropipe_cli("run", PIPELINE, "--input", folder / "BAD.parquet", "--out", out)
    assert done.returncode == 0, done.stderr
    last = done.stdout.strip().splitlines()[-1]
    assert last.endswith("QC: 1 failed check (in_out_azimuth: 1) at 1 station"), last
    found = checks(out / "summary.json")
    assert (found["in_out_azimuth"]["failed"], found["in_out_inclination"]["failed"]) == (1, 0)
    assert found["in_out_inclination"]["evaluated"] == twice
    qc = pq.read_table(out / "drift.qc.parquet").to_pylist()
    (failed,) = [r for r in qc if not r["passed"]]
    assert failed["md"] == pytest.approx(md, abs=1e-6)
    assert abs(failed["azi_diff"]) > failed["azi_tolerance"]

    batch = tmp_path / "batch"
    args = ["batch", PIPELINE, "--inputs", f"{folder}/*.parquet", "--out", batch]
    gyropipe_cli(*args, "--well", "latitude=61.25", check=True)
    page = (batch / "fleet.html").read_text(encoding="utf-8")
    rows = dict(re.findall(r'<tr class="s-[a-z]+"><th[^>]*>(.*?)</th>(.*?)</tr>', page))
    assert set(rows) == {"GOOD", "BAD"}, sorted(rows)
    evaluated = found["in_out_inclination"]["evaluated"] + found["in_out_azimuth"]["evaluated"]
    qc_cells = {well: re.findall(r"<td[^>]*>(.*?)</td>", row)[1] for well, row in rows.items()}
    assert f"1 of {evaluated} failed" in qc_cells["BAD"], qc_cells["BAD"]
    assert "failed" not in qc_cells["GOOD"], qc_cells["GOOD"]

"""A stop the tool made that gave no reading is a station dropped by name, not a station
silently missing: a simulated point survey (stations at MD 0, 100, 200 and 300 m by its
plan, five 10 s positions each), its dwells detected from the signals (markers dropped),
with the stop at 200 m disturbed on disk (pyarrow) and run through the CLI:

- *cut short*: the tool held its depth there for 4 s only — the stop keeps its first 4 s
  (the 2 s settle and 2 s of the first position, the frame at 0° as when it leaves) — and
  arrived and left briskly (the last 0.25 m of travel either side, where the plan's smooth
  profile creeps in at under 0.16 m/s, left out): 4 s, less or more by at most half the 1 s
  MD smoothing either side (the depth is judged on the smoothed MD), against the 6 s a
  dwell needs (min_dwell 5 s after trimming 1 s);
- *frame not settling*: the frame angle swings ±1° at 0.7 Hz through the whole stop (its
  64 s by the plan: settle 2 s, five 10 s positions, four 3 s moves), beyond the 0.5° a
  dwell allows.

Before, either stop vanished (three stations, "QC: all 52 checks passed"). Now it is
numbered as station 2 — the stations after it keep the numbers of the undisturbed run — has
no angles, and the report's summary and "Stations dropped" table, summary.json and the
command line's QC line name it with the reason and its numbers. The undisturbed run flags
nothing."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from qc_support import FOUR_STOPS

from tests_support import ROOT, gyropipe_cli, tables_of

PLAN = FOUR_STOPS.format(name="unread-stop")
DISTURBED, PLAN_MD = 2, 200.0
ODOMETER = 0.5
"""m: how far the survey's MD of a station may be from the plan's (odometer errors)"""
HELD, BRISK = 4.0, 0.25
"""s the cut stop keeps; m of creeping travel left out either side of it"""
NEED = 6.0
"""s a dwell needs: the pipeline's trim_start 1 s plus the default min_dwell 5 s"""
STOP = 2 + 5 * 10 + 4 * 3
"""s the undisturbed stop lasts by the plan (settle, positions, moves)"""


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> tuple[pa.Table, pa.Table]:
    """The simulated samples and their truth."""
    root = tmp_path_factory.mktemp("sim")
    (root / "plan.yaml").write_text(PLAN)
    gyropipe_cli("simulate", root / "plan.yaml", "--out", root / "sim", check=True)
    return pq.read_table(root / "sim" / "samples.parquet"), pq.read_table(
        root / "sim" / "truth.parquet"
    )


def _column(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False))


def _retimed(samples: pa.Table, keep: np.ndarray) -> pa.Table:
    """The ``keep`` samples, timed at the sample rate from the first (a recording without
    the samples left out)."""
    time = _column(samples, "time")
    kept = samples.filter(pa.array(keep))
    uniform = time[0] + np.arange(kept.num_rows) * (time[1] - time[0])
    return kept.set_column(0, samples.schema.field("time"), pa.array(uniform))


def _cut_short(samples: pa.Table, truth: pa.Table) -> pa.Table:
    """The disturbed stop kept for its first :data:`HELD` s, reached and left briskly."""
    station = _column(samples, "station")
    stop = np.flatnonzero(station == DISTURBED)
    rate = 1.0 / (_column(samples, "time")[1] - _column(samples, "time")[0])
    keep = np.ones(samples.num_rows, dtype=bool)
    keep[stop[round(HELD * rate) :]] = False
    md = _column(truth, "md")
    creeping = np.isnan(station.astype(float)) & (np.abs(md - md[stop[0]]) < BRISK)
    keep[creeping] = False
    return _retimed(samples, keep)


def _unsettled(samples: pa.Table) -> pa.Table:
    """The disturbed stop's frame angle swinging ±1° at 0.7 Hz."""
    on = _column(samples, "station") == DISTURBED
    time, angle = _column(samples, "time"), _column(samples, "frame_angle").copy()
    angle[on] = (angle[on] + np.sin(2 * np.pi * 0.7 * time[on])) % 360.0
    i = samples.schema.get_field_index("frame_angle")
    return samples.set_column(i, samples.schema.field("frame_angle"), pa.array(angle))


def _run(root: Path, table: pa.Table) -> tuple[Path, str]:
    """``pipelines/point-gyro.yaml`` on ``table`` (markers dropped) written to disk; its
    output directory and the command's last line (the run must succeed)."""
    root.mkdir(parents=True, exist_ok=True)
    pq.write_table(table.drop_columns(["station", "position"]), root / "input.parquet")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "point-gyro.yaml", "--input", root / "input.parquet",
        "--out", root / "out", check=True,
    )  # fmt: skip
    return root / "out", result.output.strip().splitlines()[-1]


def _qc(out: Path) -> dict[str, Any]:
    qc: dict[str, Any] = json.loads((out / "summary.json").read_text())["qc"]
    return qc


def _stations(out: Path) -> dict[int, float]:
    """Station number → MD (m) of the compassed stations."""
    table = pq.read_table(out / "compass.stations.parquet")
    return dict(zip(_column(table, "station").tolist(), _column(table, "md").tolist(), strict=True))


def test_an_undisturbed_survey_flags_no_stop(tmp_path: Path, sim: tuple[pa.Table, pa.Table]):
    """Every stop is read: four stations, no unread stop anywhere, nothing dropped."""
    out, line = _run(tmp_path, sim[0])
    assert sorted(_stations(out)) == [0, 1, 2, 3]
    assert line.startswith("ok: ") and "dropped" not in line and "unread" not in line
    assert _qc(out)["dropped"] == [] and "unread_stop" not in {
        c["check"] for c in _qc(out)["checks"]
    }
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "Stations dropped" not in html and "without a reading" not in html


@pytest.mark.parametrize("disturb", ["cut short", "frame not settling"])
def test_a_stop_without_a_reading_is_numbered_and_named(
    tmp_path: Path, sim: tuple[pa.Table, pa.Table], disturb: str
):
    """The disturbed stop is station 2 without angles; the others keep the undisturbed
    run's numbers; report, summary.json and the QC line say why, with the numbers."""
    samples, truth = sim
    full, _ = _run(tmp_path / "full", samples)
    table = _cut_short(samples, truth) if disturb == "cut short" else _unsettled(samples)
    out, line = _run(tmp_path / "disturbed", table)

    expected = {k: md for k, md in _stations(full).items() if k != DISTURBED}
    found = _stations(out)
    assert sorted(found) == sorted(expected)  # station 3 stays station 3
    for k, md in expected.items():
        assert found[k] == pytest.approx(md, abs=1e-6 if k < DISTURBED else ODOMETER)
    assert pq.read_table(out / "trajectory.trajectory.parquet").num_rows == 3
    readings = pq.read_table(out / "readings.readings.parquet")
    assert DISTURBED not in _column(readings, "station").tolist()

    ((dropped,),) = [_qc(out)["dropped"]]
    assert dropped["station"] == DISTURBED and dropped["checks"] == ["unread_stop"]
    assert dropped["md"] == pytest.approx(PLAN_MD, abs=ODOMETER)
    reason = dropped["reason"]
    assert f"no dwell of ≥ {NEED:.1f} s" in reason
    (md,) = re.findall(r"found at MD (\d+\.\d\d) m", reason)
    assert float(md) == pytest.approx(PLAN_MD, abs=ODOMETER)
    (held,) = re.findall(r"held depth there for (?:only )?(\d+\.\d) s", reason)
    if disturb == "cut short":
        assert "for only" in reason and float(held) == pytest.approx(HELD, abs=1.0)
    else:
        assert "frame angle did not stay within 0.5°" in reason
        assert STOP <= float(held) <= STOP + 15  # the plan's creeping ends of travel too

    assert line.startswith("ok: ") and "1 station dropped (MD 200." in line
    assert f"unread_stop — {reason})" in line

    html = out / "report.html"
    ((table_md, by, why),) = tables_of(html)["dropped"][1:]
    assert float(table_md) == pytest.approx(PLAN_MD, abs=ODOMETER)
    assert by == "Stop without a reading" and reason[:1].upper() + reason[1:] in why
    (verdict,) = re.findall(r'<p class="verdict \w+">(QC: [^<]*)</p>', html.read_text("utf-8"))
    assert verdict.startswith("QC: 1 station recorded was dropped")
    assert "(stop without a reading)" in verdict and "no station failed" not in verdict

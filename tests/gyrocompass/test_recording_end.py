"""A stop the end of the recording cuts short is flagged, never averaged quietly: simulated
point and continuous surveys truncated inside their last stop (pyarrow, on disk), run
through the CLI.

The expected numbers come from the plans and the simulator's own station/position markers:
10 s dwells at 100 Hz, 1 s trimmed at each dwell's start (pipelines/point-gyro.yaml), so a
complete position is averaged over 9.00 s and one cut 6 s after its first sample over
5.00 s."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest

from pipeline.continuous import FLAG_SHORT_STOP
from tests_support import ROOT, gyropipe_cli

SITE = """site:
  latitude: 61.25
  longitude: 73.4
  elevation: 54.3
  date: 2026-11-21
tool: {preset: mems-vrg}
"""
POINT = (
    "name: short-stops\nseed: 3\n"
    + SITE
    + """well:
  sections:
    - {kind: vertical, length: 50}
    - {kind: build, dls: 6.0, inc: 30, azi: 37}
    - {kind: hold, to_md: 300}
survey: {mode: point, every: 100, positions: [0, 90, 180, 270, 0], dwell: 10}
"""
)
CONTINUOUS = (
    "name: short-run\nseed: 4\n"
    + SITE
    + """well:
  sections:
    - {kind: vertical, length: 60}
    - {kind: build, dls: 6.0, inc: 30, azi: 37}
    - {kind: hold, to_md: 300}
survey:
  mode: continuous
  start_md: 20
  end_md: 280
  speed: 2.0
  stop: {dwell: 10}
"""
)
USUAL = 9.0
"""s: a complete position's averaging time (10 s dwell less the 1 s start trim)"""


@pytest.fixture(scope="module")
def point_samples(tmp_path_factory: pytest.TempPathFactory) -> pa.Table:
    return _simulate(tmp_path_factory.mktemp("point"), POINT)


@pytest.fixture(scope="module")
def continuous_samples(tmp_path_factory: pytest.TempPathFactory) -> pa.Table:
    return _simulate(tmp_path_factory.mktemp("continuous"), CONTINUOUS)


def _simulate(root: Path, plan: str) -> pa.Table:
    (root / "plan.yaml").write_text(plan)
    gyropipe_cli("simulate", root / "plan.yaml", "--out", root / "sim", check=True)
    return pq.read_table(root / "sim" / "samples.parquet")


def _position_start(samples: pa.Table, station: int, position: int) -> float:
    """Time (s) of the first sample the simulator marked ``station``/``position``."""
    marked = pc.and_(
        pc.equal(samples.column("station"), station), pc.equal(samples.column("position"), position)
    )
    return float(pc.min(samples.column("time").filter(marked)).as_py())


def _last_station(samples: pa.Table) -> int:
    return int(pc.max(samples.column("station")).as_py())


def _run(
    root: Path, samples: pa.Table, before: float | None, pipeline: str = "point-gyro.yaml"
) -> tuple[Path, str]:
    """The pipeline on ``samples`` cut to times < ``before`` (None: whole), written to disk;
    its output directory and stderr (the run must succeed)."""
    root.mkdir(parents=True, exist_ok=True)
    if before is not None:
        samples = samples.filter(pc.less(samples.column("time"), before))
    pq.write_table(samples, root / "samples.parquet")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / pipeline, "--input", root / "samples.parquet",
        "--out", root / "out",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return root / "out", result.stderr


def _rows(out: Path, check: str) -> list[dict[str, object]]:
    qc = pq.read_table(out / "validity.qc.parquet")
    return qc.filter(pc.equal(qc.column("check"), check)).to_pylist()


def _counted(out: Path, check: str) -> dict[str, object]:
    summary = json.loads((out / "summary.json").read_text())
    (count,) = [c for c in summary["qc"]["checks"] if c["check"] == check]
    return dict(count)


def test_a_whole_survey_carries_no_such_flag(tmp_path: Path, point_samples: pa.Table) -> None:
    """The recording ends with the last position complete: its check passes (averaged over
    the usual 9 s), every station has its five positions, nothing is flagged."""
    out, stderr = _run(tmp_path, point_samples, None)
    (end,) = _rows(out, "recording_end")
    assert end["passed"] is True and end["measured"] == pytest.approx(0.0, abs=1e-9)
    assert all(r["passed"] for r in _rows(out, "missing_positions"))
    assert _counted(out, "recording_end")["failed"] == 0
    report = (out / "report.html").read_text(encoding="utf-8")
    for said in ("cut short by end of recording", "frame positions missing", "recording ended"):
        assert said not in report
    flags = pq.read_table(out / "compass.stations.parquet").column("flags").to_pylist()
    assert not any("fewer_positions" in f for f in flags)
    assert "warning" not in stderr


def test_a_last_position_cut_mid_dwell_is_flagged_with_its_averaging_time(
    tmp_path: Path, point_samples: pa.Table
) -> None:
    """Cut 6 s into the last position: averaged over 5.00 s of the usual 9.00 s, flagged
    in the QC table, summary.json and the report (summary line, listing, QC section)."""
    last = _last_station(point_samples)
    out, _ = _run(tmp_path, point_samples, _position_start(point_samples, last, 4) + 6.0)
    (end,) = _rows(out, "recording_end")
    assert (end["station"], end["position"], end["passed"]) == (last, 4, False)
    assert end["measured"] == pytest.approx(USUAL - 5.0, abs=1e-9)
    assert "averaged over 5.00 s" in str(end["detail"]) and "9.00 s" in str(end["detail"])
    assert _counted(out, "recording_end")["failed"] == 1
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "The recording ended during the stop at MD" in report
    assert "cut short by end of recording" in report
    assert "Stations cut short or incomplete" in report
    assert "recording_end" not in report.split("Appendix")[0]  # no internal names above


def test_a_last_position_cut_mid_dwell_is_flagged_without_markers_too(
    tmp_path: Path, point_samples: pa.Table
) -> None:
    """The same cut, the dwells found from the signals (markers dropped), the last sample's
    MD 12 cm over (2.4 σ of the odometer's 5 cm noise): the dwell the recording ended in
    is found to its last sample — the smoothed MD there is the mean of the samples its
    window holds, not the last sample repeated over half the window (6 cm over: out of the
    5 cm tolerance, the dwell ended half a window before the recording and the cut went
    unflagged) — and it is flagged, averaged over 5 s as marked (to the 0.6 s of frame
    move the angle tolerance takes in)."""
    last = _last_station(point_samples)
    cut = point_samples.filter(
        pc.less(point_samples.column("time"), _position_start(point_samples, last, 4) + 6.0)
    )
    md = cut.column("md").to_numpy().copy()
    md[-1] += 0.12
    i = cut.schema.get_field_index("md")
    samples = cut.set_column(i, cut.schema.field(i), pa.array(md))
    out, _ = _run(tmp_path, samples.drop_columns(["station", "position"]), None)
    (end,) = _rows(out, "recording_end")
    assert (end["station"], end["position"], end["passed"]) == (last, 4, False)
    assert "averaged over 5." in str(end["detail"])


@pytest.mark.parametrize("markers", [True, False], ids=["marked", "detected"])
def test_a_last_position_too_short_to_average_is_said_not_dropped_silently(
    tmp_path: Path, point_samples: pa.Table, markers: bool
) -> None:
    """Cut 2 s into the last position (1 s left after trimming, min_dwell 5 s): the survey
    runs (a marked position was an error before), a warning names the stop's MD, the QC
    says the position is missing and compassing flags the station's fewer positions."""
    last = _last_station(point_samples)
    samples = point_samples if markers else point_samples.drop_columns(["station", "position"])
    out, stderr = _run(tmp_path, samples, _position_start(point_samples, last, 4) + 2.0)
    (end,) = _rows(out, "recording_end")
    assert end["passed"] is False and "too short to average" in str(end["detail"])
    (missing,) = [r for r in _rows(out, "missing_positions") if not r["passed"]]
    assert missing["measured"] == 1.0 and missing["md"] == pytest.approx(end["md"], abs=1e-9)
    stations = pq.read_table(out / "compass.stations.parquet")
    assert stations.column("positions").to_pylist()[-1] == 4
    assert "fewer_positions" in stations.column("flags").to_pylist()[-1]
    if markers:
        assert "not averaged" in stderr and f"MD {end['md']:.2f} m" in stderr


def test_a_station_cut_between_positions_is_flagged_incomplete(
    tmp_path: Path, point_samples: pa.Table
) -> None:
    """The recording ends during the frame move after the fourth position: no dwell was cut,
    but the last station has 4 of the usual 5 positions (solved exactly, χ² 0, unflagged
    before): flagged in the QC, the compass solve and the report."""
    last = _last_station(point_samples)
    out, _ = _run(tmp_path, point_samples, _position_start(point_samples, last, 4) - 1.5)
    assert _rows(out, "recording_end") == []
    (missing,) = [r for r in _rows(out, "missing_positions") if not r["passed"]]
    assert missing["station"] == last and missing["measured"] == 1.0
    assert _counted(out, "missing_positions")["failed"] == 1
    stations = pq.read_table(out / "compass.stations.parquet").to_pylist()
    assert stations[-1]["positions"] == 4 and "fewer_positions" in stations[-1]["flags"]
    report = (out / "report.html").read_text(encoding="utf-8")
    assert "frame positions missing" in report and "fewer frame positions" in report


def test_a_continuous_closing_stop_cut_inside_its_last_position_is_flagged(
    tmp_path: Path, continuous_samples: pa.Table
) -> None:
    """As a point survey's: the whole run's closing stop is averaged over the usual 9 s in
    its last position and passes; cut 6 s into that position (not missing: 5.00 s averaged)
    the stop is flagged in the QC table, summary.json and the report."""
    whole, _ = _run(tmp_path / "whole", continuous_samples, None, "continuous-gyro.yaml")
    (end,) = _rows(whole, "recording_end")
    assert (end["station"], end["position"], end["passed"]) == (1, 4, True)
    assert end["measured"] == pytest.approx(0.0, abs=1e-9)
    assert _counted(whole, "recording_end")["failed"] == 0
    report = (whole / "report.html").read_text(encoding="utf-8")
    assert "cut short by end of recording" not in report and "recording ended" not in report
    cut, _ = _run(
        tmp_path / "cut",
        continuous_samples,
        _position_start(continuous_samples, 1, 4) + 6.0,
        "continuous-gyro.yaml",
    )
    (end,) = _rows(cut, "recording_end")
    assert (end["station"], end["position"], end["passed"]) == (1, 4, False)
    assert end["measured"] == pytest.approx(USUAL - 5.0, abs=1e-9)
    assert "averaged over 5.00 s" in str(end["detail"]) and "9.00 s" in str(end["detail"])
    assert all(r["passed"] for r in _rows(cut, "missing_positions"))
    assert _counted(cut, "recording_end")["failed"] == 1
    report = (cut / "report.html").read_text(encoding="utf-8")
    assert f"The recording ended during the stop at MD {end['md']:.2f} m" in report
    assert "cut short by end of recording" in report
    assert "Stations cut short or incomplete" in report
    assert "recording_end" not in report.split("Appendix")[0]  # no internal names above


def test_a_continuous_run_tied_to_an_incomplete_closing_stop_is_flagged(
    tmp_path: Path, continuous_samples: pa.Table
) -> None:
    """The closing stop lacks its last position: every station of the run says its azimuth
    rests on that stop; the whole run carries no such flag."""
    whole, _ = _run(tmp_path / "whole", continuous_samples, None, "continuous-gyro.yaml")
    flags = np.array(pq.read_table(whole / "continuous.stations.parquet").column("flags"))
    assert not (flags & FLAG_SHORT_STOP).any()
    before = _position_start(continuous_samples, 1, 4) - 1.0
    cut, _ = _run(tmp_path / "cut", continuous_samples, before, "continuous-gyro.yaml")
    flags = np.array(pq.read_table(cut / "continuous.stations.parquet").column("flags"))
    assert (flags & FLAG_SHORT_STOP).all()
    assert "tied to a stop with positions missing" in (cut / "report.html").read_text("utf-8")


def test_a_continuous_run_whose_closing_stop_cannot_compass_is_refused(
    tmp_path: Path, continuous_samples: pa.Table
) -> None:
    """One position of the closing stop recorded and a vertical start stop: no azimuth to
    tie the run to — refused with a message naming the stop, not closed on NaN."""
    samples = continuous_samples.filter(
        pc.less(continuous_samples.column("time"), _position_start(continuous_samples, 1, 0) + 8)
    )
    pq.write_table(samples, tmp_path / "samples.parquet")
    result = gyropipe_cli(
        "run", ROOT / "pipelines" / "continuous-gyro.yaml", "--input",
        tmp_path / "samples.parquet", "--out", tmp_path / "out",
    )  # fmt: skip
    assert result.returncode != 0
    assert "stop 1 (MD" in result.stderr and "no stop to tie the run's azimuth to" in result.stderr
    assert "Traceback" not in result.stderr

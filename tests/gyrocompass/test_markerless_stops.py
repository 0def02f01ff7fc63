"""A point survey's samples without station/position markers give the stations of the same
samples with them: simulated surveys (``gyropipe simulate``) run through the shipped
point-gyro pipeline (``gyropipe run``) as simulated and with the ``station`` and
``position`` columns dropped on disk (pyarrow), so that the readings stage finds the dwells
from the frame angle and the MD.

The simulated tool creeps within 5 cm of each stop for seconds at either end of travel
(its MD profile is smooth from rest to rest), turning and accelerating: a markerless dwell
that takes that in reads a tool not at rest, and the validity checks drop the station
(``rest_acc``) — before the fix, one to three of each plan's stations here.

Tolerances: a markerless reading averages the same stop over a few seconds more (the
settling before the first position, which no marker tells from it, the creep the odometer
cannot resolve) or less (cut where it can): the difference of the two estimates is the
noise of those few seconds, ≈ √(their share of the station's samples) ≈ 0.2–0.4 of the
station's compassed σ; a station more than its σ (``sigma_inc``, ``sigma_azi``) off read
something the marked run did not. The station MD (the median odometer MD over thousands of
samples of 5 cm noise each) agrees within 1 cm."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tests_support import gyropipe_cli, without_report

KICKOFF = """name: kickoff
seed: 4
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  start_md: 1200
  start_inc: 0.5
  start_azi: 150
  sections:
    - {kind: curve, dls: 6.0, inc: 4, azi: 200}
    - {kind: hold, length: 20}
tool: {preset: mems-vrg}
survey: {mode: point, every: 10, dwell: 20}
"""
"""Near vertical, stations 10 m apart: travel of 10 s, the tool accelerating hard within
the MD tolerance of each stop (before the fix 3 of its 4 stations were dropped)."""
TANGENT = """name: tangent
seed: 2
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  start_md: 1400
  start_inc: 45
  start_azi: 37
  sections:
    - {kind: hold, length: 450}
tool: {preset: mems-vrg}
survey: {mode: point, every: 90}
"""
"""A 45° tangent, stations 90 m apart: slow creep, the housing rolling in it (before the fix
the station at 1760 m was dropped)."""
PLANS = {"kickoff": (KICKOFF, 4), "tangent": (TANGENT, 6)}
"""plan text, number of stations"""
MD_TOLERANCE = 0.01
"""m: how far a markerless station's MD may be from the marked one's"""


def _run(out: Path, samples: Path, pipeline: Path) -> Path:
    gyropipe_cli(
        "run", pipeline, "--input", f"samples={samples}", "--out", out, check=True
    )  # fmt: skip
    return out


@pytest.fixture(scope="module", params=sorted(PLANS))
def runs(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> dict:
    """The plan's stations count and the point-gyro runs on its samples, marked and
    markerless."""
    plan, stations = PLANS[request.param]
    root = tmp_path_factory.mktemp(request.param)
    (root / "plan.yaml").write_text(plan)
    gyropipe_cli("simulate", root / "plan.yaml", "--out", root / "sim", check=True)
    samples = root / "sim" / "samples.parquet"
    bare = root / "markerless.parquet"
    pq.write_table(pq.read_table(samples).drop_columns(["station", "position"]), bare)
    pipeline = without_report("point-gyro", root)
    return {
        "stations": stations,
        "marked": _run(root / "marked", samples, pipeline),
        "markerless": _run(root / "markerless", bare, pipeline),
    }


def _stations(out: Path) -> pa.Table:
    return pq.read_table(out / "compass.stations.parquet")


def _dropped(out: Path) -> list:
    dropped: list = json.loads((out / "summary.json").read_text())["qc"]["dropped"]
    return dropped


def test_no_station_is_dropped_with_or_without_markers(runs: dict) -> None:
    for kind in ("marked", "markerless"):
        assert _dropped(runs[kind]) == [], kind
        trajectory = pq.read_table(runs[kind] / "uncertainty.trajectory.parquet")
        assert trajectory.num_rows == runs["stations"], kind


def test_markerless_stations_are_the_marked_ones(runs: dict) -> None:
    marked, found = _stations(runs["marked"]), _stations(runs["markerless"])
    assert marked.num_rows == found.num_rows == runs["stations"]
    np.testing.assert_array_equal(found["station"].to_numpy(), marked["station"].to_numpy())
    np.testing.assert_allclose(found["md"].to_numpy(), marked["md"].to_numpy(), atol=MD_TOLERANCE)
    inc = np.abs(found["inc"].to_numpy() - marked["inc"].to_numpy())
    assert np.all(inc <= marked["sigma_inc"].to_numpy()), inc
    azi = np.abs((found["azi"].to_numpy() - marked["azi"].to_numpy() + 180.0) % 360.0 - 180.0)
    assert np.all(azi <= marked["sigma_azi"].to_numpy()), azi

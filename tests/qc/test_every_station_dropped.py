"""A run whose every station the validity checks drop says so where it stops, with the
worst value measured against each limit: the continuous survey of
``examples/plans/bystrinskoye-690m.yaml`` (the tool of Binder & Khazov 2023, whose
accelerometer noise is 10 arc-min per 100 Hz sample: 0.0285 m/s² per axis at rest, above the
at-rest limit of 0.02 m/s² on the sample std) through ``pipelines/continuous-gyro.yaml``.
Before, the run failed with "the stops table has no rows" alone; with the tool's own limit
(0.06 m/s², about twice its noise) the same samples run."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests_support import ROOT, gyropipe_cli

PIPELINE = ROOT / "pipelines" / "continuous-gyro.yaml"
NOISE = 0.0285
"""m/s²: the plan's accelerometer noise per sample (g · sin 10′), the sample std at rest"""


@pytest.fixture(scope="module")
def samples(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("bys")
    plan = ROOT / "examples" / "plans" / "bystrinskoye-690m.yaml"
    gyropipe_cli("simulate", plan, "--out", root / "sim", check=True)
    return root / "sim" / "samples.parquet"


def test_every_stop_dropped_is_told_with_the_limit_it_exceeded(tmp_path: Path, samples: Path):
    done = gyropipe_cli("run", PIPELINE, "--input", samples, "--out", tmp_path / "out")
    assert done.returncode != 0 and not (tmp_path / "out" / "run.json").exists()
    (warning,) = [line for line in done.stderr.splitlines() if "dropped every station" in line]
    assert warning.startswith("warning: stage 'validity': the checks dropped every station")
    assert "(2: MD 135.00 m: rest_acc; MD 690.00 m: rest_acc)" in warning
    (measured,) = re.findall(r"rest_acc: up to (\d\.\d+) m/s2 measured against 0\.02 m/s2", warning)
    assert float(measured) == pytest.approx(NOISE, rel=0.1)
    assert "`with:` parameter" in warning
    assert "Traceback" not in done.stderr


def test_with_the_tool_s_own_limit_the_run_goes_through(tmp_path: Path, samples: Path):
    text = PIPELINE.read_text(encoding="utf-8")
    own = text.replace(
        "    inputs: {readings: readings.readings, samples: read.samples}\n",
        "    inputs: {readings: readings.readings, samples: read.samples}\n"
        "    with: {rest_acc: {limit: 0.06, policy: drop}}\n",
        1,
    )
    assert own != text
    (tmp_path / "own.yaml").write_text(own, encoding="utf-8")
    done = gyropipe_cli("run", tmp_path / "own.yaml", "--input", samples, "--out", tmp_path / "o")
    assert done.returncode == 0, done.stderr
    assert "dropped every station" not in done.stderr
    assert (tmp_path / "o" / "run.json").exists()

"""The earth_rate_fit check of an XY gyro is not evaluated where its fit cannot tell k: a
simulated two-axis DTG survey (the preset of ``examples/plans/horizontal.yaml``) whose last
stations lie at 90°, through ``gyropipe run pipelines/point-gyro.yaml`` (its uncertainty
stage given ``outside_validity: flag``, GYRO-NS holding to 89°). The fit's high-side term is
Ω cos φ cos A cos I, nothing at 90°, so k = √((u/cos I)² + v²) there is noise divided by
≈ 0: before, the QC table listed k of thousands of °/h at the lateral's stations, passing
or failing by chance (7 of 10 failed on the example plan). The vertical stations are
evaluated and pass."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml

from tests_support import ROOT, gyropipe_cli

PLAN = """name: short-lateral
seed: 5
site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}
well:
  sections:
    - {kind: vertical, length: 110}
    - {kind: build, dls: 30.0, inc: 90, azi: 270}
    - {kind: hold, length: 210}
tool: {preset: dtg-xy}
survey: {mode: point, every: 100, positions: [0, 180, 0]}
"""
OMEGA_COS_PHI = 15.041067 * np.cos(np.radians(61.25))
"""deg/h: the horizontal Earth rate at the site, the check's reference"""


@pytest.fixture(scope="module")
def qc(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, object]]:
    root = tmp_path_factory.mktemp("lateral")
    (root / "plan.yaml").write_text(PLAN)
    gyropipe_cli("simulate", root / "plan.yaml", "--out", root / "sim", check=True)
    spec = yaml.safe_load((ROOT / "pipelines" / "point-gyro.yaml").read_text())
    for stage in spec["stages"]:
        if stage["uses"] == "position_uncertainty":
            stage.setdefault("with", {})["outside_validity"] = "flag"
    (root / "pipeline.yaml").write_text(yaml.safe_dump(spec, sort_keys=False))
    gyropipe_cli(
        "run", root / "pipeline.yaml", "--input", root / "sim" / "samples.parquet",
        "--out", root / "out", check=True,
    )  # fmt: skip
    rows = pq.read_table(root / "out" / "validity.qc.parquet").to_pylist()
    stations = pq.read_table(root / "out" / "compass.stations.parquet").to_pylist()
    inc = {s["station"]: s["inc"] for s in stations}
    return [{**r, "inc": inc[r["station"]]} for r in rows if r["check"] == "earth_rate_fit"]


def test_the_lateral_s_stations_are_not_evaluated(qc: list[dict[str, object]]) -> None:
    lateral = [r for r in qc if float(r["inc"]) > 89.0]  # type: ignore[arg-type]
    assert len(lateral) >= 2
    for row in lateral:
        assert row["passed"] is None, row
        assert row["measured"] is None or np.isnan(row["measured"]), row  # type: ignore[arg-type]
        assert str(row["detail"]).startswith("skipped: at I = "), row
        assert "the fit cannot tell k" in str(row["detail"])


def test_the_vertical_stations_are_evaluated_and_pass(qc: list[dict[str, object]]) -> None:
    vertical = [r for r in qc if float(r["inc"]) < 3.0]  # type: ignore[arg-type]
    assert len(vertical) >= 2
    for row in vertical:
        assert row["passed"] is True, row
        assert float(row["measured"]) == pytest.approx(OMEGA_COS_PHI, abs=0.5)  # type: ignore[arg-type]

"""The committed JSON Schemas under schemas/ are exactly what the models generate."""

from __future__ import annotations

import json
from pathlib import Path

from pipeline import schemas
from pipeline.registry import Registry
from tests_support import ROOT, gyropipe


def test_committed_schemas_match_the_models(registry: Registry):
    stale = schemas.stale(registry, ROOT / "schemas")
    assert stale == [], f"run `gyropipe schemas` to regenerate: {stale}"


def test_schemas_describe_units_and_pipeline_fields(registry: Registry):
    generated = {k: json.loads(v) for k, v in schemas.generate(registry).items()}
    trajectory = generated["contracts/Trajectory.schema.json"]["properties"]
    assert trajectory["dls"]["x-unit"] == "deg/30m"
    assert trajectory["azi"]["exclusiveMaximum"] == 360
    stage = generated["pipeline.schema.json"]["$defs"]["StageSpec"]["properties"]
    assert {"id", "uses", "inputs", "with", "persist"} <= set(stage)


def test_schemas_command_writes_and_checks(tmp_path: Path):
    import subprocess

    out = tmp_path / "schemas"
    wrote = subprocess.run(
        [*gyropipe(), "schemas", "--out", str(out)], capture_output=True, text=True, check=True
    )
    assert "pipeline.schema.json" in wrote.stdout
    ok = subprocess.run([*gyropipe(), "schemas", "--out", str(out), "--check"])
    assert ok.returncode == 0
    (out / "well.schema.json").write_text("{}")
    stale = subprocess.run(
        [*gyropipe(), "schemas", "--out", str(out), "--check"], capture_output=True, text=True
    )
    assert stale.returncode == 1
    assert "stale:" in stale.stdout and "well.schema.json" in stale.stdout

"""The committed JSON Schemas under schemas/ are exactly what the models generate."""

from __future__ import annotations

import json
from pathlib import Path

from pipeline import schemas
from pipeline.registry import Registry
from tests_support import ROOT, gyropipe_cli


def test_committed_schemas_match_the_models(registry: Registry):
    stale = schemas.stale(registry, ROOT / "schemas", ROOT / "docs")
    assert stale == [], f"run `gyropipe schemas` to regenerate: {stale}"


def test_schemas_describe_units_and_pipeline_fields(registry: Registry):
    generated = {k: json.loads(v) for k, v in schemas.generate(registry).items()}
    trajectory = generated["contracts/Trajectory.schema.json"]["properties"]
    assert trajectory["dls"]["x-unit"] == "deg/30m"
    assert trajectory["azi"]["exclusiveMaximum"] == 360
    stage = generated["pipeline.schema.json"]["$defs"]["StageSpec"]["properties"]
    assert {"id", "uses", "inputs", "with", "persist"} <= set(stage)


def test_schemas_command_writes_and_checks(tmp_path: Path):

    out = tmp_path / "schemas"
    where = ["--out", str(out), "--docs", str(tmp_path / "docs")]
    wrote = gyropipe_cli("schemas", *where, check=True)
    assert "pipeline.schema.json" in wrote.stdout and "tables.md" in wrote.stdout
    ok = gyropipe_cli("schemas", *where, "--check")
    assert ok.returncode == 0
    (out / "well.schema.json").write_text("{}")
    stale = gyropipe_cli("schemas", *where, "--check")
    assert stale.returncode == 1
    assert "stale:" in stale.stdout and "well.schema.json" in stale.stdout


def test_tables_page_lists_every_column_with_its_unit(registry: Registry):
    page = schemas.tables_page(registry)
    for name, contract in schemas.builtin_contracts(registry).items():
        assert f"## {name}\n" in page
        for column in contract.compiled().columns:
            assert f"| `{column.name}` |" in page
    assert (
        "| `md` | double | `m` | yes | strictly increasing, finite, no nulls | measured depth "
        "from the depth reference |" in page
    )
    assert "north reference stated" in page

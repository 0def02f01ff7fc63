"""The plugin example in the README works as written: installed through a real entry
point, wired after the survey job, its output checked against its own contract."""

from __future__ import annotations

import re
from pathlib import Path

import pyarrow.parquet as pq

from tests_support import ROOT, gyropipe_cli


def readme_block(marker: str) -> str:
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```(?:python|toml)\n(.*?)```", text, flags=re.S)
    return next(b for b in blocks if b.startswith(marker))


def test_readme_plugin_example_runs(tmp_path: Path):
    site = tmp_path / "site"
    (site / "my_vendor").mkdir(parents=True)
    (site / "my_vendor" / "__init__.py").write_text("")
    (site / "my_vendor" / "plugin.py").write_text(readme_block("# my_vendor/plugin.py"))
    entry = readme_block("# my_vendor's pyproject.toml").split("\n", 1)[1]
    info = site / "my_vendor-0.3.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my_vendor\nVersion: 0.3\n")
    # pyproject's TOML table → the entry_points.txt a wheel installs
    (info / "entry_points.txt").write_text(
        entry.replace("project.entry-points.", "").replace('"', "")
    )
    pipeline = tmp_path / "deep.yaml"
    survey = (ROOT / "pipelines" / "survey.yaml").read_text()
    stage = (
        "  - id: deep\n"
        "    uses: my_vendor.deep_only\n"
        "    inputs: {trajectory: trajectory.trajectory}\n"
        "    persist: [deep]\n"
    )
    pipeline.write_text(survey + stage)
    out_dir = tmp_path / "out"
    args = ("run", pipeline, "--input", "examples/stations-j-well.csv", "--out", out_dir)
    result = gyropipe_cli(*args, site=site)
    assert result.returncode == 0, result.stderr
    deep = pq.read_table(out_dir / "deep.deep.parquet")
    md = deep.column("md").to_numpy()
    assert len(md) > 0
    assert md.min() >= 1000
    manifest = (out_dir / "run.json").read_text()
    assert '"my_vendor": "0.3"' in manifest

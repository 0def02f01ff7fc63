"""``--disable-plugin`` is honoured everywhere, tested with the sample plugin gyropipe-acme
(installed offline, ``conftest.py``): a pipeline naming the plugin's tool model is refused
at validate time when the plugin is disabled, naming the model and the plugin; the listing
of models leaves the plugin's out; a run with the plugin records it in ``run.json`` and its
report names the model; the Python API finds the plugin's model through the registry it
loads."""

from __future__ import annotations

import json
import textwrap
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pyarrow.parquet as pq
import pytest
from click.testing import Result
from pydantic import ValidationError

import pipeline as gp
from pipeline.errors import SpecError
from tests_support import ROOT

Cli = Callable[..., Result]
STATIONS = ROOT / "examples" / "stations-j-well.csv"
REFUSAL = (
    "tool model ACME-GYRO-V2 is provided by plugin acme, which is disabled (--disable-plugin acme)"
)
PIPELINE = """
name: acme_uncertainty
version: "1"
inputs: {stations: {description: survey stations}}
stages:
  - {id: read, uses: read_stations, with: {input: stations}}
  - {id: trajectory, uses: minimum_curvature, inputs: {stations: read.stations}}
  - id: uncertainty
    uses: position_uncertainty
    inputs: {trajectory: trajectory.trajectory}
    with: {model: ACME-GYRO-V2}     # the plugin's tool model
    persist: [trajectory]
  - {id: report, uses: report, inputs: {trajectory: uncertainty.trajectory}, with: {formats: [html]}}
"""


@pytest.fixture
def pipeline_file(tmp_path: Path) -> Path:
    path = tmp_path / "acme-uncertainty.yaml"
    path.write_text(textwrap.dedent(PIPELINE).lstrip())
    return path


def test_validate_refuses_a_disabled_plugin_s_tool_model(
    acme: ModuleType, cli: Cli, pipeline_file: Path
):
    assert cli("validate", str(pipeline_file)).returncode == 0
    out = cli("validate", str(pipeline_file), "--disable-plugin", "acme")
    assert out.returncode == 2, out.output
    assert f"{pipeline_file}:" in out.stderr and "stage 'uncertainty'" in out.stderr
    assert REFUSAL in out.stderr


def test_run_with_the_plugin_disabled_is_refused_before_anything_runs(
    acme: ModuleType, cli: Cli, pipeline_file: Path, tmp_path: Path
):
    out_dir = tmp_path / "out"
    args = ("run", str(pipeline_file), "--input", str(STATIONS), "--out", str(out_dir))
    refused = cli(*args, "--disable-plugin", "acme")
    assert refused.returncode == 2, refused.output
    assert REFUSAL in refused.stderr
    assert not out_dir.exists()

    done = cli(*args)
    assert done.returncode == 0, done.output
    manifest = json.loads((out_dir / "run.json").read_text())
    assert manifest["plugins"]["acme"] == "0.1.0"  # the plugin whose model the run used
    # the report names the model by the title its file (the plugin's) gives it
    html = (out_dir / "report.html").read_text()
    assert "Acme GyroLog v2 (north-seeking gyro) error model propagated" in html


def test_python_api_finds_the_plugin_model_and_honours_disable(
    acme: ModuleType, pipeline_file: Path, tmp_path: Path
):
    """``gp.run`` with the plugin computes what the stage computes through ``gp`` functions
    (the plugin's model, not GYRO-NS); ``disable=`` refuses the pipeline as the CLI does."""
    with pytest.raises(SpecError, match=REFUSAL.replace("(", r"\(").replace(")", r"\)")):
        gp.run(pipeline_file, STATIONS, disable=["acme"])
    result = gp.run(pipeline_file, STATIONS, out=tmp_path / "out")
    persisted = pq.read_table(tmp_path / "out" / "uncertainty.trajectory.parquet")
    trajectory = result.tables["trajectory.trajectory"]
    acme_cov = gp.position_uncertainty(trajectory, model="ACME-GYRO-V2", well=result.well)
    gyro_ns = gp.position_uncertainty(trajectory, model="GYRO-NS", well=result.well)
    for name in ("cov_nn", "cov_ee", "cov_vv"):
        ours = persisted.column(name).to_numpy()
        np.testing.assert_allclose(ours, acme_cov.column(name).to_numpy(), rtol=1e-12, atol=0)
    # the thermal term grows with TVD: the plugin's model is not GYRO-NS
    assert not np.allclose(persisted.column("cov_ee").to_numpy(), gyro_ns.column("cov_ee"))


def test_models_listing_honours_disable(acme: ModuleType, cli: Cli):
    listed = cli("models")
    assert listed.returncode == 0, listed.output
    assert any(line.startswith("ACME-GYRO-V2 ") for line in listed.stdout.splitlines())
    without = cli("models", "--disable-plugin", "acme")
    assert without.returncode == 0, without.output
    names = [line.split()[0] for line in without.stdout.splitlines()]
    assert "ACME-GYRO-V2" not in names and "GYRO-NS" in names
    shown = cli("models", "ACME-GYRO-V2", "--disable-plugin", "acme")
    assert shown.returncode == 2
    assert f"error: {REFUSAL}" in shown.stderr


def test_a_disabled_plugin_registers_nothing_and_is_only_asked_what_it_provides(
    acme: ModuleType,
):
    """A disabled plugin is left out of the registry; what it would provide is looked up
    (in a registry of its own) only to explain a name that is unknown."""
    from pipeline.plugins import load_registry

    registry = load_registry(["acme"])
    assert "acme" not in registry.plugins and "ACME-GYRO-V2" not in registry.tool_models
    assert registry.disabled_provider("tool_model", "GYRO-NS") is None
    assert registry.disabled_provider("tool_model", "acme-gyro-v2") == "acme"
    assert registry.disabled_provider("reader", "acme_survey") == "acme"
    assert "acme" not in registry.plugins  # it explained; it was not added


@pytest.mark.parametrize(
    ("uses", "params"),
    [
        ("position_uncertainty", {"model": "ACME-GYRO-V2"}),
        ("clearance", {"reference_model": "acme-gyro-v2", "reference_hole_diameter": 0.2}),
        ("definitive_survey", {"runs": {"run1": {"model": "ACME-GYRO-V2"}}}),
    ],
)
def test_every_stage_naming_a_tool_model_takes_it_from_the_run_s_registry(
    acme: ModuleType, uses: str, params: dict[str, object]
):
    """Each stage's params, validated as the planner does (with the run's registry), accept
    the plugin's model and refuse it, naming the plugin, when the plugin is disabled."""
    from pipeline.plugins import load_registry

    with_acme = load_registry()
    definition = with_acme.stages[uses][0]
    definition.params.model_validate(params, context={"registry": with_acme})
    without = load_registry(["acme"])
    with pytest.raises(ValidationError) as refused:
        definition.params.model_validate(params, context={"registry": without})
    name = "acme-gyro-v2" if uses == "clearance" else "ACME-GYRO-V2"
    assert REFUSAL.replace("ACME-GYRO-V2", name) in str(refused.value)


def test_a_stage_of_a_disabled_builtin_plugin_is_named_with_its_plugin(cli: Cli):
    survey = ROOT / "pipelines" / "survey.yaml"
    out = cli("validate", str(survey), "--disable-plugin", "builtin.survey")
    assert out.returncode == 2, out.output
    assert (
        "stage 'minimum_curvature' is provided by plugin builtin.survey, which is disabled "
        "(--disable-plugin builtin.survey)"
    ) in out.stderr

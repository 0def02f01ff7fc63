"""Plugins found through real entry points: failures are reported by plugin name and
version, the other plugins keep working, and stage exceptions name their plugin."""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import pytest

from tests_support import gyropipe_cli, plugin_site

PLUGINS = {
    # name: (version, module source)
    "goodplugin": (
        "1.2.3",
        """
        from collections.abc import Callable
        from pipeline.hookspecs import hookimpl
        from pipeline.registry import StageDef
        from pipeline.tables import Trajectory

        def explode(inputs, params, ctx):
            raise ValueError("deliberate failure in a plugin stage")

        @hookimpl
        def gyropipe_register_stages(register):
            register(StageDef("goodplugin.explode", explode, "raises",
                              inputs={"trajectory": Trajectory}))
    """,
    ),
    "brokenplugin": (
        "0.1.0",
        """
        import not_a_module_that_exists  # noqa: F401
    """,
    ),
    "badregplugin": (
        "2.0.0",
        """
        from pipeline.hookspecs import hookimpl
        from pipeline.registry import StageDef

        @hookimpl
        def gyropipe_register_stages(register):
            register("not a stage")
            register(StageDef("Bad Name", print, "invalid name"))
            register(StageDef("badregplugin.params", print, "bad params", params=dict))
            register(StageDef("minimum_curvature", print, "clashes with a built-in"))
            register(StageDef("badregplugin.ok", print, "valid, kept"))
    """,
    ),
    "raisingplugin": (
        "0.0.1",
        """
        from pipeline.hookspecs import hookimpl

        @hookimpl
        def gyropipe_register_stages(register):
            raise RuntimeError("hook blew up")
    """,
    ),
    "typoplugin": (
        "3.1.4",
        """
        from pipeline.hookspecs import hookimpl

        @hookimpl
        def gyropipe_register_stagez(register):
            pass
    """,
    ),
}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A directory of installed plugins: their modules and dist-info entry points."""
    return plugin_site(tmp_path_factory.mktemp("site"), PLUGINS)


def test_plugins_command_reports_each_failure_by_name_and_version(site: Path):
    out = gyropipe_cli("plugins", site=site)
    assert out.returncode == 0, out.stderr
    text = out.stdout
    assert "goodplugin 1.2.3 (third-party): stage:goodplugin.explode" in text
    assert (
        "brokenplugin 0.1.0 (third-party): FAILED: failed to load entry point 'brokenplugin'"
        in text
    )
    assert "ModuleNotFoundError" in text
    assert "problem: plugin badregplugin 2.0.0: registered a str where a StageDef is needed" in text
    assert "problem: plugin badregplugin 2.0.0: stage name 'Bad Name' is invalid" in text
    assert (
        "problem: plugin badregplugin 2.0.0: stage 'badregplugin.params': params must be a BaseModel subclass"
        in text
    )
    assert (
        "problem: plugin badregplugin 2.0.0: stage 'minimum_curvature' is already "
        "registered by plugin builtin.survey"
    ) in text
    assert "badregplugin 2.0.0 (third-party): stage:badregplugin.ok" in text
    assert (
        "problem: plugin raisingplugin 0.0.1: gyropipe_register_stages raised RuntimeError: hook blew up"
        in text
    )
    assert (
        "typoplugin 3.1.4 (third-party): FAILED: implements unknown hook(s) gyropipe_register_stagez"
        in text
    )
    # the built-ins still work alongside
    assert "builtin.survey" in text and "stage:minimum_curvature" in text


def test_disabling_a_plugin(site: Path):
    out = gyropipe_cli(
        "plugins", "--disable-plugin", "brokenplugin", "--disable-plugin", "builtin.qc", site=site
    )
    assert "brokenplugin" not in out.stdout
    assert "builtin.qc" not in out.stdout
    assert "goodplugin 1.2.3" in out.stdout


def test_pipeline_runs_despite_broken_plugins_and_stage_error_names_plugin(
    site: Path, tmp_path: Path
):
    pipeline = tmp_path / "p.yaml"
    pipeline.write_text(
        textwrap.dedent("""
        name: explode
        version: 1
        inputs: {stations: {}}
        stages:
          - id: read
            uses: read_stations
          - id: traj
            uses: minimum_curvature
            inputs: {stations: read}
          - id: boom
            uses: goodplugin.explode
            inputs: {trajectory: traj}
    """)
    )
    out_dir = tmp_path / "out"
    args = ("run", pipeline, "--input", "examples/stations-j-well.csv", "--out", out_dir)
    out = gyropipe_cli(*args, site=site)
    assert out.returncode == 1
    assert (
        "stage 'boom' (goodplugin.explode from plugin goodplugin 1.2.3) failed: "
        "ValueError: deliberate failure in a plugin stage"
    ) in out.stderr
    assert "warning: plugin brokenplugin 0.1.0" in out.stderr
    assert not out_dir.exists()  # nothing half-written
    assert "Traceback" not in out.stderr


def test_in_process_registry_keeps_working_plugins(site: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.syspath_prepend(str(site))
    import importlib

    importlib.invalidate_caches()
    from pipeline.plugins import load_registry

    registry = load_registry()
    assert "goodplugin.explode" in registry.stages
    assert registry.stages["goodplugin.explode"][1] == "goodplugin"
    assert "badregplugin.ok" in registry.stages
    assert registry.stages["minimum_curvature"][1] == "builtin.survey"
    failed = {p.plugin for p in registry.problems}
    assert failed == {"brokenplugin", "badregplugin", "raisingplugin", "typoplugin"}
    assert sys.modules.get("not_a_module_that_exists") is None

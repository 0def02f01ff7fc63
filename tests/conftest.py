"""Shared test helpers: pipelines written to real files, a registry with test stages."""

from __future__ import annotations

import os
import textwrap
from collections.abc import Callable
from pathlib import Path

import pytest

from pipeline.plugins import load_registry
from pipeline.registry import PluginInfo, Registry, StageDef

ROOT = Path(__file__).resolve().parents[1]
TEST_PLUGIN = PluginInfo("tests.helpers", "9.9", builtin=False)

# Hundreds of tests run the ``gyropipe`` command in a new process, each importing the package
# from source: let them keep its compiled byte code, as an installed package has it, where the
# environment says not to (PYTHONDONTWRITEBYTECODE): each would compile ≈ 130 modules again
# (≈ 0.2 s of a command's ≈ 1.1 s).
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)


@pytest.fixture
def registry() -> Registry:
    """The real registry (built-in plugins) as a user gets it."""
    return load_registry()


@pytest.fixture
def add_stage(registry: Registry) -> Callable[[StageDef], None]:
    """Register an extra stage in ``registry`` as plugin ``tests.helpers`` 9.9."""
    registry.plugins[TEST_PLUGIN.name] = TEST_PLUGIN

    def add(stage: StageDef) -> None:
        registry.add(stage, TEST_PLUGIN, StageDef)
        assert not registry.problems, registry.problems

    return add


@pytest.fixture
def write_yaml(tmp_path: Path) -> Callable[[str], Path]:
    """Write dedented YAML text to ``tmp_path/pipeline.yaml``."""

    def write(text: str, name: str = "pipeline.yaml") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text).lstrip("\n"))
        return path

    return write

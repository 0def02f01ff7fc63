"""Shared test helpers: pipelines written to real files, a registry with test stages.

The CLI runs in this process (:func:`tests_support.gyropipe_cli`). A test that needs a real
process carries ``@pytest.mark.process("why")`` saying why (a signal, a crash, what a
fresh interpreter imports, the console script itself); the reason is required.
"""

from __future__ import annotations

import os
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pandas  # noqa: F401 -- before any CLI command: see below
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

# The CLI's commands keep pandas out of a fresh process until something imports it
# (pipeline.lazy_pandas.defer_pandas, which is a no-op where pandas is already imported):
# in this process pandas is imported first, so commands run in process leave the import
# system as they found it, whatever order the tests run in. tests/engine/test_lazy_pandas.py
# measures the deferral in real processes.


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """A ``process`` mark must say why the test needs a real process."""
    for item in items:
        mark = item.get_closest_marker("process")
        if mark is not None and not (mark.args and isinstance(mark.args[0], str)):
            raise pytest.UsageError(f"{item.nodeid}: @pytest.mark.process needs a reason")


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


@pytest.fixture
def read_only_dir(tmp_path: Path) -> Iterator[Path]:
    """A read-only directory (:func:`fs_support.read_only`; skips where none can be made)."""
    from fs_support import read_only

    with read_only(tmp_path / "read-only") as where:
        yield where


@pytest.fixture
def full_dir(tmp_path: Path) -> Iterator[Path]:
    """A directory on a full file system (:func:`fs_support.full`; skips where it cannot)."""
    from fs_support import full

    with full(tmp_path / "full") as where:
        yield where

"""The sample plugin ``plugins/gyropipe-acme`` installed offline: a site directory holding
its package and the ``.dist-info`` an installer writes (``METADATA`` and ``entry_points.txt``
from its ``pyproject.toml``), so ``importlib.metadata`` finds its entry point exactly as for
a pip-installed package — without pip, a build backend or the network."""

from __future__ import annotations

import importlib
import shutil
import sys
import tomllib
from collections.abc import Callable, Iterator
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType

import pytest

from pipeline.plugins import ENTRY_POINT_GROUP, forget_shared_registries
from tests_support import ROOT, CliResult, gyropipe_cli

PACKAGE = ROOT / "plugins" / "gyropipe-acme"


def install_offline(project: Path, site: Path) -> Path:
    """Install the plugin project ``project`` (a src layout) into ``site`` as an installer
    would, from its ``pyproject.toml``: its packages copied, and a
    ``<name>-<version>.dist-info`` with ``METADATA``, ``entry_points.txt`` and
    ``INSTALLER``. Returns the ``.dist-info`` directory."""
    meta = tomllib.loads((project / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    src = project / "src"
    for package in sorted(p for p in src.iterdir() if (p / "__init__.py").is_file()):
        shutil.copytree(package, site / package.name, ignore=shutil.ignore_patterns("__pycache__"))
    dist = site / f"{meta['name'].replace('-', '_')}-{meta['version']}.dist-info"
    dist.mkdir()
    lines = [
        "Metadata-Version: 2.1",
        f"Name: {meta['name']}",
        f"Version: {meta['version']}",
        f"Summary: {meta.get('description', '')}",
        f"Requires-Python: {meta.get('requires-python', '')}",
        *(f"Requires-Dist: {d}" for d in meta.get("dependencies", [])),
    ]
    (dist / "METADATA").write_text("\n".join(lines) + "\n", encoding="utf-8")
    groups = meta.get("entry-points", {})
    entry_points = "".join(
        f"[{group}]\n" + "".join(f"{name} = {value}\n" for name, value in eps.items()) + "\n"
        for group, eps in groups.items()
    )
    (dist / "entry_points.txt").write_text(entry_points, encoding="utf-8")
    (dist / "INSTALLER").write_text("gyropipe-tests\n", encoding="utf-8")
    return dist


@pytest.fixture(scope="session")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A site directory with gyropipe-acme installed (:func:`install_offline`); put it on
    ``sys.path`` (fixture ``acme``) or ``PYTHONPATH`` to have the plugin installed."""
    target = tmp_path_factory.mktemp("acme-site")
    install_offline(PACKAGE, target)
    return target


@pytest.fixture(scope="session")
def serial_site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A site directory with the test plugin ``gyropipe-serial`` installed (an executor)."""
    target = tmp_path_factory.mktemp("serial-site")
    install_offline(Path(__file__).parent / "gyropipe-serial", target)
    return target


@pytest.fixture
def acme(site: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[ModuleType]:
    """The plugin installed for this test only: its site directory on ``sys.path`` and the
    process's registries loaded afresh on entry and on exit (so no other test's registry
    sees it); yields the imported package."""
    monkeypatch.syspath_prepend(str(site))  # (also invalidates the import caches)
    monkeypatch.delitem(sys.modules, "gyropipe_acme", raising=False)
    forget_shared_registries()
    module = importlib.import_module("gyropipe_acme")
    assert Path(module.__file__ or "").is_relative_to(site)
    found = entry_points(group=ENTRY_POINT_GROUP, name="acme")
    assert [(ep.value, ep.dist and ep.dist.version) for ep in found] == [
        ("gyropipe_acme.plugin", "0.1.0")
    ]
    yield module
    forget_shared_registries()


@pytest.fixture
def cli() -> Callable[..., CliResult]:
    """``gyropipe ARGS…`` run in process (:func:`tests_support.gyropipe_cli`)."""
    return gyropipe_cli

"""Plugin manager: loads built-in and third-party plugins into a :class:`Registry`.

Each entry point of the group ``gyropipe`` is loaded in its own try/except and each plugin's
hook implementations are called one plugin at a time, so a plugin that fails to import,
misspells a hook, raises, or registers something invalid is reported by name and version
while every other plugin keeps working.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Callable, Iterable
from importlib.metadata import entry_points

import pluggy

from pipeline import hookspecs
from pipeline.errors import PluginError
from pipeline.executing import ExecutorDef
from pipeline.registry import (
    CheckDef,
    PluginInfo,
    ReaderDef,
    Registry,
    StageDef,
    ToolModelDef,
    WriterDef,
)
from pipeline.reporting import ReportDef
from pipeline.version import __version__

ENTRY_POINT_GROUP = "gyropipe"

BUILTIN_PLUGINS = {
    "builtin.files": "pipeline.stages.files",
    "builtin.survey": "pipeline.stages.survey",
    "builtin.qc": "pipeline.stages.qc",
    "builtin.simulation": "pipeline.stages.simulation",
    "builtin.compass": "pipeline.stages.compass",
    "builtin.validity": "pipeline.stages.validity",
    "builtin.drift": "pipeline.stages.drift",
    "builtin.continuous": "pipeline.stages.continuous",
    "builtin.stations": "pipeline.stages.stations",
    "builtin.uncertainty": "pipeline.stages.uncertainty",
    "builtin.definitive": "pipeline.stages.definitive",
    "builtin.gates": "pipeline.stages.gates",
    "builtin.clearance": "pipeline.stages.clearance",
    "builtin.report": "pipeline.stages.report",
    "builtin.las": "pipeline.io.las",
    "builtin.mcap": "pipeline.io.mcap",
    "builtin.csv": "pipeline.io.csv",
    "builtin.parquet": "pipeline.io.parquet",
    "builtin.witsml": "pipeline.io.witsml",
    "builtin.json_summary": "pipeline.io.json_summary",
    "builtin.drift_tables": "pipeline.io.drift_tables",
    "builtin.exports": "pipeline.stages.exports",
    "builtin.executors": "pipeline.batch.builtin_executors",
}
"""Built-in plugins by name → module; they register through the same hooks as any other."""

HOOKS: tuple[tuple[str, type], ...] = (
    ("gyropipe_register_stages", StageDef),
    ("gyropipe_register_readers", ReaderDef),
    ("gyropipe_register_writers", WriterDef),
    ("gyropipe_register_checks", CheckDef),
    ("gyropipe_register_tool_models", ToolModelDef),
    ("gyropipe_register_report_parts", ReportDef),
    ("gyropipe_register_executors", ExecutorDef),
)


def load_registry(disabled: Iterable[str] = ()) -> Registry:
    """Load all plugins except those named in ``disabled`` (they are not imported) and
    collect their registrations. A fresh registry each call: a process uses
    :func:`shared_registry`."""
    blocked = frozenset(disabled)
    registry = _load(lambda name: name not in blocked)
    registry.disabled = blocked
    if blocked:
        registry.load_disabled = lambda: _load(lambda name: name in blocked)
    return registry


def shared_registry(disabled: Iterable[str] = ()) -> Registry:
    """The registry of this process for a set of disabled plugins, loaded on first need and
    then reused (as xarray caches its engines): what the command line, the Python API and
    batch workers hand to the runner. :func:`forget_shared_registries` drops them (tests
    that change what is installed)."""
    return _shared(frozenset(disabled))


@functools.cache
def _shared(disabled: frozenset[str]) -> Registry:
    return load_registry(disabled)


def forget_shared_registries() -> None:
    """Load the plugins afresh on the next :func:`shared_registry` call."""
    _shared.cache_clear()


def _load(wanted: Callable[[str], bool]) -> Registry:
    """The registry of the plugins whose name is ``wanted``."""
    registry = Registry()
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    candidates: list[tuple[PluginInfo, object]] = []

    for name, module_name in BUILTIN_PLUGINS.items():
        info = PluginInfo(name, __version__, builtin=True)
        if not wanted(name):
            continue
        try:
            candidates.append((info, importlib.import_module(module_name)))
        except Exception as exc:  # a broken built-in is reported like any other plugin
            _fail(registry, info, f"failed to import {module_name}: {type(exc).__name__}: {exc}")

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        version = ep.dist.version if ep.dist is not None else "unknown"
        dist = f" ({ep.dist.name})" if ep.dist is not None else ""
        if not wanted(ep.name):
            continue
        try:
            obj = ep.load()
        except Exception as exc:  # any import failure is this plugin's, not ours
            _fail(
                registry,
                PluginInfo(ep.name, version, builtin=False),
                f"failed to load entry point {ep.value!r}{dist}: {type(exc).__name__}: {exc}",
            )
            continue
        candidates.append((PluginInfo(ep.name, version, builtin=False), obj))

    for info, obj in candidates:
        try:
            pm.register(obj, name=info.name)
        except Exception as exc:  # pluggy rejects malformed hook implementations
            _fail(registry, info, f"cannot be registered: {exc}")
            continue
        unknown = _unknown_hooks(pm, obj)
        if unknown:
            pm.unregister(obj)
            _fail(registry, info, f"implements unknown hook(s) {', '.join(unknown)}")
            continue
        registry.plugins[info.name] = info
        _collect(pm, registry, info)

    pm.check_pending()  # every unknown hook was refused above; this guards the invariant
    for name, info in list(registry.plugins.items()):
        registry.plugins[name] = PluginInfo(
            info.name, info.version, info.builtin, tuple(registry.provides(name)), info.error
        )
    return registry


def _collect(pm: pluggy.PluginManager, registry: Registry, info: PluginInfo) -> None:
    """Call this plugin's hook implementations only, tagging what they register."""
    for hook_name, expected in HOOKS:
        caller = getattr(pm.hook, hook_name)
        for impl in caller.get_hookimpls():
            if impl.plugin_name != info.name:
                continue
            try:
                impl.function(register=lambda item, e=expected: registry.add(item, info, e))
            except Exception as exc:  # a raising hook is reported against its plugin
                registry.problems.append(
                    PluginError(
                        info.name, info.version, f"{hook_name} raised {type(exc).__name__}: {exc}"
                    )
                )


def _unknown_hooks(pm: pluggy.PluginManager, obj: object) -> list[str]:
    known = {name for name, _ in HOOKS}
    return sorted(
        name
        for name in dir(obj)
        if name.startswith("gyropipe_") and name not in known and callable(getattr(obj, name))
    )


def _fail(registry: Registry, info: PluginInfo, message: str) -> None:
    registry.plugins[info.name] = PluginInfo(info.name, info.version, info.builtin, error=message)
    registry.problems.append(PluginError(info.name, info.version, message))

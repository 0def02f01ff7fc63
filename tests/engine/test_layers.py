"""The layers of ``src/pipeline`` (docs/architecture.md), checked from the source.

Every module is parsed with :mod:`ast` and every import it makes is collected: top-level,
under ``if TYPE_CHECKING:``, inside functions (lazy imports), relative ones resolved, and
imports by name (``importlib.import_module("…")``, ``__import__("…")`` with the name written
out). Three rules:

- no import circle between modules;
- no import from a lower layer to a higher one (:data:`LAYERS`); within a layer anything goes
  but a circle;
- the domain never reaches the plugin machinery (:data:`SEALED`): no import of it, however
  made, and no string naming it (a name handed to ``importlib`` later) — what the domain
  needs of plugins (tool models, readers) is handed to it by the registry of the run.

Every module must have a layer, so a new module or package is given a home here. Plugins that
:mod:`pipeline.plugins` loads from a table of names are not imports and are not seen.
"""

from __future__ import annotations

import ast
import functools
import itertools
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests_support import ROOT

PACKAGE = "pipeline"

LAYER_NAMES = {
    6: "cli / public API",
    5: "batch / stages / report",
    4: "io / sim",
    3: "domain",
    2: "engine core",
    1: "foundation",
}

LAYERS: dict[str, int] = {
    # 6 — faces: the command line, the package's public API (``pipeline/__init__.py`` only)
    # and the plugin authors' API (``pipeline.plugin``)
    "pipeline": 6,
    "pipeline.cli": 6,
    "pipeline.cli_models": 6,
    "pipeline.cli_args": 6,
    "pipeline.cli_run": 6,
    "pipeline.api": 6,
    "pipeline.plugin": 6,
    # 5 — orchestration: many wells, built-in stages, reports
    "pipeline.batch": 5,
    "pipeline.stages": 5,
    "pipeline.reports": 5,
    # 4 — readers and writers; the simulator
    "pipeline.io": 4,
    "pipeline.sim": 4,
    # 3 — domain: plain functions over arrays and tables
    "pipeline.earth": 3,
    "pipeline.survey": 3,
    "pipeline.uncertainty": 3,
    "pipeline.anticollision": 3,
    "pipeline.gyrocompass": 3,
    "pipeline.continuous": 3,
    "pipeline.drift": 3,
    "pipeline.qc": 3,
    # 2 — engine core: specs, the DAG, the runner, plugins, contracts, units
    "pipeline.spec": 2,
    "pipeline.graph": 2,
    "pipeline.runner": 2,
    "pipeline.manifest": 2,
    "pipeline.registry": 2,
    "pipeline.read_checks": 2,
    "pipeline.provenance": 2,
    "pipeline.reporting": 2,
    "pipeline.executing": 2,
    "pipeline.plugins": 2,
    "pipeline.hookspecs": 2,
    "pipeline.contracts": 2,
    "pipeline.tables": 2,
    "pipeline.plausibility": 2,
    "pipeline.schemas": 2,
    "pipeline.yamlsource": 2,
    "pipeline.yaml_errors": 2,
    "pipeline.filenames": 2,
    "pipeline.inputfiles": 2,
    "pipeline.units": 2,
    "pipeline.convert": 2,
    "pipeline.streams": 2,
    "pipeline.lazy_pandas": 2,
    "pipeline.ports": 2,
    # 1 — foundation
    "pipeline.well": 1,
    "pipeline.jsontext": 1,
    "pipeline.errors": 1,
    "pipeline.atomic": 1,
    "pipeline.hashing": 1,
    "pipeline.processes": 1,
    "pipeline.version": 1,
    "pipeline.lazy": 1,
}
"""Module prefix → layer rank (higher imports lower). A prefix covers its submodules, except
the bare package name, which is ``pipeline/__init__.py`` alone."""

PLUGIN_MACHINERY = ("pipeline.plugins", "pipeline.registry", "pipeline.hookspecs")
"""What loads plugins and holds their registrations."""
SEALED: dict[str, tuple[str, ...]] = {
    prefix: PLUGIN_MACHINERY for prefix, rank in LAYERS.items() if rank == 3
}
"""Module prefix → modules it may not import in any way nor name: the domain packages and
the plugin machinery (one registry per run, passed explicitly: docs/architecture.md)."""
BY_NAME = frozenset({"import_module", "__import__"})
"""Functions that import a module by name (``importlib.import_module``, ``__import__``)."""


@dataclass(frozen=True)
class Import:
    importer: str
    imported: str
    path: Path
    line: int
    how: str = "import"
    """``import``, ``by name`` (``import_module``/``__import__``) or ``named`` (a string)"""


@dataclass(frozen=True)
class Violation:
    key: str
    """A short name of the violation (``circle: a, b`` or ``upward: a -> b``)."""
    detail: str


def modules(src: Path, package: str) -> dict[str, tuple[Path, bool]]:
    """Module name → (file, is a package's ``__init__``) of every module of ``package``."""
    found: dict[str, tuple[Path, bool]] = {}
    for path in sorted((src / package).rglob("*.py")):
        parts = list(path.relative_to(src).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts.pop()
        found[".".join(parts)] = (path, is_package)
    return found


def _nodes(path: Path) -> tuple[ast.AST, ...]:
    """Every node of a module's syntax tree, parsed once per version of the file (the
    checks walk each module three times)."""
    stat = path.stat()
    return _parsed(path, stat.st_mtime_ns, stat.st_size)


@functools.cache
def _parsed(path: Path, mtime_ns: int, size: int) -> tuple[ast.AST, ...]:
    return tuple(ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))))


def imports(src: Path, package: str) -> Iterator[Import]:
    """Every import of a module of ``package`` by a module of ``package``, wherever it stands."""
    known = modules(src, package)

    def module_of(name: str) -> str | None:
        """The longest prefix of ``name`` that is a module of the package."""
        while name and name not in known:
            name = name.rpartition(".")[0]
        return name or None

    for importer, (path, is_package) in known.items():
        for node in _nodes(path):
            targets: list[str] = []
            how = "import"
            if isinstance(node, ast.Call) and _called(node.func) in BY_NAME:
                first = node.args[0] if node.args else None
                if isinstance(first, ast.Constant) and isinstance(first.value, str):
                    targets, how = [first.value], "by name"
            elif isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = importer if is_package else importer.rpartition(".")[0]
                    for _ in range(node.level - 1):
                        base = base.rpartition(".")[0]
                    base = f"{base}.{node.module}" if node.module else base
                else:
                    base = node.module or ""
                # ``from a import b``: module a.b if there is one, else a name of module a
                targets = [
                    f"{base}.{alias.name}" if f"{base}.{alias.name}" in known else base
                    for alias in node.names
                ]
            for target in targets:
                if target.partition(".")[0] != package:
                    continue
                imported = module_of(target)
                if imported is not None and imported != importer:
                    yield Import(importer, imported, path, node.lineno, how)


def _called(func: ast.expr) -> str | None:
    """The name of a called function (``f(…)``, ``module.f(…)``)."""
    if isinstance(func, ast.Name):
        return func.id
    return func.attr if isinstance(func, ast.Attribute) else None


def named(src: Path, package: str) -> Iterator[Import]:
    """Every string constant of a module of ``package`` that is exactly the name of one of
    its modules (``"pipeline.plugins"``): a module a later ``import_module(name)`` may load."""
    known = modules(src, package)
    for importer, (path, _) in known.items():
        for node in _nodes(path):
            if isinstance(node, ast.Constant) and node.value in known and node.value != importer:
                yield Import(importer, str(node.value), path, node.lineno, "named")


def prefixed(module: str, prefixes: tuple[str, ...], package: str) -> str | None:
    """The longest of ``prefixes`` that covers ``module``: the module itself or a package
    above it (the bare package name covers ``pipeline/__init__.py`` alone)."""
    covering = [p for p in prefixes if module == p or (p != package and module.startswith(p + "."))]
    return max(covering, key=len) if covering else None


def layer_of(module: str, layers: Mapping[str, int], package: str) -> int | None:
    """The rank of the longest prefix of ``module`` in ``layers`` (None if it has none)."""
    prefix = prefixed(module, tuple(layers), package)
    return None if prefix is None else layers[prefix]


def circles(edges: Mapping[str, set[str]]) -> list[tuple[set[str], list[str]]]:
    """Each strongly connected component of more than one module (Tarjan), with one cycle
    through it (a path of modules from its smallest back to it)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(edges.get(node, ())):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component: set[str] = set()
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.add(top)
                if top == node:
                    break
            if len(component) > 1:
                components.append(component)

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return [(c, _cycle_through(min(c), c, edges)) for c in components]


def _cycle_through(start: str, component: set[str], edges: Mapping[str, set[str]]) -> list[str]:
    """A shortest path start → … → start inside ``component`` (breadth first)."""
    came_from: dict[str, str] = {}
    frontier = [start]
    while frontier:
        following: list[str] = []
        for node in frontier:
            for nxt in sorted(edges.get(node, set()) & component):
                if nxt == start:
                    path = [node]
                    while path[-1] != start:
                        path.append(came_from[path[-1]])
                    return [*reversed(path), start]
                if nxt not in came_from:
                    came_from[nxt] = node
                    following.append(nxt)
        frontier = following
    raise AssertionError(f"{start} is on no cycle of {sorted(component)}")


def violations(
    src: Path,
    package: str,
    layers: Mapping[str, int],
    names: Mapping[int, str] = LAYER_NAMES,
    sealed: Mapping[str, tuple[str, ...]] | None = None,
) -> list[Violation]:
    """Unassigned modules, circles, upward imports and reaches into what ``sealed`` (default
    :data:`SEALED`) forbids, of ``package`` under ``src``."""
    found: list[Violation] = []
    root = src.parent
    for module, (path, _) in modules(src, package).items():
        if layer_of(module, layers, package) is None:
            found.append(
                Violation(
                    f"unassigned: {module}",
                    f"{path.relative_to(root)}: module {module} has no layer: give it one in "
                    "LAYERS",
                )
            )
    edges: dict[str, set[str]] = {}
    first: dict[tuple[str, str], Import] = {}
    upward: dict[tuple[str, str], list[Import]] = {}
    for imp in imports(src, package):
        edges.setdefault(imp.importer, set()).add(imp.imported)
        first.setdefault((imp.importer, imp.imported), imp)
        low = layer_of(imp.importer, layers, package)
        high = layer_of(imp.imported, layers, package)
        if low is not None and high is not None and high > low:
            upward.setdefault((imp.importer, imp.imported), []).append(imp)
    for component, cycle in circles(edges):
        found.append(
            Violation(
                f"circle: {', '.join(sorted(component))}",
                f"import circle among {', '.join(sorted(component))}: "
                + " -> ".join(cycle)
                + "".join(
                    f"\n  {a} -> {b} at {first[a, b].path.relative_to(root)}:{first[a, b].line}"
                    for a, b in itertools.pairwise(cycle)
                ),
            )
        )
    found += _reaches(src, package, SEALED if sealed is None else sealed)
    for (importer, imported), where in sorted(upward.items()):
        low = layer_of(importer, layers, package)
        high = layer_of(imported, layers, package)
        assert low is not None and high is not None
        lines = ", ".join(f"{imp.path.relative_to(root)}:{imp.line}" for imp in where)
        found.append(
            Violation(
                f"upward: {importer} -> {imported}",
                f"{lines}: {importer} ({_layer_name(low, names)}) imports {imported} "
                f"({_layer_name(high, names)}), a higher layer",
            )
        )
    return found


def _reaches(src: Path, package: str, sealed: Mapping[str, tuple[str, ...]]) -> list[Violation]:
    """Each import (of any kind) or naming of a module that ``sealed`` forbids its importer."""
    found: dict[tuple[str, str], list[Import]] = {}
    for imp in itertools.chain(imports(src, package), named(src, package)):
        rule = prefixed(imp.importer, tuple(sealed), package)
        if rule is not None and prefixed(imp.imported, sealed[rule], package) is not None:
            found.setdefault((imp.importer, imp.imported), []).append(imp)
    root = src.parent
    return [
        Violation(
            f"sealed: {importer} -> {imported}",
            ", ".join(f"{i.path.relative_to(root)}:{i.line} ({i.how})" for i in where)
            + f": {importer} reaches {imported}; the domain never loads plugins — take what "
            "you need (tool models, readers) as an argument from the registry of the run",
        )
        for (importer, imported), where in sorted(found.items())
    ]


def _layer_name(rank: int, names: Mapping[int, str]) -> str:
    return f"layer {rank}, {names[rank]}" if rank in names else f"layer {rank}"


def test_layers_are_kept() -> None:
    found = [v.detail for v in violations(ROOT / "src", PACKAGE, LAYERS)]
    assert not found, "layering violations (docs/architecture.md):\n" + "\n".join(found)


def test_every_layer_prefix_names_a_module() -> None:
    """A stale entry in LAYERS (a module moved or gone) would hide nothing, but mislead."""
    known = modules(ROOT / "src", PACKAGE)
    stale = [
        prefix
        for prefix in LAYERS
        if not any(m == prefix or m.startswith(prefix + ".") for m in known)
    ]
    assert not stale, f"LAYERS names no module: {stale}"


def _package(root: Path, files: Mapping[str, str]) -> Path:
    src = root / "src"
    for name, text in files.items():
        path = src / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return src


SYNTHETIC_LAYERS = {"toy": 3, "toy.top": 3, "toy.mid": 2, "toy.low": 1}


def test_checker_finds_circles_and_upward_imports(tmp_path: Path) -> None:
    src = _package(
        tmp_path,
        {
            "toy/__init__.py": "",
            "toy/top.py": "from toy import mid\n",
            "toy/mid/__init__.py": "",
            # a circle through a relative import and a lazy one
            "toy/mid/a.py": "from .b import thing\n",
            "toy/mid/b.py": "def thing():\n    from toy.mid import a\n    return a\n",
            # upward, hidden under TYPE_CHECKING, and by name in a function
            "toy/low.py": (
                "import importlib\nfrom typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                "    from toy.top import x\ndef f():\n    return importlib.import_module('toy.top')\n"
            ),
            "toy/stray.py": "import toy.low\n",
        },
    )
    found = {v.key: v.detail for v in violations(src, "toy", SYNTHETIC_LAYERS, names={})}
    assert set(found) == {
        "circle: toy.mid.a, toy.mid.b",
        "upward: toy.low -> toy.top",
        "unassigned: toy.stray",
    }
    assert found["circle: toy.mid.a, toy.mid.b"].splitlines() == [
        "import circle among toy.mid.a, toy.mid.b: toy.mid.a -> toy.mid.b -> toy.mid.a",
        "  toy.mid.a -> toy.mid.b at src/toy/mid/a.py:1",
        "  toy.mid.b -> toy.mid.a at src/toy/mid/b.py:2",
    ]
    assert found["upward: toy.low -> toy.top"].startswith(
        "src/toy/low.py:4, src/toy/low.py:6: toy.low (layer 1) imports toy.top (layer 3)"
    )


def test_checker_passes_a_clean_package(tmp_path: Path) -> None:
    src = _package(
        tmp_path,
        {
            "toy/__init__.py": "from toy.top import run\n",
            "toy/top.py": "from . import mid\nfrom .low import base\n",
            "toy/mid.py": "import toy.low as low\n",
            "toy/low.py": "import ast\nbase = 1\n",
        },
    )
    assert violations(src, "toy", SYNTHETIC_LAYERS, names={}) == []


@pytest.mark.parametrize(
    ("module", "rank"),
    [
        ("pipeline", 6),
        ("pipeline.cli", 6),
        ("pipeline.plugin", 6),
        ("pipeline.plugins", 2),
        ("pipeline.io.drift_tables", 4),
        ("pipeline.survey.stations", 3),
        ("pipeline.gyrocompass.positions", 3),
        ("pipeline.version", 1),
        ("pipeline.unknown", None),
    ],
)
def test_layer_of(module: str, rank: int | None) -> None:
    assert layer_of(module, LAYERS, PACKAGE) == rank


MAX_LINES = 700


def test_no_module_is_longer_than_700_lines() -> None:
    """Small modules whose names say what they hold: a module over the limit is split."""
    long = {
        str(path.relative_to(ROOT)): n
        for path in (ROOT / "src" / PACKAGE).rglob("*.py")
        if (n := len(path.read_text().splitlines())) > MAX_LINES
    }
    assert not long, long


def test_checker_finds_a_domain_module_reaching_the_plugin_registry(tmp_path: Path) -> None:
    """The real rules (:data:`LAYERS`, :data:`SEALED`) on a synthetic ``pipeline`` whose
    domain module loads the registry inside a function — the hidden registry — and by name."""
    src = _package(
        tmp_path,
        {
            "pipeline/__init__.py": "",
            "pipeline/registry.py": "class Registry: ...\n",
            "pipeline/plugins.py": "from pipeline.registry import Registry\n"
            "def load_registry() -> Registry: ...\n",
            "pipeline/uncertainty/__init__.py": "",
            "pipeline/uncertainty/engine.py": (
                "def plugin_files():\n"
                "    from pipeline.plugins import load_registry\n"
                "    return load_registry().tool_models\n"
            ),
            "pipeline/uncertainty/lazy.py": (
                "import importlib\n"
                "def registry():\n"
                '    return importlib.import_module("pipeline.plugins").load_registry()\n'
                "def raw():\n"
                '    return __import__("pipeline.registry")\n'
            ),
            "pipeline/uncertainty/spelled.py": (
                'WHERE = "pipeline.plugins"  # handed to importlib later\n'
            ),
            "pipeline/survey/__init__.py": "",
            "pipeline/survey/fine.py": "import importlib\nmath = importlib.import_module('math')\n",
        },
    )
    found = {v.key: v.detail for v in violations(src, PACKAGE, LAYERS)}
    assert set(found) == {
        "sealed: pipeline.uncertainty.engine -> pipeline.plugins",
        "sealed: pipeline.uncertainty.lazy -> pipeline.plugins",
        "sealed: pipeline.uncertainty.lazy -> pipeline.registry",
        "sealed: pipeline.uncertainty.spelled -> pipeline.plugins",
    }
    assert found["sealed: pipeline.uncertainty.engine -> pipeline.plugins"].startswith(
        "src/pipeline/uncertainty/engine.py:2 (import): pipeline.uncertainty.engine reaches "
        "pipeline.plugins; the domain never loads plugins"
    )
    assert (
        "src/pipeline/uncertainty/lazy.py:3 (by name)"
        in found["sealed: pipeline.uncertainty.lazy -> pipeline.plugins"]
    )
    assert (
        "src/pipeline/uncertainty/spelled.py:1 (named)"
        in found["sealed: pipeline.uncertainty.spelled -> pipeline.plugins"]
    )

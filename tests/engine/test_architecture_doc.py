"""docs/architecture.md names only what exists: every backticked module, path and name in it
resolves against the code, so the map a new maintainer reads cannot drift from the house.

How a span is resolved (the first rule that applies):

- a command line (``gyropipe X …``): ``X`` is a ``gyropipe`` command;
- an import line (``from a import b``): it imports;
- other text with spaces, and literals (``file:line``, ``.svg``): prose, not checked;
- a path (has ``/`` or a file ending): a file or folder under ``src/pipeline/``, the
  repository root or ``docs/``, or under the folder of the path named last before it
  (``reports/charts/model.py``, ``ticks.py``); ``path.name`` is a path and a name defined in
  that module;
- ``a.b.c`` (a trailing call ``(…)`` dropped, ``gp.`` read as ``pipeline.``): a module of
  ``pipeline`` (or of the package named last) or an installed package and attributes of it,
  or a class of ``pipeline`` and its attribute (fields of dataclasses and pydantic models
  included);
- an option (``--set``): an option of a ``gyropipe`` command;
- a single name: a module, a class, function, constant, enum member or field defined in
  ``src/pipeline`` or in the module named last, a string the code uses as a key or column
  name, a stage, port, hook or plugin of the built-in registry, a key of a pipeline file, a
  command, a module of the standard library or an installed package, or a name of
  :data:`EXTERNAL`.
"""

from __future__ import annotations

import ast
import functools
import importlib
import re
import sys
from dataclasses import dataclass
from pathlib import Path

import click
import pytest

from tests_support import ROOT

DOC = ROOT / "docs" / "architecture.md"
SRC = ROOT / "src" / "pipeline"
BASES = (SRC, ROOT, ROOT / "docs")
EXTERNAL = {
    "pread": "os.pread",
    "pwrite": "os.pwrite",
    "iter_batches": "pyarrow.parquet.ParquetFile.iter_batches",
    "to_pandas": "pyarrow.Table.to_pandas",
}
"""Names of other libraries the document uses bare, and where each lives."""
PLACEHOLDERS = {"stage.port"}
"""Spans that stand for a value, not a name (a pipeline's ``stage.port`` wiring)."""
LITERAL = re.compile(r"^(\.\w+|@[\w-]+|\w+:\w+|[\w.-]+\.(json|yaml|csv|las|mcap|parquet|txt))$")
"""File endings, CSS at-rules, ``file:line``-style placeholders, file names of outputs."""
IDENT = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$")


@dataclass
class Context:
    """The path named last before a span: its folder, and the module it is (if any)."""

    folder: Path = SRC
    module: Path | None = None

    def folders(self) -> list[Path]:
        """The folder, then each one above it up to the repository root."""
        found = [self.folder]
        while found[-1] != ROOT and ROOT in found[-1].parents:
            found.append(found[-1].parent)
        return found


def spans(text: str) -> list[tuple[int, str]]:
    """Every backticked span (line number, text) outside fenced code blocks."""
    found: list[tuple[int, str]] = []
    fenced = False
    for number, line in enumerate(text.splitlines(), start=1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            found.extend((number, m) for m in re.findall(r"`([^`]+)`", line))
    return found


def module_name(path: Path) -> str | None:
    """The import name of a file under ``src/``, or None."""
    if SRC not in path.parents:
        return None
    name = ".".join(("pipeline", *path.relative_to(SRC).with_suffix("").parts))
    return name.removesuffix(".__init__")


def names_in(path: Path) -> tuple[set[str], set[str]]:
    """Names a Python file defines (classes, functions, assignments at any level) and the
    strings it uses."""
    defined: set[str] = set()
    strings: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            defined.add(node.name)
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            defined.update(t.id for t in targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            strings.add(node.value)
    return defined, strings


@functools.cache
def source_names() -> tuple[dict[str, set[str]], set[str]]:
    """Name → modules of ``pipeline`` defining it; every string the package uses."""
    defined: dict[str, set[str]] = {}
    strings: set[str] = set()
    for path in SRC.rglob("*.py"):
        names, used = names_in(path)
        strings |= used
        for name in names:
            defined.setdefault(name, set()).add(module_name(path) or "")
    return defined, strings


@functools.cache
def registry_names() -> set[str]:
    """Stages, their ports and parameters, hooks and plugins of the built-in registry, and
    the keys of a pipeline file."""
    from pipeline import hookspecs
    from pipeline.plugins import BUILTIN_PLUGINS, load_registry
    from pipeline.spec import PipelineSpec, StageSpec

    registry = load_registry()
    found = set(registry.stages) | set(BUILTIN_PLUGINS) | set(registry.plugins)
    for stage, _ in registry.stages.values():
        found |= set(stage.inputs) | set(stage.outputs)
        if stage.params is not None:
            found |= set(stage.params.model_fields)
    found |= {name for name in dir(hookspecs) if name.startswith("gyropipe_")}
    for model in (PipelineSpec, StageSpec):
        found |= set(model.model_fields)
        found |= {f.alias for f in model.model_fields.values() if f.alias}
    return found


@functools.cache
def commands() -> dict[str, click.Command]:
    from pipeline.cli import main

    assert isinstance(main, click.Group)
    return dict(main.commands)


def attribute(owner: object, name: str) -> bool:
    """Whether ``owner`` (a module or class) has ``name``, dataclass and model fields too."""
    if hasattr(owner, name):
        return True
    fields = getattr(owner, "__dataclass_fields__", None) or getattr(owner, "model_fields", {})
    return name in fields or name in getattr(owner, "__annotations__", {})


def chain(obj: object, parts: list[str]) -> bool:
    """Whether ``obj.p1.p2…`` exists (a field without a value ends the chain, found)."""
    for part in parts:
        if not attribute(obj, part):
            return False
        obj = getattr(obj, part, None)
    return True


def dotted(name: str, context: Context) -> bool:
    """``a.b.c`` as module + attributes (under ``pipeline``, the context's package or
    installed), or as a class of ``pipeline`` + its attribute."""
    parts = name.split(".")
    packages = [m for f in context.folders() if (m := module_name(f / "__init__.py"))]
    for prefix in [*packages, "pipeline", ""]:
        for cut in range(len(parts), 0, -1):
            try:
                module = importlib.import_module(".".join(filter(None, [prefix, *parts[:cut]])))
            except ImportError:
                continue
            if chain(module, parts[cut:]):
                return True
            break
    defined, _ = source_names()
    return any(chain(importlib.import_module(owner), parts) for owner in defined.get(parts[0], ()))


def path_like(span: str, context: Context) -> bool:
    """A file or folder, with an optional ``.name`` after a module path."""
    span = span.rstrip("/")
    bases = [*BASES, *context.folders()]
    if any((base / span).exists() for base in bases):
        return True
    head, _, tail = span.rpartition(".")
    for base in bases:
        if head and IDENT.match(tail) and (file := base / f"{head}.py").exists():
            name = module_name(file)
            return name is not None and attribute(importlib.import_module(name), tail)
    return False


def resolves(span: str, context: Context | None = None) -> bool:
    """Whether a backticked span names something that exists (module docstring)."""
    context = context or Context()
    span = span.strip()
    if span.startswith("gyropipe "):
        return span.split()[1] in commands()
    if span.startswith("from ") and " import " in span:
        module, _, names = span[5:].partition(" import ")
        imported = importlib.import_module(module)
        return all(attribute(imported, n.strip()) for n in names.split(","))
    if span.startswith("--"):
        option = span.split()[0]
        return any(option in p.opts for c in commands().values() for p in c.params)
    if " " in span or LITERAL.match(span) or span in PLACEHOLDERS:
        return True
    if "/" in span or span.endswith(".py"):
        return path_like(span, context)
    name = re.sub(r"\(.*\)$", "", span).rstrip(":")
    name = re.sub(r"^gp\.", "pipeline.", name)
    if name.endswith("_*"):
        return any(n.startswith(name[:-1]) for n in registry_names())
    if not IDENT.match(name):
        return False
    defined, strings = source_names()
    if name in registry_names() or name in commands():
        return True
    if "." in name:
        return dotted(name, context)
    if name in EXTERNAL:
        return dotted(EXTERNAL[name], context)
    if name in defined or name in strings or name == "gyropipe":
        return True
    if context.module is not None and name in names_in(context.module)[0]:
        return True
    return name in sys.stdlib_module_names or dotted(name, context)


def unresolved(text: str) -> list[str]:
    """``line: `span``` for each span that names nothing, in the order of the text."""
    context = Context()
    found: list[str] = []
    for number, span in spans(text):
        if not resolves(span, context):
            found.append(f"{number}: `{span}`")
        elif "/" in span and " " not in span:
            path = next(
                (
                    b / span.rstrip("/")
                    for b in [*BASES, *context.folders()]
                    if (b / span.rstrip("/")).exists()
                ),
                None,
            )
            if path is not None:
                folder = path if path.is_dir() else path.parent
                module = path if path.suffix == ".py" else context.module
                context = Context(folder, module)
    return found


def test_every_backticked_name_in_the_architecture_notes_resolves() -> None:
    missing = unresolved(DOC.read_text(encoding="utf-8"))
    assert not missing, "docs/architecture.md names what does not exist:\n" + "\n".join(missing)


@pytest.mark.parametrize(
    "span",
    [
        "atomic.publish",  # a function that does not exist
        "StageContext.read",  # a method that does not exist
        "qc/checks.py",  # a module that was split away
        "io/parquet.nothing_here",  # a name not in a module that exists
        "gyropipe frobnicate",  # not a command
        "--no-such-option",
        "NoSuchClass",
    ],
)
def test_the_check_fails_on_drifted_names(span: str) -> None:
    assert not resolves(span)


def test_a_file_named_after_its_folder_resolves_there_only() -> None:
    """``ticks.py`` after ``reports/charts/model.py`` is ``reports/charts/ticks.py``."""
    text = "`reports/charts/model.py`, `ticks.py`, `ticks.linear_labels`\n`nothing.py`"
    assert unresolved(text) == ["2: `nothing.py`"]
    assert unresolved("`ticks.py`") == ["1: `ticks.py`"]


@pytest.mark.parametrize(
    "span",
    [
        "Registry.read",
        "io/parquet.py",
        "gyropipe run",
        "read_samples",
        "streams.TableStream",
        "pyarrow.parquet.ParquetWriter",
        "persist:",
        "pread",
        "gyropipe_register_*",
        "CONTENT",
        "--set",
        "gp.run",
    ],
)
def test_the_check_passes_names_that_exist(span: str) -> None:
    assert resolves(span)


def test_the_layer_table_names_every_layer_entry() -> None:
    """Each module or package the layer test places has its line in the layer table."""
    from test_layers import LAYERS

    text = DOC.read_text(encoding="utf-8")
    table = text[text.index("```text") : text.index("Rules that come with the layers")]
    words = set(re.findall(r"[\w.]+/?", table))
    missing = [
        name
        for name in LAYERS
        if name != "pipeline"
        and not {f"{name.split('.')[-1]}.py", f"{name.split('.')[-1]}/"} & words
    ]
    assert not missing, f"the layer table lacks {missing}"


def test_every_hook_is_named() -> None:
    from pipeline import hookspecs

    text = DOC.read_text(encoding="utf-8")
    hooks = sorted(n for n in dir(hookspecs) if n.startswith("gyropipe_"))
    assert [h for h in hooks if f"`{h}`" not in text] == []

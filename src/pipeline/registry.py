"""What plugins register: stages, readers, writers and checks, and the registry holding them.

Every registration is tagged with the plugin that made it, so any later error can name it.
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import pyarrow as pa
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationInfo

from pipeline.contracts import TableContract
from pipeline.errors import PluginError
from pipeline.well import WellMetadata

NAME = re.compile(r"^[a-z][a-z0-9_]*(\.[a-z][a-z0-9_]*)*$")
PIPELINE_INPUT = "x-pipeline-input"
"""JSON-schema marker of a params field that names one of the pipeline's ``inputs``."""


def pipeline_input(default: str, description: str) -> Any:
    """A params field naming a pipeline input; the planner checks the name is declared."""
    return Field(default, description=description, json_schema_extra={PIPELINE_INPUT: True})


def registered(kind: str, *, also: tuple[str, ...] = ()) -> AfterValidator:
    """Annotation for a params field naming a registered ``kind`` (reader, writer, check);
    names in ``also`` are accepted as they are (e.g. ``auto``). Checked when the planner
    validates params with the registry in the validation context."""

    def check(name: str, info: ValidationInfo) -> str:
        registry = (info.context or {}).get("registry")
        if name in also or not isinstance(registry, Registry):
            return name
        table = getattr(registry, kind + "s")
        if name not in table:
            raise ValueError(
                f"no {kind} named {name!r} (installed: {', '.join(sorted(table)) or 'none'})"
            )
        return name

    return AfterValidator(check)


class NoParams(BaseModel):
    """Parameters of a stage that takes none."""

    model_config = ConfigDict(extra="forbid")


@dataclass(frozen=True)
class InputFile:
    """A pipeline input file as the run received it."""

    path: str
    sha256: str
    bytes: int


@dataclass(frozen=True)
class StageSetup:
    """One stage of the running plan: what it uses, from which plugin, with which params."""

    id: str
    uses: str
    plugin: str
    """plugin name and version"""
    params: Mapping[str, Any]
    """validated params, JSON-compatible"""


@dataclass(frozen=True)
class Provenance:
    """Where a run's results come from (what ``run.json`` records), known while it runs."""

    pipeline: str
    pipeline_version: str
    pipeline_file: str
    pipeline_sha256: str
    gyropipe: str
    plugins: Mapping[str, str]
    """plugin name → version (plugins that loaded)"""
    inputs: Mapping[str, InputFile]
    started: dt.datetime
    """UTC start of the run"""
    stages: tuple[StageSetup, ...]
    """every stage of the plan, in execution order"""


class StageContext(Protocol):
    """What the runner gives a stage besides its tables and params."""

    @property
    def stage_id(self) -> str: ...

    @property
    def well(self) -> WellMetadata: ...

    @property
    def provenance(self) -> Provenance:
        """The run's pipeline, software versions, input file hashes and start time."""
        ...

    def input_path(self, name: str) -> Path:
        """The file given for the pipeline input ``name`` (readers only)."""
        ...

    def output_path(self, filename: str) -> Path:
        """Where a writer stage writes ``filename``; published atomically when the run ends."""
        ...

    def readers(self) -> list[ReaderDef]: ...

    def writer(self, name: str) -> WriterDef: ...

    def check(self, name: str) -> CheckDef: ...


StageFunc = Callable[[Mapping[str, pa.Table], Any, StageContext], Mapping[str, pa.Table]]


@dataclass(frozen=True)
class StageDef:
    """A stage type: validated params and contracted tables in, contracted tables out.

    ``func(inputs, params, ctx)`` receives the input tables by port name, an instance of
    ``params`` and a :class:`StageContext`; it returns the output tables by port name.
    Ports in ``optional_inputs`` may be left unwired (they are then absent from ``inputs``).
    """

    name: str
    func: StageFunc
    description: str
    inputs: Mapping[str, type[TableContract]] = field(default_factory=dict)
    outputs: Mapping[str, type[TableContract]] = field(default_factory=dict)
    params: type[BaseModel] = NoParams
    optional_inputs: frozenset[str] = frozenset()


@dataclass(frozen=True)
class ReaderDef:
    """A file reader. ``read(path, kind, options)`` returns a table of ``kinds[kind]`` and the
    well metadata found in the file; ``sniff(path)`` says whether it can open the file."""

    name: str
    description: str
    kinds: Mapping[str, type[TableContract]]
    read: Callable[[Path, str, Any], tuple[pa.Table, WellMetadata]]
    sniff: Callable[[Path], bool]
    options: type[BaseModel] = NoParams


@dataclass(frozen=True)
class WriterDef:
    """A table writer: ``write(table, path, well)`` writes one file (the caller makes it
    atomic)."""

    name: str
    description: str
    extension: str
    write: Callable[[pa.Table, Path, WellMetadata], None]
    write_tables: (
        Callable[[Mapping[str, pa.Table], Path, WellMetadata, Provenance], None] | None
    ) = None
    """Writers whose file holds several tables of a run (the ``export`` stage): the tables by
    role (``trajectory``, ``qc``…), the path, the well and the run's provenance."""
    schema: type[BaseModel] | None = None
    """Writers of JSON documents: the model of the document (``gyropipe schemas`` publishes
    its JSON Schema)."""


@dataclass(frozen=True)
class CheckDef:
    """A QC check: ``func(table, params, well)`` returns a :class:`CheckResults` table."""

    name: str
    description: str
    contract: type[TableContract]
    func: Callable[[pa.Table, Any, WellMetadata], pa.Table]
    params: type[BaseModel] = NoParams


@dataclass(frozen=True)
class PluginInfo:
    """A loaded (or failed) plugin."""

    name: str
    version: str
    builtin: bool
    provides: tuple[str, ...] = ()
    error: str | None = None


Registration = StageDef | ReaderDef | WriterDef | CheckDef
KIND_OF: dict[type, str] = {
    StageDef: "stage",
    ReaderDef: "reader",
    WriterDef: "writer",
    CheckDef: "check",
}


@dataclass
class Registry:
    """Everything the loaded plugins registered, each tagged with its plugin name."""

    stages: dict[str, tuple[StageDef, str]] = field(default_factory=dict)
    readers: dict[str, tuple[ReaderDef, str]] = field(default_factory=dict)
    writers: dict[str, tuple[WriterDef, str]] = field(default_factory=dict)
    checks: dict[str, tuple[CheckDef, str]] = field(default_factory=dict)
    plugins: dict[str, PluginInfo] = field(default_factory=dict)
    problems: list[PluginError] = field(default_factory=list)

    def add(self, item: object, plugin: PluginInfo, expected: type) -> None:
        """Validate and store one registration; a bad one becomes a problem of its plugin."""
        try:
            kind, name = _validate(item, expected)
        except (TypeError, ValueError) as exc:
            self.problems.append(PluginError(plugin.name, plugin.version, str(exc)))
            return
        table: dict[str, Any] = getattr(self, kind + "s")
        if name in table:
            other = table[name][1]
            self.problems.append(
                PluginError(
                    plugin.name,
                    plugin.version,
                    f"{kind} {name!r} is already registered by plugin {other}; kept that one",
                )
            )
            return
        table[name] = (item, plugin.name)

    def plugin_label(self, plugin: str) -> str:
        info = self.plugins.get(plugin)
        return f"{plugin} {info.version}" if info else plugin

    def provides(self, plugin: str) -> list[str]:
        """``kind:name`` of everything ``plugin`` registered."""
        return [
            f"{kind}:{name}"
            for kind in ("stage", "reader", "writer", "check")
            for name, (_, owner) in getattr(self, kind + "s").items()
            if owner == plugin
        ]


def _validate(item: object, expected: type) -> tuple[str, str]:
    kind = KIND_OF[expected]
    if not isinstance(item, expected):
        raise TypeError(f"registered a {type(item).__name__} where a {expected.__name__} is needed")
    name = getattr(item, "name", None)
    if not isinstance(name, str) or not NAME.match(name):
        raise ValueError(
            f"{kind} name {name!r} is invalid: use lower-case letters, digits, '_' and '.'"
        )
    callables = {
        "stage": ("func",),
        "reader": ("read", "sniff"),
        "writer": ("write",),
        "check": ("func",),
    }[kind]
    for attr in callables:
        if not callable(getattr(item, attr)):
            raise TypeError(f"{kind} {name!r}: {attr} is not callable")
    models: list[tuple[str, object, type]] = []
    if isinstance(item, StageDef):
        models.append(("params", item.params, BaseModel))
        models += [(f"input {p}", c, TableContract) for p, c in item.inputs.items()]
        models += [(f"output {p}", c, TableContract) for p, c in item.outputs.items()]
        unknown = set(item.optional_inputs) - set(item.inputs)
        if unknown:
            raise ValueError(f"stage {name!r}: optional inputs {sorted(unknown)} are not inputs")
    elif isinstance(item, ReaderDef):
        models.append(("options", item.options, BaseModel))
        models += [(f"kind {k}", c, TableContract) for k, c in item.kinds.items()]
    elif isinstance(item, CheckDef):
        models += [("params", item.params, BaseModel), ("contract", item.contract, TableContract)]
    elif isinstance(item, WriterDef):
        if item.write_tables is not None and not callable(item.write_tables):
            raise TypeError(f"writer {name!r}: write_tables is not callable")
        if item.schema is not None:
            models.append(("schema", item.schema, BaseModel))
    for what, model, base in models:
        if not (isinstance(model, type) and issubclass(model, base)):
            raise TypeError(f"{kind} {name!r}: {what} must be a {base.__name__} subclass")
    return kind, name

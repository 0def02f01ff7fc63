"""What plugins register: stages, readers, writers, checks, tool models, report parts and
executors, and the registry holding them.

Every registration is tagged with the plugin that made it, so any later error can name it.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol

import pyarrow as pa
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, ValidationInfo

from pipeline.contracts import BatchChecker, TableContract
from pipeline.errors import (
    ContractViolation,
    GyropipeError,
    PluginError,
    ReaderChoiceError,
    ReaderError,
    WrongKindError,
)
from pipeline.executing import ExecutorDef
from pipeline.plausibility import CONFIRM, DROP, without_null_stations
from pipeline.provenance import InputFile as InputFile
from pipeline.provenance import Provenance as Provenance
from pipeline.provenance import StageSetup as StageSetup
from pipeline.read_checks import check_columns, check_read, read_violation, reader_options
from pipeline.reporting import ReportDef
from pipeline.streams import Port, TableStream
from pipeline.well import WELL_DEFAULT, WellMetadata

NAME = re.compile(r"^[a-z][a-z0-9_]*(\.[a-z][a-z0-9_]*)*\Z")
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


class StageContext(Protocol):
    """What the runner gives a stage besides its tables and params."""

    @property
    def stage_id(self) -> str: ...

    @property
    def well(self) -> WellMetadata:
        """The run's well metadata as it stands: the pipeline's, updated by the stages before
        this one (:meth:`update_well`), under the run's overrides; a field the input files'
        headers state differently is left unstated (a table's own: :meth:`well_for`)."""
        ...

    def well_for(self, header: WellMetadata | None) -> WellMetadata:
        """The well metadata that applies to a table carrying ``header`` (its own file's,
        :func:`~pipeline.well.well_of`): the header, where it is silent the pipeline's
        ``well:``, under the run's overrides — never another input file's header (its survey
        date, declination, convergence, tool, depth reference). ``None`` (a table that
        carries none): :attr:`well`."""
        ...

    def update_well(self, found: WellMetadata) -> None:
        """Report well metadata the stage found or established (a simulation plan's site, the
        north reference its azimuths were converted to): every field set in ``found`` enters
        the run's well, under the run's overrides, for the stages after this one and
        ``run.json``. The header of a pipeline input read by :meth:`read_input` or
        :meth:`read_input_stream` is reported by the engine."""
        ...

    @property
    def provenance(self) -> Provenance:
        """The run's pipeline, software versions, input file hashes and start time."""
        ...

    def input_path(self, name: str) -> Path:
        """The file given for the pipeline input ``name`` (readers only)."""
        ...

    def read_input(
        self,
        name: str,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        into_well: bool = True,
    ) -> tuple[pa.Table, WellMetadata]:
        """The pipeline input ``name`` as a table of ``kind`` and the well metadata it
        carries: read from its file by :meth:`read_file`, or the table the caller gave.
        ``into_well``: its header states the run's well (``False``: another job's record —
        a stand calibration, whose date and serial are the calibration's — that the table
        carries as its own, :meth:`well_for`, but the run's well and report do not take)."""
        ...

    def read_input_stream(
        self,
        name: str,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        into_well: bool = True,
    ) -> tuple[TableStream, WellMetadata]:
        """:meth:`read_input` as a stream of record batches (:meth:`Registry.read_stream`):
        the file is read a batch at a time; a table the caller gave is cut into slices."""
        ...

    def output_path(self, filename: str) -> Path:
        """Where a writer stage writes ``filename``; published atomically when the run ends."""
        ...

    def read_file(
        self,
        path: Path,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
    ) -> tuple[pa.Table, WellMetadata]:
        """Read ``path`` as a table of ``kind`` with the reader the engine chooses
        (:meth:`Registry.read`); options marked as well defaults come from the run's well."""
        ...

    def record_file(self, path: Path, param: str, what: str, sha256: str | None = None) -> str:
        """Record a file read through ``param``; its SHA-256 (:mod:`pipeline.inputfiles`).
        ``sha256`` (optional, added later: three-argument calls are as before): that of
        the bytes the stage read and used, where it read them itself, recorded as given
        (the file is not read again: the hash is of the bytes the run used); None: the file
        is hashed here."""
        ...

    def writer(self, name: str) -> WriterDef: ...

    def check(self, name: str) -> CheckDef: ...

    def report_parts(self) -> list[tuple[ReportDef, PluginInfo]]:
        """What the loaded plugins add to reports (the report stages), each with its plugin."""
        ...


StageFunc = Callable[[Mapping[str, Any], Any, StageContext], Mapping[str, Port]]


@dataclass(frozen=True)
class StageDef:
    """A stage type: validated params and contracted tables in, contracted tables out.

    ``func(inputs, params, ctx)`` receives the input tables by port name, an instance of
    ``params`` and a :class:`StageContext`; it returns the output tables by port name.
    Ports in ``optional_inputs`` may be left unwired (they are then absent from ``inputs``).

    Streamed ports: an input port named in ``streamed_inputs`` receives a
    :class:`~pipeline.streams.TableStream` (a schema and record batches, each pass read
    afresh) whatever its upstream produced — a whole table is cut into slices; every other
    input port receives a whole ``pyarrow.Table`` — a stream is concatenated for it. An
    output port named in ``streamed_outputs`` may return a ``TableStream`` (or a table). The
    engine checks a stream's batches against the port's contract as they pass (rows in
    errors count from the start of the stream) and writes a streamed output that is
    persisted, or given to the ``write`` stage, batch by batch.
    """

    name: str
    func: StageFunc
    description: str
    inputs: Mapping[str, type[TableContract]] = field(default_factory=dict)
    outputs: Mapping[str, type[TableContract]] = field(default_factory=dict)
    params: type[BaseModel] = NoParams
    optional_inputs: frozenset[str] = frozenset()
    streamed_inputs: frozenset[str] = frozenset()
    streamed_outputs: frozenset[str] = frozenset()
    unread_inputs: frozenset[str] = frozenset()
    """streamed inputs the stage may leave unread though wired (validity's samples, read
    only with magnetometers): the plan does not count them as a pass to keep
    (:attr:`~pipeline.graph.PlannedStage.passes`)"""


class Claim(enum.IntEnum):
    """How sure a reader is that a file is its own (xarray's ``guess_can_open``, graded).

    With ``reader: auto`` the engine asks every reader of the wanted kind: the strongest claim
    wins; at equal strength a third-party plugin's reader beats a built-in one; a tie that is
    left is an error naming the candidates. A reader's ``sniff`` may also return a bool:
    ``True`` counts as :attr:`CONTENT`, ``False`` as :attr:`NO`.
    """

    NO = 0
    """not this reader's file"""
    NAME = 1
    """only the file name fits (an extension such as ``.csv``)"""
    CONTENT = 2
    """the content was recognised (magic bytes, a header this reader parses)"""


@dataclass(frozen=True)
class ReaderDef:
    """A file reader. ``read(path, kind, options)`` returns a table of ``kinds[kind]`` and the
    well metadata found in the file; ``options`` is an instance of the ``options`` model.
    ``sniff(path)`` says how sure the reader is that the file is its own (:class:`Claim`);
    it must not raise. ``recognises`` says in a few words what it claims (for
    ``gyropipe plugins``; default: the first line of ``sniff``'s docstring).

    ``stream(path, kind, options)``, when given, reads the same table as a
    :class:`~pipeline.streams.TableStream` (schema known up front, the file read a batch at a
    time on each pass) and the well metadata; a reader without it is read whole and the
    engine cuts the table into slices (:meth:`Registry.read_stream`)."""

    name: str
    description: str
    kinds: Mapping[str, type[TableContract]]
    read: Callable[[Path, str, Any], tuple[pa.Table, WellMetadata]]
    sniff: Callable[[Path], Claim | bool]
    options: type[BaseModel] = NoParams
    recognises: str = ""
    stream: Callable[[Path, str, Any], tuple[TableStream, WellMetadata]] | None = None

    def claim(self, path: Path) -> Claim:
        """:meth:`sniff` as a :class:`Claim`; a sniff that raises claims nothing."""
        try:
            said = self.sniff(path)
        except Exception:  # a reader's bug must not stop the others being asked
            return Claim.NO
        if isinstance(said, Claim):
            return said
        return Claim.CONTENT if said is True else Claim.NO

    def parse_options(
        self, options: Mapping[str, Any], well: WellMetadata | None = None
    ) -> BaseModel:
        """``options`` validated by the reader's :attr:`options` model: the one place reader
        options are validated (when a pipeline is validated and when a file is read; the
        reader gets the model instance). An option marked as a well default
        (:data:`~pipeline.well.WELL_DEFAULT`) and not given takes ``well``'s value. Raises
        pydantic's ``ValidationError``."""
        values = dict(options)
        for name, info in self.options.model_fields.items():
            extra = info.json_schema_extra
            source = extra.get(WELL_DEFAULT) if isinstance(extra, dict) else None
            default = getattr(well, str(source), None) if source and well is not None else None
            if default is not None and name not in values:
                values[name] = default
        return self.options.model_validate(values)

    def what_it_claims(self) -> str:
        """What the reader recognises, in words."""
        doc = (self.sniff.__doc__ or "").strip().split("\n\n")[0]
        return self.recognises or " ".join(doc.split()) or "(not described)"


@dataclass(frozen=True)
class WriterDef:
    """A table writer: ``write(table, path, well)`` writes one file (the caller makes it
    atomic); ``write_stream(stream, path, well)``, when given, writes a
    :class:`~pipeline.streams.TableStream` batch by batch (else the stream is concatenated
    and given to ``write``)."""

    name: str
    description: str
    extension: str
    write: Callable[[pa.Table, Path, WellMetadata], None]
    write_stream: Callable[[TableStream, Path, WellMetadata], None] | None = None
    write_tables: Callable[[Mapping[str, Any], Path, WellMetadata, Provenance], None] | None = None
    """Writers whose file holds several tables of a run (the ``export`` stage): the tables by
    role (``trajectory``, ``qc``…), the path, the well and the run's provenance."""
    tables_streamed: bool = False
    """``write_tables`` takes a :class:`~pipeline.streams.TableStream` for a table too (the
    export stage then passes the full-rate series as it streams, not concatenated)."""
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
class ToolModelDef:
    """A tool-model (error model) file a plugin ships: ``path`` is its YAML file in the
    format of ``docs/tool-models.md``; ``name`` is the model's name (as the file's ``name:``
    declares it; letters, digits, ``.``, ``-`` and ``_``), by which stages select it."""

    name: str
    path: Path
    description: str = ""


TOOL_MODEL_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.\-]*\Z")


@dataclass(frozen=True)
class PluginInfo:
    """A loaded (or failed) plugin."""

    name: str
    version: str
    builtin: bool
    provides: tuple[str, ...] = ()
    error: str | None = None


Registration = StageDef | ReaderDef | WriterDef | CheckDef | ToolModelDef | ReportDef | ExecutorDef
KIND_OF: dict[type, str] = {
    StageDef: "stage",
    ReaderDef: "reader",
    WriterDef: "writer",
    CheckDef: "check",
    ToolModelDef: "tool_model",
    ReportDef: "report",
    ExecutorDef: "executor",
}


@dataclass
class Registry:
    """Everything the loaded plugins registered, each tagged with its plugin name."""

    stages: dict[str, tuple[StageDef, str]] = field(default_factory=dict)
    readers: dict[str, tuple[ReaderDef, str]] = field(default_factory=dict)
    writers: dict[str, tuple[WriterDef, str]] = field(default_factory=dict)
    checks: dict[str, tuple[CheckDef, str]] = field(default_factory=dict)
    tool_models: dict[str, tuple[ToolModelDef, str]] = field(default_factory=dict)
    reports: dict[str, tuple[ReportDef, str]] = field(default_factory=dict)
    executors: dict[str, tuple[ExecutorDef, str]] = field(default_factory=dict)
    plugins: dict[str, PluginInfo] = field(default_factory=dict)
    problems: list[PluginError] = field(default_factory=list)
    disabled: frozenset[str] = frozenset()
    """plugins left out by name (``--disable-plugin``): not loaded"""
    load_disabled: Callable[[], Registry] | None = field(default=None, repr=False, compare=False)
    """loads the registry of the disabled plugins alone (set by the plugin manager; used
    only to say which of them an unknown name belongs to)"""
    _left_out: Registry | None = field(default=None, init=False, repr=False, compare=False)

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

    def report_parts(self) -> list[tuple[ReportDef, PluginInfo]]:
        """Every report part in registration order, with the plugin that registered it."""
        unknown = PluginInfo("", "unknown", builtin=False)  # a registry built by hand
        return [
            (part, self.plugins.get(owner, replace(unknown, name=owner)))
            for part, owner in self.reports.values()
        ]

    def tool_model_files(self) -> dict[str, Path]:
        """The tool-model files the plugins registered, by model name."""
        return {name: Path(d.path) for name, (d, _) in self.tool_models.items()}

    def disabled_provider(self, kind: str, name: str) -> str | None:
        """The disabled plugin that registers the ``kind`` (``stage``, ``tool_model``…) called
        ``name`` (tool models case-insensitively), if any. The disabled plugins are loaded
        for this, once, only when it is asked (to explain a name that is unknown)."""
        if not self.disabled or self.load_disabled is None:
            return None
        if self._left_out is None:
            self._left_out = self.load_disabled()
        table: dict[str, tuple[Any, str]] = getattr(self._left_out, kind + "s")
        fold = str.upper if kind == "tool_model" else str
        return next((owner for key, (_, owner) in table.items() if fold(key) == fold(name)), None)

    def plugin_label(self, plugin: str) -> str:
        info = self.plugins.get(plugin)
        return f"{plugin} {info.version}" if info else plugin

    def reader_for(self, path: Path, kind: str, name: str = "auto") -> ReaderDef:
        """The reader called ``name`` (it must read ``kind``) or, with ``auto``, the reader of
        ``kind`` surest that ``path`` is its own: the strongest :class:`Claim` wins, then a
        third-party reader over a built-in one; a tie left is a :class:`ReaderChoiceError`."""
        if name != "auto":
            found = self.readers.get(name)
            if found is None:
                raise ReaderChoiceError(
                    f"no reader named {name!r} (installed: {', '.join(sorted(self.readers))})"
                )
            if kind not in found[0].kinds:
                raise ReaderChoiceError(
                    f"reader {name!r} cannot read {kind} (it reads: {', '.join(found[0].kinds)})"
                )
            return found[0]
        able = [(r, owner) for r, owner in self.readers.values() if kind in r.kinds]
        claims = [(r.claim(path), not self._builtin(owner), r) for r, owner in able]
        best = max((claim for claim, _, _ in claims), default=Claim.NO)
        if best is Claim.NO:
            raise ReaderChoiceError(
                f"no installed reader recognises {str(path)!r} as {kind} (readers of {kind}: "
                f"{', '.join(r.name for r, _ in able) or 'none'}); name one with `reader:`"
            )
        top = [(third, r) for claim, third, r in claims if claim == best]
        if any(third for third, _ in top):
            top = [(third, r) for third, r in top if third]
        if len(top) > 1:
            named = ", ".join(
                f"{r.name} ({self.plugin_label(self.readers[r.name][1])})" for _, r in top
            )
            how = "by its content" if best is Claim.CONTENT else "by its name"
            raise ReaderChoiceError(
                f"several readers claim {str(path)!r} as {kind} {how}: {named}; "
                f"choose one with `reader:` (e.g. reader: {top[0][1].name})"
            )
        return top[0][1]

    def _reader_of(self, path: Path, kind: str, name: str) -> ReaderDef:
        """:meth:`reader_for`; when no reader of ``kind`` claims ``path`` but a reader of one
        other kind does by content, a :class:`WrongKindError` naming that kind (``found``): a
        WITSML trajectory given as samples is a stations file, not a file no reader knows."""
        try:
            return self.reader_for(path, kind, name)
        except ReaderChoiceError:
            readers = [r for r, _ in self.readers.values()]
            if name == "auto" and not any(kind in r.kinds and r.claim(path) for r in readers):
                other = next(
                    (r for r in readers if len(r.kinds) == 1 and r.claim(path) is Claim.CONTENT),
                    None,
                )
                if other is not None:
                    found = next(iter(other.kinds))
                    raise WrongKindError(
                        path,
                        f"a {other.name} file of {found}, not {kind} (no reader of {kind} "
                        "recognises it)",
                        found=found,
                    ) from None
            raise

    def read(
        self,
        path: Path,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        well: WellMetadata | None = None,
    ) -> tuple[pa.Table, WellMetadata]:
        """Read ``path`` as a table of ``kind`` (canonical units, contract of the kind) and
        return it with the well metadata found in the file.

        The reader is :meth:`reader_for`'s choice; ``options`` are validated by its options
        model, options marked as well defaults filled from ``well``. A third-party reader's
        failure (and any reader's unexpected exception) is a :class:`ReaderError` naming the
        reader and its plugin; built-in readers' located errors pass unchanged.
        """
        chosen = self._reader_of(path, kind, reader)
        return self._read_whole(chosen, path, kind, reader_options(chosen, options or {}, well))

    def _read_whole(
        self, chosen: ReaderDef, path: Path, kind: str, parsed: BaseModel
    ) -> tuple[pa.Table, WellMetadata]:
        """``chosen``'s table of ``path`` (options parsed), checked against the kind."""
        table, found = self._reading(chosen, lambda: chosen.read(path, kind, parsed))
        if getattr(parsed, DROP, None) == "drop":
            table = without_null_stations(path, table)
        check_read(path, kind, chosen, table, confirmed=bool(getattr(parsed, CONFIRM, False)))
        return table, found

    def read_stream(
        self,
        path: Path,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        well: WellMetadata | None = None,
    ) -> tuple[TableStream, WellMetadata]:
        """:meth:`read` as a stream: the reader's ``stream`` when it has one, else its table
        cut into slices. The schema is checked for the kind's columns at once, each batch
        against the kind's contract as it passes (the same errors as :meth:`read`, rows
        counted from the start of the file's table; a pass after one checked to its end is
        not checked again); a reader's failure while streaming is reported as :meth:`read`
        reports it."""
        chosen = self._reader_of(path, kind, reader)
        parsed = reader_options(chosen, options or {}, well)
        if chosen.stream is None:  # the reader and its options are resolved once
            table, found = self._read_whole(chosen, path, kind, parsed)
            return TableStream.from_table(table), found
        opener = chosen.stream
        stream, found = self._reading(chosen, lambda: opener(path, kind, parsed))
        check_columns(path, kind, chosen, stream.schema.names)
        contract = chosen.kinds[kind].compiled()
        proven = False  # a pass checked to its end: the file's batches hold the contract

        def checked() -> Iterator[pa.RecordBatch]:
            nonlocal proven
            checker = None if proven else BatchChecker(contract)
            batches = iter(stream)
            while True:
                batch = self._reading(chosen, lambda: next(batches, None))
                if batch is None:
                    proven = True
                    return
                try:
                    if checker is not None:
                        checker.check(batch)
                except ContractViolation as exc:
                    raise read_violation(path, kind, chosen, exc) from None
                yield batch

        holds = frozenset({chosen.kinds[kind]})
        return TableStream(stream.schema, checked, holds, stream.nbytes), found

    def _reading(self, reader: ReaderDef, call: Callable[[], Any]) -> Any:
        """``call()``, a reader's failure reported as :meth:`read` says."""
        owner = self.readers[reader.name][1]
        try:
            return call()
        except GyropipeError as exc:
            if self._builtin(owner):
                raise
            raise ReaderError(reader.name, self.plugin_label(owner), exc) from exc
        except Exception as exc:  # a reader's bug is reported against the reader
            raise ReaderError(reader.name, self.plugin_label(owner), exc) from exc

    def check_reader_options(
        self, kind: str, reader: str, options: Mapping[str, Any]
    ) -> BaseModel | None:
        """``options`` parsed by ``reader`` (``auto``: the first reader of ``kind`` taking them;
        None: none), else the best fit's :class:`ValidationError`. Used by validation."""
        if reader != "auto":
            found = self.readers.get(reader)
            candidates = [found[0]] if found is not None else []
        else:
            if not options:
                return None
            candidates = [r for r, _ in self.readers.values() if kind in r.kinds]
        errors: list[ValidationError] = []
        for candidate in candidates:
            try:
                return candidate.parse_options(options)
            except ValidationError as exc:
                errors.append(exc)
        if errors:
            raise min(errors, key=lambda e: e.error_count())
        return None

    def _builtin(self, plugin: str) -> bool:
        info = self.plugins.get(plugin)
        return info is None or info.builtin

    def provides(self, plugin: str) -> list[str]:
        """``kind:name`` of everything ``plugin`` registered."""
        return [
            f"{kind}:{name}"
            for kind in KIND_OF.values()
            for name, (_, owner) in getattr(self, kind + "s").items()
            if owner == plugin
        ]


def _validate(item: object, expected: type) -> tuple[str, str]:
    kind = KIND_OF[expected]
    if not isinstance(item, expected):
        raise TypeError(f"registered a {type(item).__name__} where a {expected.__name__} is needed")
    name = getattr(item, "name", None)
    if isinstance(item, ToolModelDef):
        if not isinstance(name, str) or not TOOL_MODEL_NAME.match(name):
            raise ValueError(
                f"tool model name {name!r} is invalid: use letters, digits, '.', '-' and '_'"
            )
        if not Path(item.path).is_file():
            raise ValueError(f"tool model {name!r}: no file {str(item.path)!r}")
        return kind, name
    if not isinstance(name, str) or not NAME.match(name):
        raise ValueError(
            f"{kind} name {name!r} is invalid: use lower-case letters, digits, '_' and '.'"
        )
    if isinstance(item, ReportDef):
        given = [a for a in ("method", "section") if getattr(item, a) is not None]
        if not given:
            raise ValueError(f"report part {name!r}: give a method or a section (or both)")
        for attr in given:
            if not callable(getattr(item, attr)):
                raise TypeError(f"report part {name!r}: {attr} is not callable")
        return kind, name
    callables = {
        "stage": ("func",),
        "reader": ("read", "sniff"),
        "writer": ("write",),
        "check": ("func",),
        "executor": ("factory",),
    }[kind]
    for attr in callables:
        if not callable(getattr(item, attr)):
            raise TypeError(f"{kind} {name!r}: {attr} is not callable")
    models: list[tuple[str, object, type]] = []
    if isinstance(item, StageDef):
        models.append(("params", item.params, BaseModel))
        models += [(f"input {p}", c, TableContract) for p, c in item.inputs.items()]
        models += [(f"output {p}", c, TableContract) for p, c in item.outputs.items()]
        for what, ports, declared in (
            ("optional inputs", item.optional_inputs, item.inputs),
            ("streamed inputs", item.streamed_inputs, item.inputs),
            ("streamed outputs", item.streamed_outputs, item.outputs),
            ("unread inputs", item.unread_inputs, item.inputs),
        ):
            unknown = set(ports) - set(declared)
            if unknown:
                kind_of = "inputs" if declared is item.inputs else "outputs"
                raise ValueError(f"stage {name!r}: {what} {sorted(unknown)} are not {kind_of}")
    elif isinstance(item, ReaderDef):
        models.append(("options", item.options, BaseModel))
        models += [(f"kind {k}", c, TableContract) for k, c in item.kinds.items()]
        if item.stream is not None and not callable(item.stream):
            raise TypeError(f"reader {name!r}: stream is not callable")
    elif isinstance(item, CheckDef):
        models += [("params", item.params, BaseModel), ("contract", item.contract, TableContract)]
    elif isinstance(item, WriterDef):
        for attr in ("write_tables", "write_stream"):
            if getattr(item, attr) is not None and not callable(getattr(item, attr)):
                raise TypeError(f"writer {name!r}: {attr} is not callable")
        if item.schema is not None:
            models.append(("schema", item.schema, BaseModel))
    for what, model, base in models:
        if not (isinstance(model, type) and issubclass(model, base)):
            raise TypeError(f"{kind} {name!r}: {what} must be a {base.__name__} subclass")
    return kind, name

"""Runs one well's DAG: inputs checked against contracts before each stage, outputs after,
chosen outputs persisted, the manifest written, everything published in one step.

A run's files are written into a private staging directory beside the output directory,
which replaces the output directory whole when every stage has succeeded: a failed or
killed run changes nothing, and the output directory holds one complete run.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import os
import shutil
import tempfile
import time
import uuid
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any, TypeAlias, TypeVar

import pyarrow as pa

from pipeline.atomic import atomic_write_bytes, discard, fsync_files, replace_dir, write_synced
from pipeline.contracts import SOURCE_KEY, implies
from pipeline.errors import (
    ContractViolation,
    FileSystemError,
    GyropipeError,
    ParameterError,
    StageError,
    file_errors,
)
from pipeline.graph import Plan, PlannedStage
from pipeline.hashing import FileKey, key_after, regular_bytes, sha256_file
from pipeline.inputfiles import parameter_paths
from pipeline.manifest import MANIFEST, StageRecord, acceptance, provenance_of, run_manifest
from pipeline.ports import (
    CheckedTables,
    Tables,
    UpstreamError,
    counted,
    kept,
    settled,
    write_port,
)
from pipeline.processes import owner_alive
from pipeline.provenance import ParameterFile
from pipeline.registry import (
    CheckDef,
    PluginInfo,
    Provenance,
    Registry,
    WriterDef,
)
from pipeline.reporting import ReportDef
from pipeline.streams import Port, TableStream, as_stream, as_table, release
from pipeline.well import WellMetadata, agreed, well_of

T = TypeVar("T")
STAGING_PREFIX = ".gyropipe-staging-"


class RunInputError(GyropipeError):
    """The files given for a run do not match the pipeline's declared inputs."""


class InputChangedError(GyropipeError):
    """A file the run read changed while it ran: ``run.json`` could not say which bytes the
    outputs come from, so nothing is published."""

    def __init__(self, paths: list[str]) -> None:
        self.paths = paths
        super().__init__(
            f"changed while the run read it: {', '.join(paths)}; nothing was published "
            "(run it again once the file is complete)"
        )


@dataclass
class RunResult:
    """The outcome of a successful run: every stage output table by (stage id, port), the
    well metadata at the end, and (a run with an output directory) the files published."""

    out_dir: Path | None
    manifest: dict[str, Any]
    tables: Tables[tuple[str, str]]
    well: WellMetadata
    outputs: list[Path]


Source: TypeAlias = "Path | pa.Table"
"""What a pipeline input is given as: a file, or a table already read (the Python API)."""


@dataclass
class _Context:
    """The :class:`~pipeline.registry.StageContext` given to stages."""

    stage_id: str
    well: WellMetadata
    registry: Registry
    inputs: Mapping[str, Source]
    staging: Path
    staged: list[Path]
    provenance: Provenance
    found: list[WellMetadata] = field(default_factory=list)
    """well metadata the stage reported (:meth:`update_well`, the headers of inputs it read)"""
    headers: dict[str, WellMetadata] = field(default_factory=dict)
    """the headers of the inputs it read, by input name"""
    out_dir: Path | None = None
    """where the staged files will be published"""
    own: tuple[WellMetadata, WellMetadata] = (WellMetadata(), WellMetadata())
    """the pipeline's ``well:`` and the run's overrides: a table's own header goes between
    them (:meth:`well_for`)"""

    def well_for(self, header: WellMetadata | None) -> WellMetadata:
        if header is None:
            return self.well
        pipeline, overrides = self.own
        return pipeline.merged(header).merged(overrides)

    def record_file(self, path: Path, param: str, what: str, sha256: str | None = None) -> str:
        self.provenance.see(path)
        digest = sha256 or sha256_file(path)
        entry = ParameterFile(str(path.absolute()), digest, self.stage_id, param, what)
        self.provenance.read.setdefault(entry)
        return entry.sha256

    def update_well(self, found: WellMetadata) -> None:
        self.found.append(found)

    def found_header(self, name: str, header: WellMetadata) -> None:
        """The header of the input ``name``, read: into the run's well."""
        self.headers[name] = header
        self.update_well(header)

    def published(self, path: Path) -> Path:
        """Where a file of the staging directory will be once published (others: itself)."""
        if self.out_dir is not None and path.parent == self.staging:
            return self.out_dir / path.name
        return path

    def input_path(self, name: str) -> Path:
        given = self.inputs[name]
        if isinstance(given, pa.Table):
            raise RunInputError(f"input {name!r} was given as a table; this stage needs a file")
        return given

    def read_input(
        self,
        name: str,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        into_well: bool = True,
    ) -> tuple[pa.Table, WellMetadata]:
        given = self.inputs[name]
        if isinstance(given, pa.Table):
            header = well_of(given) or WellMetadata()
            if into_well:
                self.found_header(name, header)
            return given, header
        table, header = self.read_file(given, kind, reader=reader, options=options)
        if into_well:
            self.found_header(name, header)
        meta = {**(table.schema.metadata or {}), SOURCE_KEY: str(given).encode()}
        return table.replace_schema_metadata(meta), header

    def read_input_stream(
        self,
        name: str,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
        into_well: bool = True,
    ) -> tuple[TableStream, WellMetadata]:
        given = self.inputs[name]
        if isinstance(given, pa.Table):
            header = well_of(given) or WellMetadata()
            if into_well:
                self.found_header(name, header)
            return TableStream.from_table(given), header
        stream, header = self.registry.read_stream(
            given, kind, reader=reader, options=options, well=self.well_for(WellMetadata())
        )
        self._north_agrees(given, header)
        self._dates_agree(given, header)
        if into_well:
            self.found_header(name, header)
        meta = {**(stream.schema.metadata or {}), SOURCE_KEY: str(given).encode()}
        return stream.replace_schema_metadata(meta), header

    def output_path(self, filename: str) -> Path:
        path = self.staging / filename
        if path.parent != self.staging or path in self.staged:
            raise ValueError(f"output file name {filename!r} is not a new plain file name")
        self.staged.append(path)
        return path

    def read_file(
        self,
        path: Path,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
    ) -> tuple[pa.Table, WellMetadata]:
        run = self.well_for(WellMetadata())  # the run's, not another file's header
        table, header = self.registry.read(path, kind, reader=reader, options=options, well=run)
        self._north_agrees(path, header)
        self._dates_agree(path, header)
        return table, header

    def _north_agrees(self, path: Path, header: WellMetadata) -> None:
        """Refuse a run's override of the north reference that contradicts the one a file
        names for its azimuths: the override is the azimuths' north only where the file
        names none (the readers' default), so over a file naming another it would state a
        north its azimuths are not in."""
        wanted, named = self.own[1].north_reference, header.north_reference
        if wanted is not None and named is not None and named != wanted:
            raise RunInputError(
                f"{path}: the file names {named} north for its azimuths; the run's well "
                f"override north_reference={wanted} contradicts it (an override states the "
                "north of azimuths whose file names none; drop it, or correct the file)"
            )

    def _dates_agree(self, path: Path, header: WellMetadata) -> None:
        """Refuse a run's override of the survey's last day (``survey_date_last`` alone)
        before the survey date a file states: the run's well would be out of order."""
        try:
            header.merged(self.own[1])
        except ParameterError as exc:
            raise RunInputError(
                f"{path}: the file states survey_date {header.survey_date}; the run's well "
                f"override contradicts it: {exc}"
            ) from None

    def writer(self, name: str) -> WriterDef:
        return _lookup(self.registry.writers, name, "writer")

    def check(self, name: str) -> CheckDef:
        return _lookup(self.registry.checks, name, "check")

    def report_parts(self) -> list[tuple[ReportDef, PluginInfo]]:
        return self.registry.report_parts()


def _lookup(table: Mapping[str, tuple[T, str]], name: str, kind: str) -> T:
    try:
        return table[name][0]
    except KeyError:
        raise KeyError(
            f"no {kind} named {name!r} (installed: {', '.join(sorted(table)) or 'none'})"
        ) from None


def run_plan(
    plan: Plan,
    registry: Registry,
    *,
    inputs: Mapping[str, Source],
    out_dir: Path | None,
    well: WellMetadata | None = None,
    publish_as: Path | None = None,
    known_inputs: Mapping[str, tuple[str, FileKey | None]] | None = None,
) -> RunResult:
    """Run ``plan`` for one well. Its well metadata is the pipeline's ``well:``, updated by
    what the stages report (the headers of the inputs they read, a simulation's site:
    :meth:`~pipeline.registry.StageContext.update_well`), under ``well`` (overrides), a field
    the inputs' headers state differently left unstated (survey dates: their range;
    :func:`~pipeline.well.agreed`, ``run.json``'s ``well_differs``); each stage gets it as it
    stands (``ctx.well``), ``run.json`` records it at the end. A table's own header is
    :meth:`~pipeline.registry.StageContext.well_for`'s.

    With ``out_dir``, the run's files (stage outputs, persisted tables, ``run.json``) are
    written into a private staging directory beside it, and ``out_dir`` is replaced by it in
    one step when every stage has succeeded (:func:`~pipeline.atomic.replace_dir`): a reader
    sees the previous run or the new one whole, and a failed or killed run changes nothing.
    ``out_dir`` must be new, empty or hold a previous run (files its ``run.json`` lists);
    anything else there is refused, never deleted. Without ``out_dir`` nothing is written:
    stages that only write files are skipped, and the tables are returned.

    With ``publish_as``, ``out_dir`` is a new private directory (a batch worker's staging)
    that the caller publishes as ``publish_as`` (:func:`~pipeline.atomic.replace_dir`): the
    run writes into it, each file fsynced, ``run.json`` naming them at ``publish_as``.
    ``known_inputs``: input name → its SHA-256 known without reading it (a batch worker's),
    with the file's stat key before it was hashed (None: it had none); each input file's key
    is checked again before ``run.json`` is written (:class:`InputChangedError`).

    Raises :class:`RunInputError`, :class:`ContractViolation` or :class:`StageError`.
    """
    files = _check_inputs(plan, inputs)
    if out_dir is not None:
        check_out_dir(out_dir)
    overrides = well or WellMetadata()
    from_files = WellMetadata()
    headers: dict[str, WellMetadata] = {}  # of the inputs read, by name
    differ: dict[str, dict[str, Any]] = {}  # field → input → value, where they differ
    current = plan.spec.well.merged(from_files).merged(overrides)
    records: list[StageRecord] = []
    known = known_inputs or {}
    seen = {  # each input's key before it was hashed
        str(p.absolute()): known[n][1] if n in known else key_after(p)
        for n, p in files.items()
        if isinstance(p, Path)
    }
    digests = {n: digest for n, (digest, _) in known.items()}
    provenance = provenance_of(plan, registry, files, start_time(), digests)
    provenance.seen.update(seen)
    t_run = time.perf_counter()
    with _staging(out_dir, private=publish_as is not None) as staging:
        staged: list[Path] = []
        ports: dict[tuple[str, str], Port] = {}
        held = 0  # bytes of the passes kept (ports.kept: at most KEEP_BYTES a run)
        checked = CheckedTables()
        for st in plan.stages:
            record = StageRecord(st.id, st.uses, registry.plugin_label(st.plugin))
            records.append(record)
            if out_dir is None and not st.definition.outputs:
                record.status = "skipped"  # it only writes files
                for key in st.releases:
                    release(ports[key])
                continue
            ins = _stage_inputs(plan, st, ports, record, checked)
            ctx = _Context(
                st.id,
                current,
                registry,
                files,
                staging,
                staged,
                provenance,
                out_dir=out_dir,
                own=(plan.spec.well, overrides),
            )
            t0 = time.perf_counter()
            outs = settled(lambda: _call(st, ins, ctx, registry))  # noqa: B023 (called here)
            record.wall_time_s = time.perf_counter() - t0
            tables = {p: t for p, t in outs.items() if isinstance(t, pa.Table)}
            _check_ports(plan, st, tables, "output", checked)
            record.rows_out.update({p: t.num_rows for p, t in tables.items()})
            record.acceptance = acceptance(st, tables)
            for header in ctx.found:
                from_files = from_files.merged(header)
            if ctx.headers:  # where the inputs' headers differ no one of them is the run's
                headers.update(ctx.headers)
                update, differ = agreed(headers)
                from_files = from_files.merged(update)
            for port, value in outs.items():
                if isinstance(value, TableStream):  # read by several: decoded once if small
                    produced = _produced(plan, st, port, value, registry, record)
                    nbytes = value.nbytes or 0
                    value = kept(produced, st.passes.get(port, 1), value.nbytes, held)
                    if value is not produced:
                        held += nbytes
                ports[(st.id, port)] = value
            for key in st.releases:  # its pass kept for no later stage
                release(ports[key])
            if ctx.found:  # (else the well stands as it was: two merges cost ~40 µs)
                current = plan.spec.well.merged(from_files).merged(overrides)
            record.status = "ok"
        if out_dir is None:
            result = Tables(ports)
            settled(lambda: [result[key] for key in result])  # the API returns tables
            _check_unchanged(provenance)
            wall = time.perf_counter() - t_run
            manifest = run_manifest(provenance, current, records, [], wall, differ)
            return RunResult(None, manifest, result, current, [])
        persisted = settled(lambda: _persist(plan, registry, ports, current, staging, out_dir))
        settled(lambda: _drain(plan, ports, records))
        for value in ports.values():
            release(value)
        written = staged + persisted
        clashes = {p.name for p in written if written.count(p) > 1} | (
            {MANIFEST} & {p.name for p in written}
        )
        if clashes:
            raise RunInputError(f"several outputs would be written as {sorted(clashes)}")
        fsync_files(written, lambda path: out_dir / path.name)
        _check_unchanged(provenance)
        final = [(publish_as or out_dir) / p.name for p in written]
        wall = time.perf_counter() - t_run
        manifest = run_manifest(
            provenance, current, records, list(zip(written, final, strict=True)), wall, differ
        )
        write = atomic_write_bytes if publish_as is None else write_synced
        write(staging / MANIFEST, json.dumps(manifest, indent=2).encode())
        if publish_as is None:
            replace_dir(staging, out_dir)
    return RunResult(out_dir, manifest, Tables(ports), current, final)


def _check_unchanged(provenance: Provenance) -> None:
    """Raise :class:`InputChangedError` if a file the run hashed has changed since."""
    changed = provenance.changed()
    if changed:
        raise InputChangedError(changed)


def _stage_inputs(
    plan: Plan, st: PlannedStage, ports: dict[tuple[str, str], Port], record: StageRecord,
    checked: CheckedTables,
) -> dict[str, Port]:  # fmt: skip
    """The stage's inputs by port: a stream on a streamed input port (a table cut into
    slices; checked per batch as it passes unless its producer checked the same contract),
    a table on any other (a stream read whole once, and kept for the next consumer)."""
    ins: dict[str, Port] = {}
    for port, src in st.wiring.items():
        value = ports[src]
        if port not in st.definition.streamed_inputs:
            if isinstance(value, TableStream):
                value = ports[src] = settled(value.read_all)
            ins[port] = value
            continue
        stream = as_stream(value)
        if not _checked_upstream(plan, st, port):
            stream = _checked(plan, st, port, stream, "input")
        ins[port] = counted(stream, record.rows_in, port)
    tables = {p: t for p, t in ins.items() if isinstance(t, pa.Table)}
    record.rows_in.update({p: t.num_rows for p, t in tables.items()})
    _check_ports(plan, st, tables, "input", checked)
    return ins


def _checked(
    plan: Plan, st: PlannedStage, port: str, stream: TableStream, direction: str
) -> TableStream:
    """``stream`` checked batch by batch against the port's contract, a violation located
    at the port and carried to whoever consumes the stream."""
    contracts = st.definition.inputs if direction == "input" else st.definition.outputs
    checked = contracts[port].validate_stream(stream)

    def located() -> Iterator[pa.RecordBatch]:
        try:
            yield from checked
        except ContractViolation as exc:
            where = exc.located(
                pipeline=plan.spec.name, stage=st.id, port=port, direction=direction
            )
            raise UpstreamError(where) from None

    return TableStream(stream.schema, located, checked.holds)


def _produced(
    plan: Plan,
    st: PlannedStage,
    port: str,
    stream: TableStream,
    registry: Registry,
    record: StageRecord,
) -> TableStream:
    """A stage's streamed output as its consumers get it: a failure while it is computed
    is the producing stage's :class:`StageError`; its batches are checked against the
    output contract, and counted (``rows_out``)."""
    plugin = registry.plugin_label(st.plugin)

    def attributed() -> Iterator[pa.RecordBatch]:
        try:
            yield from stream
        except UpstreamError:
            raise
        except Exception as exc:  # any failure inside a stage is reported as that stage's
            error = StageError(st.id, st.uses, plugin, exc)
            error.__cause__ = exc
            raise UpstreamError(error) from exc

    attributed_stream = TableStream(stream.schema, attributed, stream.holds)
    checked = _checked(plan, st, port, attributed_stream, "output")
    return counted(checked, record.rows_out, port)


def _drain(plan: Plan, ports: Mapping[tuple[str, str], Port], records: list[StageRecord]) -> None:
    """Run one pass of every streamed output that nothing consumed to its end, so that its
    errors are raised and its rows counted as a table's would be."""
    for st, record in zip(plan.stages, records, strict=True):
        for port in st.definition.outputs:
            value = ports.get((st.id, port))
            if isinstance(value, TableStream) and port not in record.rows_out:
                for _ in value:
                    pass


@contextlib.contextmanager
def _staging(out_dir: Path | None, *, private: bool = False) -> Iterator[Path]:
    """A private directory for the run's files: beside ``out_dir`` (so it can be renamed to
    it), or a temporary one; removed unless it was published (``private``: ``out_dir``)."""
    if out_dir is not None and private:
        yield out_dir
        return
    if out_dir is None:
        with tempfile.TemporaryDirectory(prefix=STAGING_PREFIX) as tmp:
            yield Path(tmp)
        return
    staging = out_dir.parent / f"{_staging_prefix(out_dir)}{os.getpid()}-{uuid.uuid4().hex[:8]}"
    with file_errors("create the output directory", out_dir):
        out_dir.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_staging(out_dir.parent)
        staging.mkdir()
    try:
        yield staging
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _staging_prefix(out_dir: Path) -> str:
    return f".{out_dir.name}{STAGING_PREFIX}"


def check_out_dir(out_dir: Path, own: frozenset[str] = frozenset()) -> None:
    """``out_dir`` is new, empty, or holds only a previous run's files (``run.json``, the
    outputs it lists, and the names in ``own``, e.g. a batch's marker); else
    :class:`RunInputError` naming the directory and the foreign files."""
    if not out_dir.exists():
        return
    if not out_dir.is_dir():
        raise RunInputError(f"output directory {str(out_dir)!r} is a file")
    entries = {p.name for p in out_dir.iterdir()}
    if not entries:
        return
    try:
        previous = json.loads(regular_bytes(out_dir / MANIFEST))  # a FIFO would block
        known = {MANIFEST, *own} | {entry["file"] for entry in previous["outputs"]}
    except (OSError, ValueError, KeyError, TypeError):
        known = set()
    foreign = sorted(entries - known)
    if foreign:
        shown = ", ".join(foreign[:5]) + (", …" if len(foreign) > 5 else "")
        raise RunInputError(
            f"output directory {str(out_dir)!r} holds files that are not a previous run's "
            f"({shown}); a run replaces its output directory whole: give a new or empty one"
        )


def start_time() -> dt.datetime:
    """Now (UTC), or the time ``SOURCE_DATE_EPOCH`` gives (s since 1970, the reproducible-
    builds convention): with it set, a run's outputs are byte-identical from run to run."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch is not None and epoch.strip().isdigit():
        return dt.datetime.fromtimestamp(int(epoch), dt.UTC)
    return dt.datetime.now(dt.UTC)


def run_stage(
    stage: PlannedStage,
    inputs: Mapping[str, pa.Table],
    *,
    registry: Registry,
    well: WellMetadata,
    overrides: WellMetadata,
    provenance: Provenance,
    out_dir: Path,
) -> tuple[dict[str, pa.Table], list[Path]]:
    """Run one stage outside a plan (the Python API): its input and output tables checked
    against the stage's contracts, a failure inside it a :class:`StageError`; it writes its
    files (if any) into ``out_dir``. ``well``: the inputs' headers merged under
    ``overrides`` (the caller's), which a table's own header is under
    (:meth:`~pipeline.registry.StageContext.well_for`). Returns its output tables and the
    files written."""
    _check_contracts("", stage, inputs, "input")
    ctx = _Context(
        stage.id, well, registry, {}, out_dir, [], provenance, own=(WellMetadata(), overrides)
    )
    given: dict[str, Port] = {
        port: TableStream.from_table(table) if port in stage.definition.streamed_inputs else table
        for port, table in inputs.items()
    }
    outs = _call(stage, given, ctx, registry)
    outputs = {port: settled(partial(as_table, value)) for port, value in outs.items()}
    _check_contracts("", stage, outputs, "output")
    return outputs, ctx.staged


def _call(
    st: PlannedStage, ins: dict[str, Port], ctx: _Context, registry: Registry
) -> dict[str, Port]:
    plugin = registry.plugin_label(st.plugin)
    before = len(ctx.staged)
    try:
        for param, path in parameter_paths(st.params):  # the files its params name
            ctx.record_file(path, param, param.rsplit(".", 1)[-1])
        outs = st.definition.func(ins, st.params, ctx)
    except UpstreamError:
        raise
    except OSError as exc:  # the file named, else the stage's latest output (as published)
        written = ctx.staged[before:]
        named = Path(exc.filename) if exc.filename else written[-1] if written else None
        where = ctx.published(named) if named is not None else f"the outputs of {st.id}"
        failure = FileSystemError.of(exc, "write" if exc.filename is None else "access", where)
        raise StageError(st.id, st.uses, plugin, failure) from exc
    except Exception as exc:  # any failure inside a stage is reported as that stage's
        raise StageError(st.id, st.uses, plugin, exc) from exc
    streamed = st.definition.streamed_outputs
    if not isinstance(outs, Mapping) or not all(
        isinstance(t, pa.Table) or (isinstance(t, TableStream) and p in streamed)
        for p, t in outs.items()
    ):
        raise StageError(
            st.id, st.uses, plugin, TypeError("must return a mapping of port name → pyarrow.Table")
        )
    if set(outs) != set(st.definition.outputs):
        raise StageError(
            st.id,
            st.uses,
            plugin,
            ValueError(f"returned ports {sorted(outs)}, declared {sorted(st.definition.outputs)}"),
        )
    return dict(outs)


def _check_ports(
    plan: Plan, st: PlannedStage, tables: Mapping[str, pa.Table], direction: str,
    checked: CheckedTables,
) -> None:  # fmt: skip
    """Check a stage's input or output tables, each (table, contract) once in the run."""
    if direction == "input":
        tables = {p: t for p, t in tables.items() if not _checked_upstream(plan, st, p)}
    contracts = st.definition.inputs if direction == "input" else st.definition.outputs
    tables = {p: t for p, t in tables.items() if checked.first(t, contracts[p])}
    _check_contracts(plan.spec.name, st, tables, direction)


def _check_contracts(
    pipeline: str, st: PlannedStage, tables: Mapping[str, pa.Table], direction: str
) -> None:
    contracts = st.definition.inputs if direction == "input" else st.definition.outputs
    for port, table in tables.items():
        try:
            contracts[port].validate_table(table)
        except ContractViolation as exc:
            raise exc.located(
                pipeline=pipeline, stage=st.id, port=port, direction=direction
            ) from None


def _checked_upstream(plan: Plan, st: PlannedStage, port: str) -> bool:
    """True if the value on ``port`` was already checked as the upstream stage's output
    against a contract that implies the input's (:func:`~pipeline.contracts.implies`; the
    value is immutable, so checking it again proves nothing)."""
    upstream, out_port = st.wiring[port]
    producer = next(s for s in plan.stages if s.id == upstream)
    return implies(producer.definition.outputs[out_port], st.definition.inputs[port])


def _check_inputs(plan: Plan, given: Mapping[str, Source]) -> dict[str, Source]:
    declared = plan.spec.inputs
    problems = [f"unknown input {n!r}" for n in given if n not in declared]
    problems += [f"missing input {n!r}: give --input {n}=FILE" for n in declared if n not in given]
    problems += [
        f"input {n!r}: no such file {str(p)!r}"
        for n, p in given.items()
        if n in declared and not isinstance(p, pa.Table) and not Path(p).is_file()
    ]
    if problems:
        names = ", ".join(declared) or "none"
        raise RunInputError(
            f"pipeline {plan.spec.name!r} (inputs: {names}): " + "; ".join(problems)
        )
    return {n: p if isinstance(p, pa.Table) else Path(p) for n, p in given.items()}


def _persist(
    plan: Plan,
    registry: Registry,
    ports: Mapping[tuple[str, str], Port],
    well: WellMetadata,
    staging: Path,
    out_dir: Path,
) -> list[Path]:
    writer = _lookup(registry.writers, plan.spec.defaults.persist_format, "writer")
    paths = []
    for st in plan.stages:
        for port in st.persist:
            path = staging / f"{st.id}.{port}.{writer.extension}"
            with file_errors("write", out_dir / path.name):
                write_port(writer, ports[(st.id, port)], path, well)
            paths.append(path)
    return paths


def remove_stale_staging(directory: Path) -> list[Path]:
    """Remove the staging directories (and their trash) that runs whose process no longer
    exists left in ``directory``; returns them."""
    removed = []
    for entry in directory.glob(f".*{STAGING_PREFIX}*"):
        pid_text = entry.name.split(STAGING_PREFIX, 1)[1].split("-", 1)[0]
        if pid_text.isdigit() and not owner_alive(int(pid_text), entry):
            discard(entry)
            removed.append(entry)
    return removed

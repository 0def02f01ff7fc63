"""Runs one well's DAG: inputs checked against contracts before each stage, outputs after,
chosen outputs persisted, everything published atomically, a manifest written last.

Files a run produces are written into a private staging directory inside the output
directory and moved to their final names only when every stage has succeeded, so a failed
or interrupted run leaves no final-named file behind.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import json
import os
import shutil
import time
import uuid
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import pyarrow as pa

from pipeline.atomic import atomic_write_bytes, publish
from pipeline.errors import ContractViolation, GyropipeError, StageError
from pipeline.graph import Plan, PlannedStage
from pipeline.registry import (
    CheckDef,
    InputFile,
    Provenance,
    Registry,
    StageSetup,
    WriterDef,
)
from pipeline.version import __version__
from pipeline.well import WellMetadata, attach, well_of

MANIFEST = "run.json"
STAGING_PREFIX = ".gyropipe-staging-"


class RunInputError(GyropipeError):
    """The files given for a run do not match the pipeline's declared inputs."""


@dataclass
class StageRecord:
    """What one stage did: timing and row counts per port."""

    id: str
    uses: str
    plugin: str
    wall_time_s: float = 0.0
    rows_in: dict[str, int] = field(default_factory=dict)
    rows_out: dict[str, int] = field(default_factory=dict)
    status: str = "pending"


@dataclass
class RunResult:
    """The outcome of a successful run."""

    out_dir: Path
    manifest: dict[str, Any]
    tables: dict[tuple[str, str], pa.Table]
    well: WellMetadata
    outputs: list[Path]


@dataclass
class _Context:
    """The :class:`~pipeline.registry.StageContext` given to stages."""

    stage_id: str
    well: WellMetadata
    registry: Registry
    inputs: Mapping[str, Path]
    staging: Path
    staged: list[Path]
    provenance: Provenance

    def input_path(self, name: str) -> Path:
        return self.inputs[name]

    def output_path(self, filename: str) -> Path:
        path = self.staging / filename
        if path.parent != self.staging or path in self.staged:
            raise ValueError(f"output file name {filename!r} is not a new plain file name")
        self.staged.append(path)
        return path

    def read(
        self,
        path: Path,
        kind: str,
        *,
        reader: str = "auto",
        options: Mapping[str, Any] | None = None,
    ) -> tuple[pa.Table, WellMetadata]:
        return self.registry.read(path, kind, reader=reader, options=options, well=self.well)

    def writer(self, name: str) -> WriterDef:
        return _lookup(self.registry.writers, name, "writer")

    def check(self, name: str) -> CheckDef:
        return _lookup(self.registry.checks, name, "check")


T = TypeVar("T")


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
    inputs: Mapping[str, Path],
    out_dir: Path,
    well: WellMetadata | None = None,
) -> RunResult:
    """Run ``plan`` for one well. ``well`` overrides metadata from the pipeline and files.

    Raises :class:`RunInputError`, :class:`ContractViolation` or :class:`StageError`; on
    any failure no output file appears under ``out_dir``.
    """
    files = _check_inputs(plan, inputs)
    overrides = well or WellMetadata()
    from_files = WellMetadata()
    current = plan.spec.well.merged(from_files).merged(overrides)
    out_dir.mkdir(parents=True, exist_ok=True)
    _remove_stale_staging(out_dir)
    staging = out_dir / f"{STAGING_PREFIX}{os.getpid()}-{uuid.uuid4().hex[:8]}"
    staging.mkdir()
    staged: list[Path] = []
    tables: dict[tuple[str, str], pa.Table] = {}
    records: list[StageRecord] = []
    started = dt.datetime.now(dt.UTC)
    provenance = _provenance(plan, registry, files, started)
    t_run = time.perf_counter()
    try:
        for st in plan.stages:
            record = StageRecord(st.id, st.uses, registry.plugin_label(st.plugin))
            records.append(record)
            ins = {port: tables[src] for port, src in st.wiring.items()}
            record.rows_in = {p: t.num_rows for p, t in ins.items()}
            _check_ports(plan, st, ins, "input")
            ctx = _Context(st.id, current, registry, files, staging, staged, provenance)
            t0 = time.perf_counter()
            outs = _call(st, ins, ctx, registry)
            record.wall_time_s = time.perf_counter() - t0
            _check_ports(plan, st, outs, "output")
            record.rows_out = {p: t.num_rows for p, t in outs.items()}
            for port, table in outs.items():
                header = well_of(table)
                if header is not None:
                    from_files = from_files.merged(header)
                tables[(st.id, port)] = table
            current = plan.spec.well.merged(from_files).merged(overrides)
            record.status = "ok"
        persisted = _persist(plan, registry, tables, current, staging)
        wall = time.perf_counter() - t_run
        final = [out_dir / p.name for p in staged + persisted]
        clashes = {p.name for p in final if final.count(p) > 1} | (
            {MANIFEST} & {p.name for p in final}
        )
        if clashes:
            raise RunInputError(f"several outputs would be written as {sorted(clashes)}")
        for src, dst in zip(staged + persisted, final, strict=True):
            publish(src, dst)
        manifest = _manifest(provenance, current, records, final, wall)
        atomic_write_bytes(out_dir / MANIFEST, json.dumps(manifest, indent=2).encode())
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return RunResult(out_dir, manifest, tables, current, final)


def _call(
    st: PlannedStage, ins: dict[str, pa.Table], ctx: _Context, registry: Registry
) -> dict[str, pa.Table]:
    plugin = registry.plugin_label(st.plugin)
    try:
        outs = st.definition.func(ins, st.params, ctx)
    except Exception as exc:  # any failure inside a stage is reported as that stage's
        raise StageError(st.id, st.uses, plugin, exc) from exc
    if not isinstance(outs, Mapping) or not all(isinstance(t, pa.Table) for t in outs.values()):
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
    plan: Plan, st: PlannedStage, tables: Mapping[str, pa.Table], direction: str
) -> None:
    contracts = st.definition.inputs if direction == "input" else st.definition.outputs
    for port, table in tables.items():
        if direction == "input" and _checked_upstream(plan, st, port):
            continue
        try:
            contracts[port].validate_table(table)
        except ContractViolation as exc:
            raise exc.located(
                pipeline=plan.spec.name, stage=st.id, port=port, direction=direction
            ) from None


def _checked_upstream(plan: Plan, st: PlannedStage, port: str) -> bool:
    """True if the table on ``port`` was already checked against the very same contract as
    the upstream stage's output (tables are immutable, so checking again proves nothing)."""
    upstream, out_port = st.wiring[port]
    producer = next(s for s in plan.stages if s.id == upstream)
    return producer.definition.outputs[out_port] is st.definition.inputs[port]


def _check_inputs(plan: Plan, given: Mapping[str, Path]) -> dict[str, Path]:
    declared = plan.spec.inputs
    problems = [f"unknown input {n!r}" for n in given if n not in declared]
    problems += [f"missing input {n!r}: give --input {n}=FILE" for n in declared if n not in given]
    problems += [
        f"input {n!r}: no such file {str(p)!r}"
        for n, p in given.items()
        if n in declared and not Path(p).is_file()
    ]
    if problems:
        names = ", ".join(declared) or "none"
        raise RunInputError(
            f"pipeline {plan.spec.name!r} (inputs: {names}): " + "; ".join(problems)
        )
    return {n: Path(p) for n, p in given.items()}


def _persist(
    plan: Plan,
    registry: Registry,
    tables: dict[tuple[str, str], pa.Table],
    well: WellMetadata,
    staging: Path,
) -> list[Path]:
    writer = _lookup(registry.writers, plan.spec.defaults.persist_format, "writer")
    paths = []
    for st in plan.stages:
        for port in st.persist:
            path = staging / f"{st.id}.{port}.{writer.extension}"
            writer.write(attach(tables[(st.id, port)], well), path, well)
            paths.append(path)
    return paths


def _provenance(
    plan: Plan, registry: Registry, files: dict[str, Path], started: dt.datetime
) -> Provenance:
    return Provenance(
        pipeline=plan.spec.name,
        pipeline_version=plan.spec.version,
        pipeline_file=plan.file,
        pipeline_sha256=plan.digest,
        gyropipe=__version__,
        plugins={n: p.version for n, p in sorted(registry.plugins.items()) if not p.error},
        inputs={n: InputFile(**_file_entry(p)) for n, p in files.items()},
        started=started,
        stages=tuple(
            StageSetup(
                st.id, st.uses, registry.plugin_label(st.plugin), st.params.model_dump(mode="json")
            )
            for st in plan.stages
        ),
    )


def _manifest(
    provenance: Provenance,
    well: WellMetadata,
    records: list[StageRecord],
    outputs: list[Path],
    wall: float,
) -> dict[str, Any]:
    return {
        "status": "ok",
        "gyropipe": provenance.gyropipe,
        "pipeline": {
            "name": provenance.pipeline,
            "version": provenance.pipeline_version,
            "file": provenance.pipeline_file,
            "sha256": provenance.pipeline_sha256,
        },
        "started": provenance.started.isoformat(),
        "wall_time_s": round(wall, 6),
        "plugins": dict(provenance.plugins),
        "inputs": {n: dataclasses.asdict(f) for n, f in provenance.inputs.items()},
        "well": well.model_dump(mode="json", exclude_none=True),
        "stages": [
            {
                "id": r.id,
                "uses": r.uses,
                "plugin": r.plugin,
                "status": r.status,
                "wall_time_s": round(r.wall_time_s, 6),
                "rows_in": r.rows_in,
                "rows_out": r.rows_out,
            }
            for r in records
        ],
        "outputs": [{"file": p.name, **_file_entry(p)} for p in outputs],
    }


def _file_entry(path: Path) -> dict[str, Any]:
    return {"path": str(path), "sha256": sha256_file(path), "bytes": path.stat().st_size}


def sha256_file(path: Path) -> str:
    """SHA-256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _remove_stale_staging(out_dir: Path) -> None:
    """Remove staging directories of runs whose process no longer exists."""
    for entry in out_dir.glob(STAGING_PREFIX + "*"):
        pid_text = entry.name[len(STAGING_PREFIX) :].split("-", 1)[0]
        if pid_text.isdigit() and not process_alive(int(pid_text)):
            shutil.rmtree(entry, ignore_errors=True)


def process_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists on this host (one of another user counts)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True

"""What a run's ``run.json`` holds: its provenance (pipeline, software, inputs, stages), what
each stage did, the files published with their SHA-256 and size, and the acceptance gates."""

from __future__ import annotations

import datetime as dt
import hashlib
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import pyarrow as pa

from pipeline.errors import file_errors
from pipeline.graph import Plan, PlannedStage
from pipeline.hashing import sha256_file
from pipeline.registry import InputFile, Provenance, Registry, StageSetup
from pipeline.version import __version__
from pipeline.well import WellMetadata

MANIFEST = "run.json"
REJECTED = "rejected"
"""``run.json``'s ``status`` of a run that succeeded but failed an acceptance gate"""


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
    acceptance: list[dict[str, Any]] = field(default_factory=list)
    """the rows of its outputs that decide the run's acceptance
    (:attr:`~pipeline.contracts.TableContract.decides_acceptance`)"""


def provenance_of(
    plan: Plan,
    registry: Registry,
    files: Mapping[str, Path | pa.Table],
    started: dt.datetime,
    known_sha256: Mapping[str, str],
) -> Provenance:
    """Where a run's results come from: its pipeline, software, plugins, inputs (each file
    hashed unless ``known_sha256`` holds its SHA-256), stages and tool-model files."""
    return Provenance(
        pipeline=plan.spec.name,
        pipeline_version=plan.spec.version,
        pipeline_file=plan.file,
        pipeline_sha256=plan.digest,
        gyropipe=__version__,
        plugins={n: p.version for n, p in sorted(registry.plugins.items()) if not p.error},
        inputs={n: input_entry(source, known_sha256.get(n)) for n, source in files.items()},
        started=started,
        stages=tuple(
            StageSetup(
                st.id, st.uses, registry.plugin_label(st.plugin), st.params.model_dump(mode="json")
            )
            for st in plan.stages
        ),
        tool_models=registry.tool_model_files(),
    )


def run_manifest(
    provenance: Provenance,
    well: WellMetadata,
    records: list[StageRecord],
    outputs: list[tuple[Path, Path]],
    wall: float,
    differ: Mapping[str, Mapping[str, Any]] | None = None,
) -> dict[str, Any]:
    """``run.json``; ``outputs`` are (file written, its published path) pairs; with the gates
    of every acceptance-gates table the run produced (``acceptance``: overall ``pass`` unless
    a gate failed; a failed gate makes the run's ``status`` ``rejected``: it ran, its outputs
    are the evidence, the survey is not accepted). ``differ``: the fields the headers of the
    run's input files state differently (:func:`~pipeline.well.agreed`), each input's value,
    as ``well_differs`` (the run's ``well`` states none of them; survey dates their range)."""
    manifest: dict[str, Any] = {
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
        "inputs": {n: asdict(f) for n, f in provenance.inputs.items()},
        "parameter_inputs": [asdict(f) for f in provenance.read],
        "well": well.model_dump(mode="json", exclude_none=True),
        **({"well_differs": {k: dict(v) for k, v in differ.items()}} if differ else {}),
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
        "outputs": [
            {"file": final.name, **file_entry(written), "path": str(final)}
            for written, final in outputs
        ],
    }
    gates = [gate for r in records for gate in r.acceptance]
    if gates:
        failed = any(g["status"] == "fail" for g in gates)
        manifest["acceptance"] = {"status": "fail" if failed else "pass", "gates": gates}
        if failed:
            manifest["status"] = REJECTED
    return manifest


def acceptance(st: PlannedStage, tables: Mapping[str, pa.Table]) -> list[dict[str, Any]]:
    """The gates of a stage's outputs whose contract decides the run's acceptance
    (:attr:`~pipeline.contracts.TableContract.decides_acceptance`), as ``run.json`` records
    them: the contract's columns, a number that is not finite (a gate not evaluated) as null."""
    rows = []
    for port, table in tables.items():
        contract = st.definition.outputs[port]
        if contract.decides_acceptance:
            names = [c.name for c in contract.compiled().columns]
            for row in table.select(names).to_pylist():
                finite = {
                    k: None if isinstance(v, float) and not math.isfinite(v) else v
                    for k, v in row.items()
                }
                rows.append({"stage": st.id, "port": port, **finite})
    return rows


def file_entry(path: Path, sha256: str | None = None) -> dict[str, Any]:
    """A file's path, SHA-256 (hashed unless ``sha256`` is given) and size in bytes."""
    with file_errors("read", path):  # e.g. an input deleted since the run began
        digest = sha256 or sha256_file(path)
        return {"path": str(path), "sha256": digest, "bytes": path.stat().st_size}


def input_entry(source: Path | pa.Table, sha256: str | None) -> InputFile:
    """A file's path, hash (``sha256`` where known) and size; a table: its IPC stream's."""
    if isinstance(source, Path):
        return InputFile(**file_entry(source, sha256))
    sink = pa.BufferOutputStream()
    with pa.ipc.new_stream(sink, source.schema) as writer:
        writer.write_table(source)
    data = sink.getvalue()
    return InputFile("<table>", hashlib.sha256(data).hexdigest(), data.size)

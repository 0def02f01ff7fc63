"""What a well's result depends on, and why a well must be run again.

A :class:`Fingerprint` holds the SHA-256 of every input file, the hash of the pipeline's
structure (its spec without stage parameters), the resolved parameters of every stage, the
gyropipe version and the versions of third-party plugins, the well's header overrides, and
the SHA-256 of every file the run read through a parameter (``run.json``'s
``parameter_inputs``: offset wells, tool-model files, reader profiles). Which files those
are is known once the run has read them: a well's last run records them
(:meth:`Fingerprint.completed`) and the next batch compares the same files again
(:meth:`Fingerprint.reading`) — the set changes only with the pipeline, its inputs or
params, or one of those files, each of which is a reason already — and with the working
directory where a parameter names a file by a relative path (the same parameters then name
another file: the fingerprint keeps the directory, :attr:`Fingerprint.cwd`). Two runs with
equal fingerprints produce the same outputs; :func:`changes` says in words what differs
("input changed: stations", "plugin acme 1.2→1.3", "offset file offsets/w3.csv changed").

The batch process reads no file: a hash it does not know from the file's stat
(:mod:`pipeline.batch.filestate`) is :data:`PENDING` until a worker has hashed the file
(:func:`hashed`); a pending hash is no reason of its own (:func:`changes` leaves it out).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pipeline.graph import Plan
from pipeline.hashing import sha256_file
from pipeline.registry import Registry
from pipeline.version import __version__
from pipeline.well import WellMetadata

from .jobs import WellJob

UNREADABLE = "unreadable"
PENDING = "pending"
"""the hash of a file the batch process has not had hashed yet"""


@dataclass(frozen=True)
class Fingerprint:
    """Everything a well run's outputs depend on (module docstring)."""

    inputs: Mapping[str, str]
    """pipeline input name → SHA-256 of the file"""
    pipeline: str
    """SHA-256 of the pipeline spec without stage parameters"""
    params: Mapping[str, Mapping[str, Any]]
    """stage id → validated parameters (JSON values)"""
    gyropipe: str
    plugins: Mapping[str, str]
    """third-party plugin name → version (built-ins go with the gyropipe version)"""
    well: Mapping[str, Any]
    """header fields the batch overrides (JSON values)"""
    files: Mapping[str, Mapping[str, str]] = field(default_factory=dict)
    """absolute path → ``{"sha256", "what"}`` of every file the run read through a
    parameter (:mod:`pipeline.inputfiles`)"""
    cwd: str = ""
    """the working directory a parameter's relative path is read from (empty: not
    recorded, an earlier version's fingerprint)"""

    def reading(
        self, files: Mapping[str, Mapping[str, str]], digests: Mapping[str, str]
    ) -> Fingerprint:
        """This fingerprint with the files ``files`` names (a previous run's), their hashes
        now from ``digests`` (path → SHA-256, :data:`UNREADABLE`; :data:`PENDING` where
        missing)."""
        now = {
            path: {"sha256": digests.get(path, PENDING), "what": entry["what"]}
            for path, entry in files.items()
        }
        return replace(self, files=now)

    def completed(self, manifest: Mapping[str, Any]) -> Fingerprint:
        """This fingerprint with the input hashes and the files a run's ``run.json`` says it
        read (the run's own hashes replace pending or earlier ones)."""
        hashes = {name: entry["sha256"] for name, entry in manifest.get("inputs", {}).items()}
        files: dict[str, dict[str, str]] = {}
        for entry in manifest.get("parameter_inputs", []):
            files.setdefault(entry["path"], {"sha256": entry["sha256"], "what": entry["what"]})
        return replace(self.with_inputs(hashes), files=files)

    def with_inputs(self, hashes: Mapping[str, str]) -> Fingerprint:
        """This fingerprint with the input hashes ``hashes`` gives (name → SHA-256)."""
        inputs = {name: hashes.get(name, digest) for name, digest in self.inputs.items()}
        return replace(self, inputs=inputs)

    def pending(self) -> tuple[list[str], list[str]]:
        """The inputs (by name) and files (by path) whose hash is :data:`PENDING`."""
        inputs = [name for name, digest in self.inputs.items() if digest == PENDING]
        files = [path for path, entry in self.files.items() if entry["sha256"] == PENDING]
        return inputs, files

    def assuming(self, other: Fingerprint) -> Fingerprint:
        """This fingerprint with each pending hash taken from ``other`` (where it has one)."""
        inputs = {n: other.inputs.get(n, d) if d == PENDING else d for n, d in self.inputs.items()}
        files = {
            p: {**e, "sha256": other.files[p]["sha256"]}
            if e["sha256"] == PENDING and p in other.files
            else e
            for p, e in self.files.items()
        }
        return replace(self, inputs=inputs, files=files)

    def to_json(self) -> str:
        """The fields as one JSON object (their values are JSON values already: no
        :func:`dataclasses.asdict` deep copy, 1 ms a call for a report pipeline's params)."""
        return json.dumps(vars(self), sort_keys=True, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> Fingerprint:
        return cls(**json.loads(text))


@dataclass(frozen=True)
class PlanIdentity:
    """The parts of a fingerprint shared by every well of a batch."""

    pipeline: str
    params: Mapping[str, Mapping[str, Any]]
    gyropipe: str
    plugins: Mapping[str, str]
    cwd: str

    @classmethod
    def of(cls, plan: Plan, registry: Registry) -> PlanIdentity:
        spec = plan.spec.model_dump(mode="json", by_alias=True)
        for stage in spec["stages"]:
            stage.pop("with", None)
        spec["defaults"].pop("with", None)
        canonical = json.dumps(spec, sort_keys=True, separators=(",", ":"))
        return cls(
            pipeline=hashlib.sha256(canonical.encode()).hexdigest(),
            params={st.id: st.params.model_dump(mode="json") for st in plan.stages},
            gyropipe=__version__,
            plugins={
                name: info.version
                for name, info in sorted(registry.plugins.items())
                if not info.builtin and not info.error
            },
            cwd=os.getcwd(),
        )

    def fingerprint(self, job: WellJob, inputs: Mapping[str, str]) -> Fingerprint:
        """The fingerprint of ``job`` with the hashes ``inputs`` (input name → SHA-256,
        :data:`PENDING` or :data:`UNREADABLE`)."""
        return Fingerprint(
            inputs=dict(sorted(inputs.items())),
            pipeline=self.pipeline,
            params=self.params,
            gyropipe=self.gyropipe,
            plugins=self.plugins,
            well=well_overrides(job.well),
            cwd=self.cwd,
        )


def hashed(path: str) -> str:
    """The SHA-256 of the file ``path``, :data:`UNREADABLE` if it cannot be read."""
    try:
        return sha256_file(Path(path))
    except OSError:
        return UNREADABLE


def completed_json(fingerprint: object, manifest: Mapping[str, Any]) -> object:
    """A stored fingerprint (JSON text) completed by a run's ``run.json``
    (:meth:`Fingerprint.completed`); as it was where either does not parse (the next batch
    then re-runs the well, as for any damaged row)."""
    if not isinstance(fingerprint, str):
        return fingerprint
    try:
        return Fingerprint.from_json(fingerprint).completed(manifest).to_json()
    except (ValueError, TypeError, KeyError, AttributeError):
        return fingerprint


def well_overrides(well: WellMetadata) -> dict[str, Any]:
    """The header fields set on ``well``, as JSON values."""
    return well.model_dump(mode="json", exclude_unset=True)


def changes(old: Fingerprint, new: Fingerprint) -> list[str]:
    """Why a run with fingerprint ``new`` differs from one with ``old``; empty if equal (a
    :data:`PENDING` hash on either side is no reason)."""
    reasons: list[str] = []
    for name in sorted(set(old.inputs) | set(new.inputs)):
        if name not in old.inputs:
            reasons.append(f"new input {name}")
        elif name not in new.inputs:
            reasons.append(f"input {name} removed")
        elif PENDING not in (old.inputs[name], new.inputs[name]) and (
            old.inputs[name] != new.inputs[name]
        ):
            reasons.append(f"input changed: {name}")
    if old.pipeline != new.pipeline:
        reasons.append("pipeline changed")
    reasons += _diff("params changed", _flatten(old.params), _flatten(new.params))
    if old.cwd and new.cwd and old.cwd != new.cwd:
        named = _relative_files(_flatten(new.params), (old.cwd, new.cwd))
        if named:
            reasons.append(
                f"working directory changed: {old.cwd}→{new.cwd} ({', '.join(named)} "
                "name files relative to it)"
            )
    if old.gyropipe != new.gyropipe:
        reasons.append(f"gyropipe {old.gyropipe}→{new.gyropipe}")
    for name in sorted(set(old.plugins) | set(new.plugins)):
        before, after = old.plugins.get(name), new.plugins.get(name)
        if before != after:
            reasons.append(
                f"plugin {name} added ({after})"
                if before is None
                else f"plugin {name} removed (was {before})"
                if after is None
                else f"plugin {name} {before}→{after}"
            )
    reasons += _diff("well header changed", dict(old.well), dict(new.well))
    for path in sorted(old.files):
        read, now = old.files[path], new.files.get(path)
        if (
            now is not None
            and PENDING not in (now["sha256"], read["sha256"])
            and (now["sha256"] != read["sha256"])
        ):
            gone = " (now unreadable)" if now["sha256"] == UNREADABLE else ""
            reasons.append(f"{read['what']} {_shown(path)} changed{gone}")
    return reasons


def _shown(path: str) -> str:
    """``path`` relative to the current directory when it lies below it."""
    relative = os.path.relpath(path)
    return path if relative.startswith("..") else relative


def _relative_files(params: Mapping[str, Any], directories: tuple[str, ...]) -> list[str]:
    """The (dotted) parameters, nested values included, whose value is a relative path of a
    regular file in one of ``directories`` — a file that the same parameters name another
    of when the working directory changes (a profile, a tool-model file given by path)."""
    found = []
    for name, value in params.items():
        if isinstance(value, Mapping):
            found += _relative_files({f"{name}.{k}": v for k, v in value.items()}, directories)
        elif isinstance(value, list | tuple):
            found += _relative_files({f"{name}.{i}": v for i, v in enumerate(value)}, directories)
        elif (
            isinstance(value, str)
            and value
            and not os.path.isabs(value)
            and any(os.path.isfile(os.path.join(d, value)) for d in directories)
        ):
            found.append(name)
    return found


def _flatten(params: Mapping[str, Mapping[str, Any]]) -> dict[str, Any]:
    return {f"{stage}.{key}": value for stage, p in params.items() for key, value in p.items()}


def _diff(what: str, old: dict[str, Any], new: dict[str, Any], shown: int = 3) -> list[str]:
    keys = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
    if not keys:
        return []
    parts = [f"{k} {_text(old.get(k))}→{_text(new.get(k))}" for k in keys[:shown]]
    more = f" (+{len(keys) - shown} more)" if len(keys) > shown else ""
    return [f"{what}: {', '.join(parts)}{more}"]


def _text(value: Any) -> str:
    return "unset" if value is None else json.dumps(value, sort_keys=True)

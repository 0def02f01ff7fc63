"""Where a run's results come from: its pipeline, software, input files and stages (what
``run.json`` records), known to every stage while the run goes on."""

from __future__ import annotations

import datetime as dt
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pipeline.hashing import FileKey, key_after


@dataclass(frozen=True)
class InputFile:
    """A pipeline input file as the run received it."""

    path: str
    sha256: str
    bytes: int


@dataclass(frozen=True)
class ParameterFile:
    """A file a stage read because a parameter named it, or a file it found through one (an
    offset well a manifest lists, a tool-model file a model extends): ``run.json``'s
    ``parameter_inputs`` (:mod:`pipeline.inputfiles`)."""

    path: str
    """absolute path"""
    sha256: str
    stage: str
    param: str
    """the parameter that named it or led to it (dotted: ``options.profile``)"""
    what: str
    """what it is, in words (``offset file``, ``tool-model file``, ``profile``)"""


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
    read: dict[ParameterFile, None] = field(default_factory=dict)
    """the files the stages so far read through parameters, in order (an ordered set, filled
    as the run goes on: :meth:`~pipeline.registry.StageContext.record_file`)"""
    seen: dict[str, FileKey | None] = field(default_factory=dict)
    """each file the run hashed, or was given the hash of (absolute path) → its stat key
    before (None: it had none); :meth:`changed` compares them with the files as they are"""
    tool_models: Mapping[str, Path] = field(default_factory=dict)
    """the tool-model files the run's plugins registered, by model name (what a stage's
    ``model:`` may name besides the shipped models; :meth:`Registry.tool_model_files`)"""

    def see(self, path: Path) -> None:
        """Note ``path``'s stat key, before the run hashes it (the first time only)."""
        self.seen.setdefault(str(path.absolute()), key_after(path))

    def changed(self) -> list[str]:
        """The files the run hashed that have changed since (their stat keys differ): their
        recorded SHA-256 may not be that of the bytes the run read."""
        return [path for path, key in self.seen.items() if key_after(path) != key]

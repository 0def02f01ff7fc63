"""Pipeline YAML → pydantic models, remembering where every node came from (see
:mod:`pipeline.yamlsource`), so every problem — a pydantic error, an unknown stage, a
cycle — can point at its YAML node."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from pipeline.errors import Location, Problem, SpecError
from pipeline.hashing import regular_bytes
from pipeline.well import WellMetadata
from pipeline.yamlsource import SourceMap, load_mapping, load_value, validation_problems

IDENT = r"^[A-Za-z_][A-Za-z0-9_-]*$"
DEFAULT_VERSION = "1"
"""The version of a pipeline that declares none (recorded in run.json, shown in reports)."""
PLACEHOLDER_NAME = "invalid"
"""Stands for an invalid pipeline name while the rest is checked (its problem reported)."""


class InputSpec(BaseModel):
    """A file the user supplies at run time (``--input NAME=FILE``)."""

    model_config = ConfigDict(extra="forbid")
    description: str = ""


class StageSpec(BaseModel):
    """One node of the DAG."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)
    id: str = Field(pattern=IDENT, description="unique stage id")
    uses: str = Field(description="registered stage name")
    description: str = ""
    inputs: dict[str, str] = Field(
        default_factory=dict,
        description="input port → upstream 'stage.port' (or 'stage' if it has one output)",
    )
    with_: dict[str, Any] = Field(
        default_factory=dict, alias="with", description="stage parameters"
    )
    persist: list[str] | bool = Field(
        default_factory=list, description="output ports to save (true: all)"
    )


class Defaults(BaseModel):
    """Pipeline-wide defaults."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)
    with_: dict[str, Any] = Field(
        default_factory=dict,
        alias="with",
        description="parameters given to every stage whose params model has that field",
    )
    persist_format: Literal["parquet", "csv"] = Field(
        "parquet", description="writer used for persisted outputs"
    )


class PipelineSpec(BaseModel):
    """A pipeline: a named, versioned DAG of stages."""

    model_config = ConfigDict(extra="forbid")
    name: str = Field(pattern=IDENT)
    version: str = Field(DEFAULT_VERSION, description="pipeline version (numbers are read as text)")
    description: str = ""
    inputs: dict[str, InputSpec] = Field(default_factory=dict)
    well: WellMetadata = Field(default_factory=WellMetadata, description="default well metadata")
    defaults: Defaults = Field(default_factory=Defaults)
    stages: list[StageSpec] = Field(min_length=1)

    @field_validator("version", mode="before")
    @classmethod
    def _version_text(cls, value: Any) -> Any:
        return (
            str(value) if isinstance(value, int | float) and not isinstance(value, bool) else value
        )

    def digest(self) -> str:
        """SHA-256 of the canonical JSON of the resolved spec (after overrides)."""
        canonical = json.dumps(
            self.model_dump(mode="json", by_alias=True), sort_keys=True, separators=(",", ":")
        )
        return hashlib.sha256(canonical.encode()).hexdigest()


@dataclass
class LoadedSpec:
    """A spec of valid shape, the source map of its YAML, and the problems found so far
    that did not prevent building it (reported with the planner's, all together).

    When parts of the YAML have the wrong shape, their problems are in ``problems`` and the
    spec is built from the rest, so the planner can still report every other problem: a
    stage of invalid shape is left out (``positions`` maps each stage of ``spec`` to its
    index in the YAML; ``dropped`` maps the index of each stage left out to its id), an invalid
    top-level field is left at its default (named in ``invalid``)."""

    spec: PipelineSpec
    source: SourceMap
    raw: dict[str, Any]
    problems: list[Problem]
    positions: tuple[int, ...] = ()
    dropped: Mapping[int, str] = field(default_factory=dict)
    invalid: frozenset[str] = frozenset()

    def position(self, i: int) -> int:
        """Index in the YAML's ``stages`` of stage ``i`` of the spec."""
        return self.positions[i] if self.positions else i


def load_spec(path: str | Path, overrides: list[str] | None = None) -> LoadedSpec:
    """Read a pipeline YAML, apply ``--set stage.param=value`` overrides, validate its shape.

    Raises :class:`SpecError` if the spec cannot be built at all. Stage names, params and
    wiring are checked against the plugin registry by :func:`pipeline.graph.build_plan`,
    which reports them together with the problems already found here.
    """
    path = Path(path)
    try:
        text = regular_bytes(path).decode("utf-8")  # a FIFO is refused, never waited on
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError([Problem(Location(str(path)), f"cannot read pipeline: {exc}")]) from exc
    return parse_spec(text, str(path), overrides)


def parse_spec(text: str, file: str, overrides: list[str] | None = None) -> LoadedSpec:
    """Parse pipeline YAML text (see :func:`load_spec`)."""
    raw, source, problems = load_mapping(text, file, "a pipeline must be a mapping (name, stages…)")
    problems += apply_overrides(raw, overrides or [], source)
    try:
        spec = PipelineSpec.model_validate(raw)
    except ValidationError as exc:
        reported = {p.location for p in problems}
        problems += [
            p
            for p in validation_problems(exc, (), source, PipelineSpec)
            if p.location not in reported
        ]
        return _salvaged(raw, source, problems, exc)
    return LoadedSpec(spec, source, raw, problems)


def _salvaged(
    raw: dict[str, Any], source: SourceMap, problems: list[Problem], exc: ValidationError
) -> LoadedSpec:
    """The spec without the parts ``exc`` found invalid (see :class:`LoadedSpec`); raises
    :class:`SpecError` when no stage is left to plan."""
    bad_fields: set[str] = set()
    bad_stages: set[int] = set()
    for err in exc.errors():
        loc = err["loc"]
        if len(loc) > 1 and loc[0] == "stages" and isinstance(loc[1], int):
            bad_stages.add(loc[1])
        elif loc:
            bad_fields.add(str(loc[0]))
    stages = raw.get("stages") if "stages" not in bad_fields else None
    kept = (
        [i for i in range(len(stages)) if i not in bad_stages] if isinstance(stages, list) else []
    )
    if not kept:
        raise SpecError(problems)
    patched = {k: v for k, v in raw.items() if k not in bad_fields and k != "stages"}
    patched["name"] = raw["name"] if "name" not in bad_fields else PLACEHOLDER_NAME
    assert isinstance(stages, list)
    patched["stages"] = [stages[i] for i in kept]
    try:
        spec = PipelineSpec.model_validate(patched)  # every part left has been validated
    except ValidationError:  # pragma: no cover - defensive: report what was found
        raise SpecError(problems) from None
    dropped = {
        i: stage["id"]
        for i, stage in enumerate(stages)
        if i in bad_stages and isinstance(stage, dict) and isinstance(stage.get("id"), str)
    }
    return LoadedSpec(spec, source, raw, problems, tuple(kept), dropped, frozenset(bad_fields))


def apply_overrides(raw: dict[str, Any], overrides: list[str], source: SourceMap) -> list[Problem]:
    """Apply ``stage.param[.sub]=value`` overrides in place (values parsed as YAML); later
    problems with an overridden value point at its ``--set``."""
    problems = []
    stages = raw.get("stages")
    # Only well-typed ids can be targets: a list or mapping as an id is reported by the
    # model's validation, located at its node.
    by_id = (
        {s["id"]: s for s in stages if isinstance(s, dict) and isinstance(s.get("id"), str)}
        if isinstance(stages, list)
        else {}
    )
    for item in overrides:
        where = Location(f"--set {item}")
        target, sep, value = item.partition("=")
        parts = target.strip().split(".")
        if not sep or len(parts) < 2 or not all(parts):
            problems.append(Problem(where, "expected STAGE.PARAM=VALUE"))
            continue
        stage = by_id.get(parts[0])
        if stage is None:
            problems.append(
                Problem(where, f"no stage with id {parts[0]!r} (ids: {', '.join(map(str, by_id))})")
            )
            continue
        try:
            parsed = load_value(value, where.file) if value.strip() else None
        except SpecError as exc:
            problems += [Problem(where, f"value: {p.message}") for p in exc.problems]
            continue
        index = stages.index(stage) if isinstance(stages, list) else 0
        source.values[("stages", index, "with", *parts[1:])] = where
        params = stage.setdefault("with", {})
        for part in parts[1:-1]:
            params = params.setdefault(part, {}) if isinstance(params, dict) else None
        if not isinstance(params, dict):
            problems.append(Problem(where, f"{'.'.join(parts[1:-1])} is not a mapping"))
            continue
        params[parts[-1]] = parsed
    return problems

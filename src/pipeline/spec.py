"""Pipeline YAML → pydantic models, remembering where every node came from.

YAML is composed with ``yaml.SafeLoader`` (no tags that construct Python objects), then
converted to plain data while recording each node's line and column, so every later
problem — a pydantic error, an unknown stage, a cycle — can point at its YAML node.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from pipeline.errors import Location, Problem, SpecError
from pipeline.well import WellMetadata

PathKey = tuple[str | int, ...]
IDENT = r"^[A-Za-z_][A-Za-z0-9_-]*$"


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
    version: str = Field(description="pipeline version (numbers are read as text)")
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
class SourceMap:
    """Where each node of the loaded data came from (YAML line/column, or a ``--set``)."""

    file: str
    values: dict[PathKey, Location] = field(default_factory=dict)
    keys: dict[PathKey, Location] = field(default_factory=dict)

    def locate(self, path: PathKey, *, key: bool = False) -> Location:
        """Location of the node at ``path`` (of its key if ``key``), else of its nearest
        ancestor that has one."""
        if key and path in self.keys:
            return self.keys[path]
        for end in range(len(path), -1, -1):
            if path[:end] in self.values:
                return self.values[path[:end]]
        return Location(self.file)


@dataclass
class LoadedSpec:
    """A spec of valid shape, the source map of its YAML, and the problems found so far
    that did not prevent building it (reported with the planner's, all together)."""

    spec: PipelineSpec
    source: SourceMap
    raw: dict[str, Any]
    problems: list[Problem]


def load_spec(path: str | Path, overrides: list[str] | None = None) -> LoadedSpec:
    """Read a pipeline YAML, apply ``--set stage.param=value`` overrides, validate its shape.

    Raises :class:`SpecError` if the spec cannot be built at all. Stage names, params and
    wiring are checked against the plugin registry by :func:`pipeline.graph.build_plan`,
    which reports them together with the problems already found here.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError([Problem(Location(str(path)), f"cannot read pipeline: {exc}")]) from exc
    return parse_spec(text, str(path), overrides)


def parse_spec(text: str, file: str, overrides: list[str] | None = None) -> LoadedSpec:
    """Parse pipeline YAML text (see :func:`load_spec`)."""
    source = SourceMap(file)
    problems: list[Problem] = []
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        loc = Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)
        raise SpecError([Problem(loc, f"malformed YAML: {exc.problem or exc}")]) from exc
    except yaml.YAMLError as exc:
        raise SpecError([Problem(Location(file), f"malformed YAML: {exc}")]) from exc
    if node is None:
        raise SpecError([Problem(Location(file, 1, 1), "empty pipeline file")])
    try:
        raw = _to_data(node, (), source, problems)
    except yaml.MarkedYAMLError as exc:  # e.g. a tag the safe loader refuses
        mark = exc.problem_mark or exc.context_mark
        loc = Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)
        raise SpecError([Problem(loc, f"invalid YAML value: {exc.problem or exc}")]) from exc
    if not isinstance(raw, dict):
        loc = Location(file, node.start_mark.line + 1, node.start_mark.column + 1)
        raise SpecError([Problem(loc, "a pipeline must be a mapping (name, version, stages…)")])
    problems += apply_overrides(raw, overrides or [], source)
    try:
        spec = PipelineSpec.model_validate(raw)
    except ValidationError as exc:
        reported = {p.location for p in problems}
        problems += [p for p in validation_problems(exc, (), source) if p.location not in reported]
        raise SpecError(problems) from None
    return LoadedSpec(spec, source, raw, problems)


def validation_problems(exc: ValidationError, prefix: PathKey, source: SourceMap) -> list[Problem]:
    """One problem per pydantic error, located at the YAML node it concerns."""
    out = []
    for err in exc.errors():
        loc = tuple(p for p in err["loc"] if isinstance(p, str | int))
        path = prefix + loc
        where = ".".join(str(p) for p in loc) or "value"
        if err["type"] == "extra_forbidden":
            message = f"unknown field {where!r}"
            out.append(Problem(source.locate(path, key=True), message))
            continue
        if err["type"] == "missing":
            message = f"missing required field {where!r}"
        else:
            got = err.get("input")
            shown = "" if isinstance(got, dict | list) else f" (got {got!r})"
            message = f"{where}: {err['msg']}{shown}"
        out.append(Problem(source.locate(path), message))
    return out


def apply_overrides(raw: dict[str, Any], overrides: list[str], source: SourceMap) -> list[Problem]:
    """Apply ``stage.param[.sub]=value`` overrides in place (values parsed as YAML); later
    problems with an overridden value point at its ``--set``."""
    problems = []
    stages = raw.get("stages")
    by_id = (
        {s.get("id"): s for s in stages if isinstance(s, dict)} if isinstance(stages, list) else {}
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
            parsed = yaml.safe_load(value) if value.strip() else None
        except yaml.YAMLError as exc:
            problems.append(Problem(where, f"value is not valid YAML: {exc}"))
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


def _to_data(node: yaml.Node, path: PathKey, source: SourceMap, problems: list[Problem]) -> Any:
    source.values[path] = Location(
        source.file, node.start_mark.line + 1, node.start_mark.column + 1
    )
    standard = _STANDARD_TAGS.get(type(node))
    if standard is not None and node.tag != standard:
        problems.append(
            Problem(source.locate(path), f"YAML tag {node.tag!r} is not allowed in a pipeline")
        )
        return None
    if isinstance(node, yaml.MappingNode):
        out: dict[str, Any] = {}
        for key_node, value_node in node.value:
            key = _scalar(key_node)
            loc = Location(
                source.file, key_node.start_mark.line + 1, key_node.start_mark.column + 1
            )
            if not isinstance(key, str | int | float | bool) or key is None:
                problems.append(Problem(loc, "mapping keys must be plain scalars"))
                continue
            key = str(key)
            if key in out:
                problems.append(Problem(loc, f"duplicate key {key!r}"))
                continue
            source.keys[(*path, key)] = loc
            out[key] = _to_data(value_node, (*path, key), source, problems)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_to_data(n, (*path, i), source, problems) for i, n in enumerate(node.value)]
    return _scalar(node)


_CONSTRUCTOR = yaml.SafeLoader("")
_STANDARD_TAGS: dict[type, str] = {
    yaml.MappingNode: "tag:yaml.org,2002:map",
    yaml.SequenceNode: "tag:yaml.org,2002:seq",
}


def _scalar(node: yaml.Node) -> Any:
    if isinstance(node, yaml.ScalarNode):
        return _CONSTRUCTOR.construct_object(node, deep=True)
    return node  # a collection used as a key: rejected by the caller

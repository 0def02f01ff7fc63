"""Safe YAML loading that remembers the line and column of every node.

YAML is composed with ``yaml.SafeLoader`` (no tag constructs a Python object; non-standard
tags on collections are refused), then converted to plain data while recording where each
node came from, so pydantic errors and later checks can point at ``file:line:column``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from pipeline.errors import Location, Problem, SpecError

PathKey = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)


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


def load_mapping(
    text: str, file: str, not_mapping: str
) -> tuple[dict[str, Any], SourceMap, list[Problem]]:
    """Parse YAML text that must hold a mapping. Returns the data, its source map and the
    non-fatal problems found (duplicate keys, refused tags); raises :class:`SpecError` if
    the text cannot be parsed or is not a mapping (``not_mapping`` is that message)."""
    source = SourceMap(file)
    problems: list[Problem] = []
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        if node is None:
            raise SpecError([Problem(Location(file, 1, 1), "empty file")])
        raw = _to_data(node, (), source, problems)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        loc = Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)
        raise SpecError([Problem(loc, f"malformed YAML: {exc.problem or exc}")]) from exc
    except yaml.YAMLError as exc:
        raise SpecError([Problem(Location(file), f"malformed YAML: {exc}")]) from exc
    if not isinstance(raw, dict):
        loc = Location(file, node.start_mark.line + 1, node.start_mark.column + 1)
        raise SpecError([Problem(loc, not_mapping)])
    return raw, source, problems


def validate_located(
    model: type[M], raw: dict[str, Any], source: SourceMap, problems: list[Problem]
) -> M:
    """Validate ``raw`` as ``model``; on failure raise :class:`SpecError` with ``problems``
    plus one located problem per pydantic error (one per YAML node)."""
    try:
        return model.model_validate(raw)
    except ValidationError as exc:
        reported = {p.location for p in problems}
        problems += [p for p in validation_problems(exc, (), source) if p.location not in reported]
        raise SpecError(problems) from None


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

"""Safe YAML loading that remembers the line and column of every node.

YAML is composed with ``yaml.SafeLoader`` (no tag constructs a Python object; non-standard
tags on collections are refused), then converted to plain data while recording where each
node came from, so pydantic errors and later checks can point at ``file:line:column``.

Aliases are followed (an alias is a copy of its anchor's node), but a document whose aliases
expand it beyond :data:`MAX_NODES` nodes (a "billion laughs" document) or
:data:`MAX_SCALAR_CHARS` characters of scalar text (a large ``!!binary`` anchor aliased many
times), an alias inside the node it refers to, and nesting deeper than :data:`MAX_DEPTH` are
refused, located at the alias (or node), before anything is expanded. A scalar no safe
constructor builds (a tag such as ``!!python/name:…`` or ``!custom``, a merge key ``<<``,
``!!int abc``, ``!!timestamp abc``, a date-like ``2026-13-45``) is a located problem, not an
exception.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass, field
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from pipeline.errors import Location, Problem, SpecError, did_you_mean
from pipeline.yaml_errors import explain

PathKey = tuple[str | int, ...]
M = TypeVar("M", bound=BaseModel)

MAX_NODES = 100_000
"""Most nodes a loaded document may hold once its aliases are expanded."""
MAX_SCALAR_CHARS = 10_000_000
"""Most characters of scalar text a loaded document may hold once its aliases are expanded
(a pipeline file is a few kB; its scalars are built once per alias)."""
MAX_DEPTH = 100
"""Deepest nesting of collections a loaded document may have (aliases expanded)."""


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
    node = _compose(text, file)
    if node is None:
        raise SpecError([Problem(Location(file, 1, 1), "empty file")])
    raw = _to_data(node, (), source, problems)
    if not isinstance(raw, dict):
        raise SpecError([Problem(_location(file, node.start_mark), not_mapping)])
    return raw, source, problems


def load_value(text: str, where: str) -> Any:
    """Parse one YAML value (a ``--set`` value, say) as a document is parsed, with its
    limits; a problem is a :class:`SpecError` located at ``where``."""
    problems: list[Problem] = []
    try:
        node = _compose(text, where)
        value = None if node is None else _to_data(node, (), SourceMap(where), problems)
    except SpecError as exc:
        problems = exc.problems
    if problems:
        raise SpecError([Problem(Location(where), _within(p, text)) for p in problems])
    return value


def _within(problem: Problem, text: str) -> str:
    """A value's parse error with its place in the value ("column 7: …")."""
    at = problem.location
    if not at.column or not problem.message.startswith("malformed YAML"):
        return problem.message
    if "\n" not in text.strip("\n"):  # one line: columns only
        return f"column {at.column}: {problem.message.replace('at line 1, column', 'at column')}"
    return f"line {at.line}, column {at.column}: {problem.message}"


def _compose(text: str, file: str) -> yaml.Node | None:
    """The YAML node graph of ``text`` (safe tags only), checked against the limits
    (:func:`_check_size`); None for an empty document."""
    try:
        node = yaml.compose(text, Loader=_Loader)
    except _TooDeep as exc:
        raise SpecError([Problem(_location(file, exc.mark), exc.message)]) from None
    except yaml.MarkedYAMLError as exc:
        line, column, message = explain(exc, text)
        raise SpecError([Problem(Location(file, line, column), message)]) from exc
    except yaml.reader.ReaderError as exc:  # a character YAML does not allow: no mark
        at = min(exc.position, len(text))
        line, column = text.count("\n", 0, at) + 1, at - text.rfind("\n", 0, at)
        char = exc.character
        shown = f"U+{char:04X}" if isinstance(char, int) else repr(char)
        message = f"malformed YAML: character {shown} is not allowed ({exc.reason})"
        raise SpecError([Problem(Location(file, line, column), message)]) from exc
    except yaml.YAMLError as exc:
        raise SpecError([Problem(Location(file), f"malformed YAML: {exc}")]) from exc
    if node is not None:
        _check_size(node, file)
    return node


def _location(file: str, mark: yaml.Mark | None) -> Location:
    return Location(file, mark.line + 1, mark.column + 1) if mark else Location(file)


def validate_located(
    model: type[M], raw: dict[str, Any], source: SourceMap, problems: list[Problem]
) -> M:
    """Validate ``raw`` as ``model``; on failure raise :class:`SpecError` with ``problems``
    plus one located problem per pydantic error (one per YAML node)."""
    try:
        return model.model_validate(raw)
    except ValidationError as exc:
        reported = {p.location for p in problems}
        problems += [
            p for p in validation_problems(exc, (), source, model) if p.location not in reported
        ]
        raise SpecError(problems) from None


def validation_problems(
    exc: ValidationError,
    prefix: PathKey,
    source: SourceMap,
    model: type[BaseModel] | None = None,
) -> list[Problem]:
    """One problem per pydantic error, located at the YAML node it concerns; an unknown
    field of ``model`` (or of a model nested in it) gets a did-you-mean."""
    out = []
    for err in exc.errors():
        loc = tuple(p for p in err["loc"] if isinstance(p, str | int))
        loc = _data_path(loc, prefix, source, missing=err["type"] == "missing")
        path = prefix + loc
        where = ".".join(str(p) for p in loc) or "value"
        if err["type"] == "extra_forbidden":
            known = _field_names(model, loc[:-1]) if model is not None else ()
            known = tuple(k for k in known if k != loc[-1])  # another member of a union's
            message = f"unknown field {where!r}{did_you_mean(str(loc[-1]), known)}"
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


def _data_path(loc: PathKey, prefix: PathKey, source: SourceMap, *, missing: bool) -> PathKey:
    """``loc`` without the labels pydantic puts between the keys of the data (a union
    member's tag, ``function-after[…]``): every part must be a node of the document, but
    the last one of a ``missing`` field."""
    kept: list[str | int] = []
    for i, part in enumerate(loc):
        path = (*prefix, *kept, part)
        if (missing and i == len(loc) - 1) or path in source.values or path in source.keys:
            kept.append(part)
    return tuple(kept) if kept else loc  # no node of the document: as pydantic says


def _field_names(model: type[BaseModel], loc: PathKey) -> tuple[str, ...]:
    """The field names of the model at ``loc`` inside ``model`` (list items and unions of
    models followed), or none where ``loc`` leaves the models."""
    current: Any = model
    for part in loc:
        if isinstance(part, int):
            continue
        fields = getattr(current, "model_fields", {})
        if part not in fields:
            return ()
        current = _model_in(fields[part].annotation)
        if current is None:
            return ()
    return tuple(getattr(current, "model_fields", {}))


def _model_in(annotation: Any) -> Any:
    """The pydantic model an annotation holds (directly, in a list/dict/union), or None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None


def _to_data(node: yaml.Node, path: PathKey, source: SourceMap, problems: list[Problem]) -> Any:
    if isinstance(node, _Alias):
        node = node.value  # located at its anchor, where its content is written
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
            found = len(problems)
            key = _scalar(key_node, source.file, problems)
            loc = Location(
                source.file, key_node.start_mark.line + 1, key_node.start_mark.column + 1
            )
            if len(problems) > found:  # a key that cannot be read (a merge key '<<')
                continue
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
    return _scalar(node, source.file, problems)


_CONSTRUCTOR = yaml.SafeLoader("")
_TIMESTAMP = "tag:yaml.org,2002:timestamp"
"""PyYAML builds this tag from a regular expression match it does not check (None for
``!!timestamp abc``: an AttributeError), so the match is checked first."""
_STANDARD_TAGS: dict[type, str] = {
    yaml.MappingNode: "tag:yaml.org,2002:map",
    yaml.SequenceNode: "tag:yaml.org,2002:seq",
}


def _scalar(node: yaml.Node, file: str, problems: list[Problem]) -> Any:
    """The value of a scalar node (a collection node as it is: a key the caller rejects).
    A scalar no safe constructor builds (an unknown or unsafe tag, a merge key ``<<``, a
    tagged value of the wrong form such as ``!!int abc``) is a located problem and None."""
    if isinstance(node, _Alias):
        node = node.value
    if not isinstance(node, yaml.ScalarNode):
        return node
    try:
        if node.tag == _TIMESTAMP and not _CONSTRUCTOR.timestamp_regexp.match(node.value):
            raise ValueError("expected a date YYYY-MM-DD or a date and time (ISO 8601)")
        return _CONSTRUCTOR.construct_object(node, deep=True)
    except (yaml.constructor.ConstructorError, ValueError, LookupError, OverflowError) as exc:
        # LookupError: !!bool maybe (PyYAML looks the word up in its table of booleans)
        problems.append(Problem(_location(file, node.start_mark), _unbuilt(node, exc)))
        return None
    finally:  # the shared constructor must keep no node (nor a half-built one) between calls
        _CONSTRUCTOR.constructed_objects.pop(node, None)
        _CONSTRUCTOR.recursive_objects.pop(node, None)
        _CONSTRUCTOR.deep_construct = False


def _unbuilt(node: yaml.ScalarNode, exc: Exception) -> str:
    """Why a scalar node has no value, in words."""
    if node.tag == "tag:yaml.org,2002:merge":
        return "YAML merge keys ('<<') are not supported: write the keys out"
    if isinstance(exc, yaml.constructor.ConstructorError):
        return f"YAML tag {node.tag!r} is not allowed in a pipeline"
    short = node.tag.rsplit(":", 1)[-1]
    return f"{node.value!r} is not a valid YAML {short}: {exc}"


# ------------------------------------------------------------------ aliases and limits


class _Alias(yaml.Node):
    """An alias in the node graph: ``value`` is the node it refers to, the marks are where
    the alias itself is written (PyYAML gives the anchor's node, and forgets the alias)."""

    id = "alias"

    def __init__(self, target: yaml.Node, start_mark: Any, end_mark: Any) -> None:
        super().__init__(target.tag, target, start_mark, end_mark)


class _TooDeep(Exception):
    def __init__(self, mark: Any, message: str) -> None:
        self.mark = mark
        self.message = message


class _Loader(yaml.SafeLoader):
    """The safe loader, keeping aliases as :class:`_Alias` nodes and refusing nesting
    deeper than :data:`MAX_DEPTH` before PyYAML's recursive composer overflows."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node | None:
        event: yaml.Event = self.peek_event()  # type: ignore[no-untyped-call]
        if isinstance(event, yaml.AliasEvent):
            target = super().compose_node(parent, index)
            assert target is not None  # an alias refers to a composed node
            return _Alias(target, event.start_mark, event.end_mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _TooDeep(event.start_mark, _too_deep())
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _too_deep() -> str:
    return f"collections nested deeper than {MAX_DEPTH} levels: refused"


def _check_size(root: yaml.Node, file: str) -> None:
    """Raise :class:`SpecError` if the document, its aliases expanded, holds more than
    :data:`MAX_NODES` nodes or :data:`MAX_SCALAR_CHARS` characters of scalars, or nests
    deeper than :data:`MAX_DEPTH`, or if an alias lies inside the node it refers to. Counts
    without expanding: each node's expanded size and height is computed once."""
    measured: dict[int, tuple[int, int, int]] = {}  # id(node) → (nodes, characters, height)
    open_nodes: set[int] = set()
    largest: list[tuple[int, int, _Alias]] = []  # the alias that expands the most

    def measure(node: yaml.Node, depth: int) -> tuple[int, int, int]:
        target = node.value if isinstance(node, _Alias) else node
        key = id(target)
        if key in open_nodes:
            raise SpecError(
                [Problem(_location(file, node.start_mark), "alias inside the node it refers to")]
            )
        if key not in measured:
            if depth > MAX_DEPTH:
                raise SpecError([Problem(_location(file, node.start_mark), _too_deep())])
            open_nodes.add(key)
            size, chars, height = 1, len(target.value) if _is_scalar(target) else 0, 1
            for child in _children(target):
                child_size, child_chars, child_height = measure(child, depth + 1)
                size += child_size
                chars += child_chars
                height = max(height, child_height + 1)
            open_nodes.discard(key)
            measured[key] = (size, chars, height)
        size, chars, height = measured[key]
        if depth + height - 1 > MAX_DEPTH:
            raise SpecError([Problem(_location(file, node.start_mark), _too_deep())])
        if isinstance(node, _Alias) and (not largest or (size, chars) > largest[0][:2]):
            largest[:] = [(size, chars, node)]
        return size, chars, height

    total, chars, _ = measure(root, 1)
    if total <= MAX_NODES and chars <= MAX_SCALAR_CHARS:
        return
    if total > MAX_NODES:
        what, limit, alone = f"{total:,} nodes", MAX_NODES, 0
    else:
        what, limit, alone = f"{chars:,} characters of scalars (keys included)", MAX_SCALAR_CHARS, 1
    if largest:
        alias = largest[0][2]
        where = _location(file, alias.start_mark)
        unit = "nodes" if alone == 0 else "characters"
        message = (
            f"aliases expand the document to {what}, more than {limit:,}: "
            f"refused (this alias alone expands to {largest[0][alone]:,} {unit})"
        )
    else:
        where = _location(file, root.start_mark)
        message = f"the document holds {what}, more than {limit:,}: refused"
    raise SpecError([Problem(where, message)])


def _is_scalar(node: yaml.Node) -> bool:
    return isinstance(node, yaml.ScalarNode) and isinstance(node.value, str)


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [child for pair in node.value for child in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []

"""The DAG of a pipeline: stages resolved against the registry, params validated, ports
wired, contracts matched and an execution order found — or every problem, located."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel, ValidationError

from pipeline.contracts import TableContract
from pipeline.errors import Location, Problem, SpecError, did_you_mean
from pipeline.registry import PIPELINE_INPUT, Registry, StageDef
from pipeline.spec import LoadedSpec, PipelineSpec, StageSpec
from pipeline.yamlsource import PathKey, SourceMap, validation_problems


@dataclass(frozen=True)
class PlannedStage:
    """A stage ready to run."""

    id: str
    uses: str
    definition: StageDef
    plugin: str
    params: BaseModel
    wiring: dict[str, tuple[str, str]]
    """input port → (upstream stage id, output port)"""
    persist: tuple[str, ...]
    passes: Mapping[str, int] = field(default_factory=dict)
    """the passes over each streamed output: the stages wired to it (but where it is one of
    their ``unread_inputs`` — validity's samples, read only with magnetometers) and
    ``persist``; the runner keeps a pass read by several (:func:`~pipeline.ports.kept`)"""
    releases: tuple[tuple[str, str], ...] = ()
    """the streamed outputs (stage id, port), not persisted, whose last stage wired to them
    this is: the runner lets a pass kept for them go once it has run, even where it made no
    pass (an input it may leave unread)"""


@dataclass(frozen=True)
class Plan:
    """A validated pipeline in execution order."""

    spec: PipelineSpec
    file: str
    stages: tuple[PlannedStage, ...]

    @property
    def digest(self) -> str:
        return self.spec.digest()


def build_plan(loaded: LoadedSpec, registry: Registry) -> Plan:
    """Resolve, validate and order a loaded spec. Raises :class:`SpecError` with all
    problems found (nothing runs before the whole pipeline is valid): those of the spec's
    shape and, for every stage, its `uses`, params, wiring and persisted ports — a stage
    whose id is a duplicate is checked too."""
    spec, source = loaded.spec, loaded.source
    problems: list[Problem] = list(loaded.problems)
    at = loaded.position
    index: dict[str, int] = {}  # id → its first stage
    first: dict[str, int] = {}  # id → YAML index of its first stage, left-out stages included
    for pos, stage_id in sorted([(at(i), s.id) for i, s in enumerate(spec.stages)]):
        first.setdefault(stage_id, pos)
    for pos, stage_id in sorted(loaded.dropped.items()):
        first[stage_id] = min(pos, first.get(stage_id, pos))
    duplicates = sorted(  # left-out stages whose id is a duplicate: reported in file order
        (pos, stage_id) for pos, stage_id in loaded.dropped.items() if first[stage_id] != pos
    )
    known: dict[int, tuple[StageDef, str]] = {}  # stages whose `uses` is registered

    def duplicate(pos: int, stage_id: str) -> None:
        problems.append(
            Problem(source.locate(("stages", pos, "id")), f"duplicate stage id {stage_id!r}")
        )

    for i, stage in enumerate(spec.stages):
        while duplicates and duplicates[0][0] < at(i):
            duplicate(*duplicates.pop(0))
        index.setdefault(stage.id, i)
        if first[stage.id] != at(i):
            duplicate(at(i), stage.id)
        found = registry.stages.get(stage.uses)
        if found is None:
            problems.append(
                Problem(
                    source.locate(("stages", at(i), "uses")), _unknown_stage(stage.uses, registry)
                )
            )
            continue
        known[i] = found
    for pos, stage_id in duplicates:
        duplicate(pos, stage_id)
    defs = {spec.stages[i].id: found for i, found in known.items() if index[spec.stages[i].id] == i}
    check_inputs = "inputs" not in loaded.invalid

    params: dict[str, BaseModel] = {}
    wiring: dict[str, dict[str, tuple[str, str]]] = {}
    for i, (definition, _) in known.items():
        stage, pos = spec.stages[i], at(i)
        model = _params(spec, stage, pos, definition, registry, source, problems, check_inputs)
        wired = _wire(stage, pos, definition, defs, index, loaded.dropped, source, problems)
        _check_persist(stage, pos, definition, source, problems)
        if index[stage.id] == i:
            if model is not None:
                params[stage.id] = model
            wiring[stage.id] = wired

    positions = {k: at(i) for k, i in index.items()}
    _check_output_names(spec, params, defs, positions, registry, source, problems)
    order = _order(wiring, positions, source, problems)
    if problems:
        raise SpecError(problems)
    readers = Counter(
        src
        for consumer, wired in wiring.items()
        for port, src in wired.items()
        if port not in defs[consumer][0].unread_inputs
    )
    persists = {sid: _persisted(spec.stages[index[sid]].persist, defs[sid][0]) for sid in order}
    last_wired = {src: consumer for consumer in order for src in wiring[consumer].values()}
    releases: dict[str, list[tuple[str, str]]] = {}
    for (producer, port), consumer in last_wired.items():
        if port in defs[producer][0].streamed_outputs and port not in persists[producer]:
            releases.setdefault(consumer, []).append((producer, port))
    planned = []
    for stage_id in order:
        stage = spec.stages[index[stage_id]]
        definition, plugin = defs[stage_id]
        persist = persists[stage_id]
        passes = {p: readers[stage_id, p] + (p in persist) for p in definition.streamed_outputs}
        planned.append(
            PlannedStage(
                stage_id,
                stage.uses,
                definition,
                plugin,
                params[stage_id],
                wiring[stage_id],
                persist,
                passes,
                tuple(releases.get(stage_id, ())),
            )
        )
    return Plan(spec, source.file, tuple(planned))


def _persisted(persist: list[str] | bool, definition: StageDef) -> tuple[str, ...]:
    """The output ports a stage persists: all (``persist: true``), those listed, or none."""
    if persist is True:
        return tuple(definition.outputs)
    return tuple(persist) if persist else ()


def _unknown_stage(name: str, registry: Registry) -> str:
    plugin = registry.disabled_provider("stage", name)
    if plugin is not None:
        return (
            f"stage {name!r} is provided by plugin {plugin}, which is disabled "
            f"(--disable-plugin {plugin})"
        )
    known = sorted(registry.stages)
    hint = did_you_mean(name, known)
    return f"unknown stage {name!r}{hint} (registered: {', '.join(known) or 'none'})"


def _params(
    spec: PipelineSpec,
    stage: StageSpec,
    pos: int,
    definition: StageDef,
    registry: Registry,
    source: SourceMap,
    problems: list[Problem],
    check_inputs: bool,
) -> BaseModel | None:
    fields = definition.params.model_fields
    values: dict[str, Any] = {k: v for k, v in spec.defaults.with_.items() if k in fields}
    values.update(stage.with_)
    try:
        model = definition.params.model_validate(values, context={"registry": registry})
    except ValidationError as exc:
        problems += [
            Problem(
                p.location,
                f"stage {stage.id!r} ({stage.uses}): {p.message}{_options_hint(stage, fields, p)}",
            )
            for p in validation_problems(exc, ("stages", pos, "with"), source, definition.params)
        ]
        return None
    unfinite = [  # 1e400 (text to YAML) is inf to pydantic: no parameter is meant so
        Problem(
            source.locate(
                ("stages", pos, "with", *path)
                if path[0] in stage.with_
                else ("defaults", "with", *path)
            ),
            f"stage {stage.id!r} ({stage.uses}): {'.'.join(map(str, path))} is {value!r}: "
            "expected a finite number",
        )
        for path, value in not_finite(model.model_dump(by_alias=True))
        if path[0] in values  # given, not a default of the stage's own
    ]
    if unfinite:
        problems += unfinite
        return None
    for name, info in fields.items():
        extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
        value = getattr(model, name)
        if check_inputs and extra.get(PIPELINE_INPUT) and value not in spec.inputs:
            problems.append(
                Problem(
                    source.locate(("stages", pos, "with", name)),
                    f"stage {stage.id!r}: {name} {value!r} is not a pipeline input "
                    f"(declared inputs: {', '.join(spec.inputs) or 'none'})",
                )
            )
    return model


def not_finite(
    value: Any, path: tuple[str | int, ...] = ()
) -> Iterator[tuple[tuple[str | int, ...], float]]:
    """The path and value of every float in ``value`` (mappings and lists walked) that is
    NaN or ±inf."""
    if isinstance(value, float) and not math.isfinite(value):
        yield path, value
    elif isinstance(value, Mapping):
        for key, item in value.items():
            yield from not_finite(item, (*path, key))
    elif isinstance(value, list | tuple):
        for i, item in enumerate(value):
            yield from not_finite(item, (*path, i))


def _options_hint(stage: StageSpec, fields: Mapping[str, Any], problem: Problem) -> str:
    """Where an unknown field of a stage with reader ``options`` (a read stage) goes, in a
    form that works: ``--set read.md_unit=ft`` is ``--set read.options.md_unit=ft``."""
    name = next((n for n in stage.with_ if problem.message.startswith(f"unknown field {n!r}")), "")
    if "options" not in fields or not name:
        return ""
    value = stage.with_[name]
    return (
        f" (reader options go under options: --set {stage.id}.options.{name}={value}, "
        f"or options: {{{name}: {value}}} in the YAML)"
    )


def _wire(
    stage: StageSpec,
    pos: int,
    definition: StageDef,
    defs: dict[str, tuple[StageDef, str]],
    index: dict[str, int],
    dropped: Mapping[int, str],
    source: SourceMap,
    problems: list[Problem],
) -> dict[str, tuple[str, str]]:
    wired: dict[str, tuple[str, str]] = {}
    here: PathKey = ("stages", pos, "inputs")
    for port, ref in stage.inputs.items():
        loc = source.locate((*here, port))
        if port not in definition.inputs:
            problems.append(
                Problem(
                    source.locate((*here, port), key=True),
                    f"stage {stage.id!r} ({stage.uses}) has no input port {port!r} "
                    f"(ports: {', '.join(definition.inputs) or 'none'})",
                )
            )
            continue
        upstream, _, out_port = ref.partition(".")
        if upstream not in index:
            if upstream not in dropped.values():  # else its own problems are reported
                problems.append(Problem(loc, f"input {port!r}: no stage with id {upstream!r}"))
            continue
        if upstream not in defs:
            continue  # its unknown `uses` is already reported
        up_def = defs[upstream][0]
        if not out_port:
            if len(up_def.outputs) != 1:
                problems.append(
                    Problem(
                        loc,
                        f"input {port!r}: {upstream!r} is ambiguous, stage {upstream!r} has "
                        f"outputs {', '.join(up_def.outputs) or 'none'}; write "
                        f"'{upstream}.<port>'",
                    )
                )
                continue
            out_port = next(iter(up_def.outputs))
        if out_port not in up_def.outputs:
            problems.append(
                Problem(
                    loc,
                    f"input {port!r}: stage {upstream!r} has no output port {out_port!r} "
                    f"(outputs: {', '.join(up_def.outputs) or 'none'})",
                )
            )
            continue
        mismatch = contract_mismatch(up_def.outputs[out_port], definition.inputs[port])
        if mismatch:
            problems.append(Problem(loc, f"input {port!r} from {upstream}.{out_port}: {mismatch}"))
            continue
        wired[port] = (upstream, out_port)
    for port in definition.inputs:
        if port not in stage.inputs and port not in definition.optional_inputs:
            problems.append(
                Problem(
                    source.locate(here if stage.inputs else ("stages", pos)),
                    f"stage {stage.id!r} ({stage.uses}): input port {port!r} is not wired",
                )
            )
    return wired


def contract_mismatch(produced: type[TableContract], wanted: type[TableContract]) -> str:
    """Why a table of contract ``produced`` cannot feed a port of contract ``wanted``
    (empty string if it can)."""
    if issubclass(produced, wanted):
        return ""
    have = {c.name: c for c in produced.compiled().columns}
    reasons = []
    for col in wanted.compiled().columns:
        if not col.required:
            continue
        other = have.get(col.name)
        if other is None:
            reasons.append(f"column {col.name!r} missing")
        elif other.type != col.type or other.unit != col.unit:
            reasons.append(
                f"column {col.name!r} is {other.type} [{other.unit}], needs {col.type} [{col.unit}]"
            )
    if not reasons:
        return ""
    return f"{produced.__name__} does not satisfy {wanted.__name__}: " + "; ".join(reasons)


def _check_persist(
    stage: StageSpec, pos: int, definition: StageDef, source: SourceMap, problems: list[Problem]
) -> None:
    if isinstance(stage.persist, bool):
        return
    for j, port in enumerate(stage.persist):
        if port in stage.persist[:j]:
            problems.append(
                Problem(
                    source.locate(("stages", pos, "persist", j)),
                    f"stage {stage.id!r} persists {port!r} twice: name each output once",
                )
            )
        elif port not in definition.outputs:
            problems.append(
                Problem(
                    source.locate(("stages", pos, "persist", j)),
                    f"stage {stage.id!r} has no output port {port!r} to persist "
                    f"(outputs: {', '.join(definition.outputs) or 'none'})",
                )
            )


def _check_output_names(
    spec: PipelineSpec,
    params: dict[str, BaseModel],
    defs: dict[str, tuple[StageDef, str]],
    positions: dict[str, int],
    registry: Registry,
    source: SourceMap,
    problems: list[Problem],
) -> None:
    """Two stages writing one file name (equal up to case: one file on a case-insensitive
    file system), given or by default, or a stage's file named as a persisted table: a
    problem at the later stage's ``filename`` (or its id), naming the other stage."""
    ext = registry.writers.get(spec.defaults.persist_format, (None, ""))[0]
    written: dict[str, tuple[str, str, Location]] = {}  # casefolded name → name, stage, where
    for stage in sorted(spec.stages, key=lambda st: positions.get(st.id, -1)):
        if positions.get(stage.id) is None:
            continue
        pos, model = positions[stage.id], params.get(stage.id)
        given = "filename" in stage.with_ or "filename" in spec.defaults.with_
        where = source.locate(
            ("stages", pos, "with", "filename") if given else ("stages", pos, "id")
        )
        names_of = getattr(model, "output_names", None)
        names = list(names_of(stage.id, registry)) if callable(names_of) else []
        outputs = tuple(defs[stage.id][0].outputs) if stage.id in defs else ()
        persist = outputs if stage.persist is True else stage.persist or ()
        if ext is not None:
            names += [f"{stage.id}.{port}.{ext.extension}" for port in persist]
        for name in names:
            other = written.setdefault(name.casefold(), (name, stage.id, where))
            if other[1] == stage.id:
                continue
            same = "" if other[0] == name else f" ({other[0]!r} up to case)"
            problems.append(
                Problem(
                    where,
                    f"stage {stage.id!r} writes {name!r}, as stage {other[1]!r} does{same} "
                    f"({other[2]}): give one of them another filename",
                )
            )


def _order(
    wiring: dict[str, dict[str, tuple[str, str]]],
    index: dict[str, int],
    source: SourceMap,
    problems: list[Problem],
) -> list[str]:
    """Stages in dependency order (stable: ties keep the file's order, ``index`` giving each
    stage's place in the YAML); cycles reported."""
    deps = {s: {up for up, _ in ports.values()} for s, ports in wiring.items()}
    order: list[str] = []
    done: set[str] = set()
    pending = sorted(deps, key=index.__getitem__)
    while pending:
        ready = [s for s in pending if deps[s] <= done]
        if not ready:
            cycle = _find_cycle(pending, deps)
            k = cycle.index(min(cycle, key=index.__getitem__))
            cycle = cycle[k:] + cycle[:k]  # start from the stage that comes first in the file
            first = cycle[0]
            problems.append(
                Problem(
                    source.locate(("stages", index[first], "inputs")),
                    "cycle between stages: " + " → ".join([*cycle, first]),
                )
            )
            return order
        order += ready
        done.update(ready)
        pending = [s for s in pending if s not in done]
    return order


def _find_cycle(nodes: list[str], deps: dict[str, set[str]]) -> list[str]:
    """One cycle among ``nodes`` (each of which has an unmet dependency)."""
    remaining = set(nodes)
    path: list[str] = []
    node = nodes[0]
    while node not in path:
        path.append(node)
        node = min(d for d in deps[node] if d in remaining)
    return path[path.index(node) :][::-1]

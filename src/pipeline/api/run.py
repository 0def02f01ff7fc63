"""Whole pipelines from Python: ``gp.run`` — what ``gyropipe run`` does, in memory or into an
output directory (the command line calls :func:`execute` too)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import pyarrow as pa

from pipeline.api.frames import TableLike, WellLike, to_frame, to_table, well_metadata
from pipeline.contracts import TableContract
from pipeline.graph import Plan, build_plan
from pipeline.plugins import shared_registry
from pipeline.registry import Registry
from pipeline.runner import RunInputError, Source, run_plan
from pipeline.spec import load_spec
from pipeline.well import WellMetadata

if TYPE_CHECKING:
    import pandas as pd

InputLike: TypeAlias = "str | Path | TableLike"
"""A pipeline input: a file, or a table already in memory."""


@dataclass(frozen=True)
class RunResult:
    """A finished pipeline run."""

    tables: Mapping[str, pa.Table]
    """every stage output as an Arrow table, by ``"stage.port"`` (a streamed output, such as
    raw samples, is read whole when it is looked up)"""
    well: WellMetadata
    """the well metadata at the end of the run (pipeline, files, overrides merged)"""
    manifest: dict[str, Any]
    """what ``run.json`` records: pipeline, versions, inputs, per-stage times and rows"""
    out: Path | None = None
    """the output directory (a run given ``out``)"""
    outputs: list[Path] = field(default_factory=list)
    """the files published into ``out``"""

    def frame(self, name: str) -> pd.DataFrame:
        """The table ``"stage.port"`` as a DataFrame (units in ``attrs``)."""
        return to_frame(self.tables[name])


def run(
    pipeline: str | Path,
    inputs: Mapping[str, InputLike] | InputLike,
    *,
    set: Mapping[str, Any] | None = None,
    well: WellLike = None,
    out: str | Path | None = None,
    disable: Sequence[str] = (),
) -> RunResult:
    """Run a pipeline YAML on one well.

    ``inputs`` maps each pipeline input to a file or a table (DataFrame or Arrow, see
    :mod:`pipeline.api.frames`); a pipeline with one input takes it bare. ``set`` overrides
    stage params (``{"trajectory.vs_azimuth": 37.5}``, as ``--set``); ``well`` overrides well
    metadata (as ``--well``); ``disable`` names plugins to leave out. Without ``out`` nothing
    is written: stages that only write files (write, export, report) are skipped and every
    table is returned. With ``out`` the run writes exactly what ``gyropipe run --out``
    writes, published in one step.

    Raises :class:`~pipeline.errors.SpecError` (an invalid pipeline), ``RunInputError``
    (inputs that do not fit it) or another :class:`~pipeline.errors.GyropipeError` (a run
    that failed: a malformed file, a broken contract, a stage that raised).
    """
    registry = shared_registry(disable)
    plan = build_plan(load_spec(pipeline, set_overrides(set)), registry)
    return execute(plan, registry, inputs, well=well_metadata(well), out=out)


def set_overrides(values: Mapping[str, Any] | Sequence[str] | None) -> list[str]:
    """``set=`` of the API as ``--set`` items: a mapping's values as JSON
    (``stage.param=JSON``); a list of items (the command line's) as it is."""
    if isinstance(values, Mapping):
        return [f"{key}={json.dumps(value)}" for key, value in values.items()]
    return list(values or ())


def execute(
    plan: Plan,
    registry: Registry,
    inputs: Mapping[str, InputLike] | InputLike,
    *,
    well: WellMetadata,
    out: str | Path | None,
) -> RunResult:
    """Run a validated ``plan`` (:func:`run` after the pipeline is loaded)."""
    defaults = plan.spec.well.merged(well)
    sources = {
        name: _source(plan, name, given, defaults) for name, given in _named(plan, inputs).items()
    }
    result = run_plan(
        plan, registry, inputs=sources, out_dir=Path(out) if out is not None else None, well=well
    )
    return RunResult(
        tables=result.tables.keyed(lambda key: f"{key[0]}.{key[1]}"),
        well=result.well,
        manifest=result.manifest,
        out=result.out_dir,
        outputs=result.outputs,
    )


def _named(plan: Plan, inputs: Mapping[str, InputLike] | InputLike) -> Mapping[str, InputLike]:
    if isinstance(inputs, Mapping):
        return inputs
    declared = list(plan.spec.inputs)
    if len(declared) != 1:
        raise RunInputError(
            f"pipeline {plan.spec.name!r} has inputs {', '.join(declared) or 'none'}: "
            "name each (NAME=FILE)"
        )
    return {declared[0]: inputs}


def _source(plan: Plan, name: str, given: InputLike, well: WellMetadata) -> Source:
    if isinstance(given, str | Path):
        return Path(given)
    return to_table(given, _contract_reading(plan, name), what=f"input {name!r}", well=well)


def _contract_reading(plan: Plan, name: str) -> type[TableContract] | None:
    """The contract of the table the stage reading input ``name`` makes, if one does."""
    for st in plan.stages:
        if getattr(st.params, "input", None) == name and len(st.definition.outputs) == 1:
            (contract,) = st.definition.outputs.values()
            return contract
    return None

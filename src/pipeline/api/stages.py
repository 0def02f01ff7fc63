"""Registered stages called one at a time, in memory: what the Python API's functions run.

Each function of :mod:`pipeline.api.functions` is one registered stage, called with the
same params model, contracts and plugins as in a pipeline, so a notebook and a pipeline
compute the same thing.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa
from pydantic import ValidationError

from pipeline.api.frames import (
    TableLike,
    WellLike,
    describe,
    to_table,
    well_metadata,
    well_of_data,
)
from pipeline.errors import MissingSiteError, ParameterError, StageError
from pipeline.graph import PlannedStage, not_finite
from pipeline.plugins import shared_registry
from pipeline.registry import Provenance, Registry, StageSetup
from pipeline.runner import run_stage, start_time
from pipeline.version import __version__
from pipeline.well import WellMetadata, agreed, attach


def registry() -> Registry:
    """The plugins installed, loaded once per process
    (:func:`~pipeline.plugins.shared_registry`)."""
    return shared_registry()


def call(
    uses: str,
    inputs: Mapping[str, TableLike | None],
    params: Mapping[str, Any],
    *,
    well: WellLike = None,
    out_dir: Path | None = None,
) -> tuple[dict[str, pa.Table], WellMetadata, list[Path]]:
    """Run the registered stage ``uses`` on ``inputs`` (None: an optional input left out)
    with ``params``; the well metadata is the inputs' merged (where they differ: none of
    them, survey dates their range, :func:`~pipeline.well.agreed`) under ``well``. Returns the
    output tables (carrying that well metadata), the well metadata and the files it wrote
    into ``out_dir``."""
    reg = registry()
    definition, plugin = reg.stages[uses]
    given = {port: data for port, data in inputs.items() if data is not None}
    overrides = well_metadata(well)
    headers = {port: well_of_data(d) for port, d in given.items()}
    update, _ = agreed(headers)  # where the inputs' headers differ, no one of them is theirs
    merged = well_metadata(*headers.values(), update, overrides)
    try:
        parsed = definition.params.model_validate(dict(params), context={"registry": reg})
    except ValidationError as exc:
        raise ParameterError(f"{uses}: {describe(exc)}") from None
    for path, value in not_finite(parsed.model_dump(by_alias=True)):
        if path[0] in params:  # given (1e400 is inf to pydantic), not a default of the stage
            where = ".".join(map(str, path))
            raise ParameterError(f"{uses}: {where} is {value!r}: expected a finite number")
    tables = {
        port: to_table(data, definition.inputs[port], what=f"{uses} input {port!r}", well=merged)
        for port, data in given.items()
    }
    stage = PlannedStage(uses, uses, definition, plugin, parsed, {}, ())
    provenance = Provenance(
        pipeline="python",
        pipeline_version="",
        pipeline_file="",
        pipeline_sha256="",
        gyropipe=__version__,
        plugins={n: p.version for n, p in sorted(reg.plugins.items()) if not p.error},
        inputs={},
        started=start_time(),
        stages=(StageSetup(uses, uses, reg.plugin_label(plugin), parsed.model_dump(mode="json")),),
        tool_models=reg.tool_model_files(),
    )
    try:
        outs, files = run_stage(
            stage,
            tables,
            registry=reg,
            well=merged,
            overrides=overrides,
            provenance=provenance,
            out_dir=out_dir or Path("."),
        )
    except StageError as exc:  # worded for Python: the `latitude=` argument, not --well
        if not isinstance(exc.__cause__, MissingSiteError):
            raise
        python = exc.__cause__.in_python()
        raise StageError(exc.stage_id, exc.uses, exc.plugin, python) from python
    return {port: attach(table, merged) for port, table in outs.items()}, merged, files

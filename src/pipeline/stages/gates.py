"""Built-in plugin: the ``acceptance_gates`` stage — an in-run compared with an out-run of a
gyro survey against a client's acceptance criteria (:mod:`pipeline.qc.gates`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import pyarrow as pa

from pipeline.drift.tables import InOutQc
from pipeline.hookspecs import hookimpl
from pipeline.qc.gates import GateOptions, acceptance_gates, compare_runs
from pipeline.qc.tables import RunComparison
from pipeline.registry import StageContext, StageDef
from pipeline.survey.stations import north_reference_of
from pipeline.tables import AcceptanceGates, Stations


def gates_stage(
    inputs: Mapping[str, pa.Table], params: GateOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """In-run and out-run stations (or a free gyro's in/out QC) → pairs and gates."""
    runs = "inrun" in inputs and "outrun" in inputs
    if runs == ("inout" in inputs) or ("inrun" in inputs) != ("outrun" in inputs):
        raise ValueError("wire either both `inrun` and `outrun` (stations) or `inout`")
    if runs:
        north_in = north_reference_of(inputs["inrun"], "azi")
        north_out = north_reference_of(inputs["outrun"], "azi")
        if north_in != north_out:
            raise ValueError(
                f"the in-run's azimuths are {north_in} north, the out-run's {north_out}: "
                "convert one (north_reference stage) before comparing"
            )
        comparison = compare_runs(inputs["inrun"], inputs["outrun"], params)
        return {"comparison": comparison, "gates": acceptance_gates(comparison, params)}
    inout = inputs["inout"]
    empty = RunComparison.compiled().make_table(
        {c.name: [] for c in RunComparison.compiled().columns}
    )
    return {"comparison": empty, "gates": acceptance_gates(inout, params)}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="acceptance_gates",
            func=gates_stage,
            description="Acceptance gates of a gyro survey, in-run against out-run: stations "
            "compared, inclination, azimuth (above and below a low inclination) and depth "
            "agreement, each pass or fail against configurable limits.",
            inputs={"inrun": Stations, "outrun": Stations, "inout": InOutQc},
            optional_inputs=frozenset({"inrun", "outrun", "inout"}),
            outputs={"comparison": RunComparison, "gates": AcceptanceGates},
            params=GateOptions,
        )
    )

"""Built-in plugin: stages that start a pipeline from a simulation plan."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.hookspecs import hookimpl
from pipeline.registry import StageContext, StageDef, pipeline_input
from pipeline.tables import FreeGyroReadings, RawSamples, SimTruth, Stations
from pipeline.well import WellMetadata, attach

if TYPE_CHECKING:  # the simulator is imported when a simulation stage runs, not to register
    from pipeline.sim.spec import SimulationSpec


class SimulateParams(BaseModel):
    """Parameters of the simulation stages."""

    model_config = ConfigDict(extra="forbid")
    plan: str = pipeline_input("plan", "name of the pipeline input holding the plan YAML")
    seed: int | None = Field(None, description="random seed (default: the plan's)")


def well_of_simulation(spec: SimulationSpec) -> WellMetadata:
    """Well metadata of a simulated survey (azimuths are true north)."""
    return WellMetadata(
        well=spec.name,
        latitude=spec.site.latitude,
        longitude=spec.site.longitude,
        elevation=spec.site.elevation,
        survey_date=spec.site.date,
        tool_type=f"simulated {spec.tool.preset}",
        tool_preset=spec.tool.preset,
        north_reference="true",
    )


def simulation_tables(spec: SimulationSpec) -> dict[str, pa.Table]:
    """All tables of a simulation by name, with the well metadata attached."""
    from pipeline.sim.freegyro import simulate_free_gyro
    from pipeline.sim.simulate import simulate
    from pipeline.sim.spec import FreeGyroSurvey

    well = well_of_simulation(spec)
    if isinstance(spec.survey, FreeGyroSurvey):
        return {"readings": attach(simulate_free_gyro(spec), well)}
    result = simulate(spec)
    return {
        name: attach(table, well)
        for name, table in (
            ("samples", result.samples),
            ("truth", result.truth),
            ("stations", result.stations),
        )
    }


def _load(params: SimulateParams, ctx: StageContext) -> SimulationSpec:
    from pipeline.sim.spec import load_simulation

    def read_stations(path: Path, reader: str) -> pa.Table:
        ctx.record_file(path, "plan", "stations file")  # a file the plan names
        return ctx.read_file(path, "stations", reader=reader)[0]

    return load_simulation(
        ctx.input_path(params.plan), seed=params.seed, read_stations=read_stations
    )


def run_simulation(
    inputs: Mapping[str, pa.Table], params: SimulateParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Point or continuous survey: raw samples, truth and true stations."""
    from pipeline.sim.spec import FreeGyroSurvey

    spec = _load(params, ctx)
    if isinstance(spec.survey, FreeGyroSurvey):
        raise ValueError("this plan is a free_gyro survey: use the simulate_free_gyro stage")
    ctx.update_well(well_of_simulation(spec))
    return simulation_tables(spec)


def run_free_gyro(
    inputs: Mapping[str, pa.Table], params: SimulateParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Free-gyro survey: drifting azimuth readings."""
    from pipeline.sim.spec import FreeGyroSurvey

    spec = _load(params, ctx)
    if not isinstance(spec.survey, FreeGyroSurvey):
        raise ValueError(f"this plan is a {spec.survey.mode} survey: use the simulate stage")
    ctx.update_well(well_of_simulation(spec))
    return simulation_tables(spec)


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="simulate",
            func=run_simulation,
            description="Simulate a point or continuous gyro survey from a plan YAML.",
            outputs={"samples": RawSamples, "truth": SimTruth, "stations": Stations},
            params=SimulateParams,
        )
    )
    register(
        StageDef(
            name="simulate_free_gyro",
            func=run_free_gyro,
            description="Simulate the drifting readings of a free-gyro survey from a plan.",
            outputs={"readings": FreeGyroReadings},
            params=SimulateParams,
        )
    )

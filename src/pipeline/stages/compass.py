"""Built-in plugin: gyrocompassing stages (raw samples → position readings → stations)."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import pyarrow as pa

from pipeline.earth.site import resolve_site
from pipeline.gyrocompass.readings import ReadingOptions, position_readings
from pipeline.gyrocompass.solve import CompassOptions, NoStationSolved, compass
from pipeline.hookspecs import hookimpl
from pipeline.registry import StageContext, StageDef
from pipeline.tables import CompassRejects, CompassStations, PositionReadings, RawSamples


def readings_stage(
    inputs: Mapping[str, pa.Table], params: ReadingOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Average each station's frame positions (transients trimmed)."""
    return {"readings": position_readings(inputs["samples"], params)}


def compass_stage(
    inputs: Mapping[str, pa.Table], params: CompassOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Solve inclination, azimuth and toolfaces of every station; none solved is an error
    naming why (a units mistake rejects every station)."""
    site = resolve_site(ctx.well, stage="compass", latitude=params.latitude)
    stations, rejects = compass(inputs["readings"], site.latitude, params)
    if stations.num_rows == 0 and rejects.num_rows:
        raise NoStationSolved(rejects)
    return {"stations": stations, "rejects": rejects}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="position_readings",
            func=readings_stage,
            description="Reduce raw samples of a point survey to one averaged reading per "
            "station and frame position.",
            inputs={"samples": RawSamples},
            outputs={"readings": PositionReadings},
            params=ReadingOptions,
        )
    )
    register(
        StageDef(
            name="compass",
            func=compass_stage,
            description="Multi-position gyrocompassing: inclination, true azimuth, gyro and "
            "high-side toolface with predicted σ per station; rejected stations with why.",
            inputs={"readings": PositionReadings},
            outputs={"stations": CompassStations, "rejects": CompassRejects},
            params=CompassOptions,
        )
    )

"""Built-in plugin: continuous-mode gyro survey (moving run between two compassed stops)."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from pipeline.continuous.options import ContinuousOptions
from pipeline.continuous.tables import ContinuousSeries, ContinuousStations
from pipeline.earth.site import SiteParams, resolve_site
from pipeline.errors import EmptyTableError
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.streams import Port, as_table
from pipeline.tables import CompassStations, RawSamples


class ContinuousParams(ContinuousOptions, SiteParams):
    """Parameters of the integrate_continuous stage: the site latitude (if not the well's)
    and the integration options."""


def continuous_stage(
    inputs: Mapping[str, Port], params: ContinuousParams, ctx: StageContext
) -> dict[str, Port]:
    """Integrate the azimuth of the moving run; close it on the end stop. The samples stream
    in (read once into a column store, on disk past 24 MiB), the full-rate series streams out."""
    if as_table(inputs["stops"]).num_rows == 0:
        raise EmptyTableError("stops", "the run starts and closes on compassed stops")
    from pipeline.continuous.integrate import integrate_continuous  # on use: numerical code

    site = resolve_site(ctx.well, stage="integrate_continuous", latitude=params.latitude)
    result = integrate_continuous(
        inputs["samples"], as_table(inputs["stops"]), site.latitude, params
    )
    misclosure = f"{result.misclosure:.6g}".encode()
    stations = result.stations.replace_schema_metadata(
        {**(result.stations.schema.metadata or {}), b"misclosure_deg": misclosure}
    )
    return {"stations": stations, "series": result.series}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="integrate_continuous",
            func=continuous_stage,
            description="Continuous-mode gyro: integrate the azimuth of the moving run from "
            "the start stop (servo'd single-axis, two-axis or three-axis strapdown tools), "
            "remove the misclosure on the end stop linearly in time, flag near-vertical "
            "sections; stations at a fixed MD spacing and the full-rate series.",
            inputs={"samples": RawSamples, "stops": CompassStations},
            outputs={"stations": ContinuousStations, "series": ContinuousSeries},
            params=ContinuousParams,
            streamed_inputs=frozenset({"samples"}),
            streamed_outputs=frozenset({"series"}),
        )
    )


def continuous_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The continuous survey in the report: integration between the stops, the spacing."""
    return MethodNote(
        "Continuous survey",
        "azimuth rate integrated from a compassing stop and closed on the other stop where "
        "both give an azimuth (the QC section says where not), stations every "
        f"{stage.params.get('spacing', '?')} m",
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("integrate_continuous", method=continuous_method))

"""Built-in plugin: the ``export`` stage — several tables of a run into one file.

Writers whose file holds several tables (``WriterDef.write_tables``: the MCAP of processed
streams, the JSON summary) receive the tables wired to the stage's ports, each under its
port name, with the well metadata and the run's provenance. One table goes through ``write``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Annotated

import pyarrow as pa
from pydantic import Field

from pipeline.contracts import TableContract, column
from pipeline.drift.tables import CorrectedFreeGyroReadings, InOutQc
from pipeline.hookspecs import hookimpl
from pipeline.qc.tables import QcSummary
from pipeline.registry import StageContext, StageDef, registered
from pipeline.stages.files import WriteParams
from pipeline.streams import Port, TableStream, as_table
from pipeline.tables import AnyTable, Stations, Trajectory
from pipeline.well import attach, attached


class QcTable(TableContract):
    """QC results of any check family: one row per evaluation (``check`` results,
    ``validity_checks`` QC…)."""

    check: str = column(unit=None, description="check name")
    passed: bool | None = column(unit=None, description="within tolerance (null: not evaluated)")


PORTS: dict[str, type[TableContract]] = {
    "trajectory": Trajectory,
    "stations": Stations,
    "readings": AnyTable,
    "series": AnyTable,
    "qc": QcTable,
    "qc_summary": QcSummary,
    "rejects": AnyTable,
    "drift": CorrectedFreeGyroReadings,
    "inout": InOutQc,
}
"""Input ports (all optional): the survey's trajectory, its stations (compassed, continuous),
per-position readings, continuous series, QC results, the validity checks' verdict per
station (the stations they dropped), the stations rejected and a free-gyro survey's
drift-corrected readings and in-run/out-run comparison."""


class ExportParams(WriteParams):
    """Parameters of the export stage."""

    writer: Annotated[str, registered("writer")] = Field(
        description="writer of several tables (mcap, json_summary, …)"
    )


def export(
    inputs: Mapping[str, Port], params: ExportParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Write the wired tables into one file (published when the run succeeds). The series
    streams into a writer that takes streams (``WriterDef.tables_streamed``), else it is
    concatenated."""
    writer = ctx.writer(params.writer)
    if writer.write_tables is None:
        raise ValueError(f"writer {params.writer!r} writes one table: use the write stage for it")
    if not inputs:
        raise ValueError(f"wire at least one of the ports {', '.join(PORTS)}")
    path = params.output_path(ctx, writer.extension)
    tables = {
        port: (
            value.replace_schema_metadata(attached(value.schema, ctx.well))
            if isinstance(value, TableStream) and writer.tables_streamed
            else attach(as_table(value), ctx.well)
        )
        for port, value in inputs.items()
    }
    writer.write_tables(tables, path, ctx.well, ctx.provenance)
    return {}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="export",
            func=export,
            description="Write several tables of the run (trajectory, stations, readings, "
            "series, QC, the validity verdicts, rejects, drift-corrected readings, in-run/out-run "
            "comparison) into one "
            "file with a writer that holds several.",
            inputs=PORTS,
            params=ExportParams,
            optional_inputs=frozenset(PORTS),
            streamed_inputs=frozenset({"series"}),
        )
    )

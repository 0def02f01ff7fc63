"""Built-in plugin: report stages — the survey report and the drift calibration report, each
one self-contained HTML file and an A4 PDF with the same content, written into the run's
output directory (published atomically with the other outputs).

The report modules are imported only when a report is made, so loading the plugins stays
fast for every other command.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any, Literal

import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.anticollision.tables import Clearance
from pipeline.continuous.tables import ContinuousSeries
from pipeline.contracts import TableContract
from pipeline.drift.tables import (
    AllanResult,
    CalibrationReadings,
    CalibrationResult,
    CalibrationSeries,
    CorrectedFreeGyroReadings,
    InOutQc,
    NoiseParameters,
)
from pipeline.filenames import OutputFilename
from pipeline.hookspecs import hookimpl
from pipeline.qc.tables import QcResults, QcSummary, RunComparison
from pipeline.registry import Registry, StageContext, StageDef
from pipeline.streams import Port, as_stream
from pipeline.survey.courses import MIN_COURSE
from pipeline.tables import AcceptanceGates, CheckResults, CompassRejects, Stations, Trajectory

if TYPE_CHECKING:
    from pipeline.reports.document import Document


class ReportParams(BaseModel):
    """Parameters of the report stages."""

    model_config = ConfigDict(extra="forbid")
    title: str | None = Field(
        None,
        description="report title (default: the stage's own; 'Clearance report' for a survey "
        "report with a clearance table wired)",
    )
    filename: OutputFilename | None = Field(
        None,
        description="base file name: <filename>.html, <filename>.pdf (default: the stage id)",
    )
    formats: list[Literal["html", "pdf"]] = Field(
        ["html", "pdf"], min_length=1, description="files to write"
    )
    min_course_length: float = Field(
        MIN_COURSE,
        ge=0,
        description="survey report, m: dogleg severity over a course shorter than this (e.g. "
        "the last course to an end stop) is left out of the summary's maximum DLS (and of the "
        "fleet page's, which states this report's) and marked in the listing; 0 counts every "
        "course",
    )
    max_course_length: float = Field(
        100.0,
        gt=0,
        description="survey report, m: a station at the end of a longer course (a first "
        "course after the tie-in, a gap between stations) is flagged 'long course'",
    )

    def output_names(self, stage_id: str, registry: Registry) -> list[str]:
        """The files the stage writes (checked by the planner against the other stages')."""
        return [f"{self.filename or stage_id}.{fmt}" for fmt in self.formats]


def _write(doc: Document, params: ReportParams, ctx: StageContext) -> None:
    from pipeline.reports.figures import Figures
    from pipeline.reports.html import render_html
    from pipeline.reports.pdf import render_pdf

    name = params.filename or ctx.stage_id
    drawn = Figures()
    if "html" in params.formats:
        ctx.output_path(f"{name}.html").write_bytes(render_html(doc, drawn))
    if "pdf" in params.formats:
        render_pdf(doc, ctx.output_path(f"{name}.pdf"), drawn)


def survey_report(
    inputs: Mapping[str, Any], params: ReportParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Trajectory (and whatever QC, drift and noise tables are wired) → survey report; a
    full-rate ``series`` streams in and is reduced batch by batch to its drawing envelope."""
    from pipeline.reports.envelope import full_rate
    from pipeline.reports.sections import north_label
    from pipeline.reports.survey import SurveyTables, survey_document

    tables = dict(inputs)
    series: Port | None = tables.pop("series", None)  # a stream from the engine
    if series is not None:
        stream = as_stream(series)
        north = north_label(stream.schema.empty_table(), "azi")
        tables["series"] = full_rate(stream, north)
    doc = survey_document(
        SurveyTables(**tables),
        ctx.well,
        ctx.provenance,
        params.title
        or ("Clearance report" if tables.get("clearance") is not None else "Gyro survey report"),
        ctx.report_parts(),
        min_course=params.min_course_length,
        max_course=params.max_course_length,
    )
    _write(doc, params, ctx)
    return {}


def calibration_report(
    inputs: Mapping[str, pa.Table], params: ReportParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Drift calibration result and series (and the readings, if wired) → calibration report."""
    from pipeline.reports.calibration import calibration_document

    doc = calibration_document(
        inputs["result"],
        inputs["series"],
        inputs.get("readings"),
        ctx.well,
        ctx.provenance,
        params.title or "Gyro drift calibration report",
        ctx.report_parts(),
    )
    _write(doc, params, ctx)
    return {}


SURVEY_INPUTS: dict[str, type[TableContract]] = {
    "trajectory": Trajectory,
    "stations": Stations,
    "qc": QcResults,
    "qc_summary": QcSummary,
    "rejects": CompassRejects,
    "checks": CheckResults,
    "inout": InOutQc,
    "drift": CorrectedFreeGyroReadings,
    "calibration": CalibrationResult,
    "allan": AllanResult,
    "noise": NoiseParameters,
    "comparison": RunComparison,
    "gates": AcceptanceGates,
    "clearance": Clearance,
    "series": ContinuousSeries,
}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="report",
            func=survey_report,
            description="Survey report (HTML and PDF): header, method and reference models, "
            "listing, trajectory plots, the full-rate series (streamed, drawn from its "
            "envelope), ellipses, QC charts and the stations dropped (validity summary, "
            "compassing rejects), drift and Allan plots, provenance.",
            inputs=SURVEY_INPUTS,
            optional_inputs=frozenset(SURVEY_INPUTS) - {"trajectory"},
            streamed_inputs=frozenset({"series"}),
            params=ReportParams,
        )
    )
    register(
        StageDef(
            name="calibration_report",
            func=calibration_report,
            description="Drift calibration report (HTML and PDF): linearity verdict, drift "
            "estimates with σ beside the traditional one, series table and plot.",
            inputs={
                "result": CalibrationResult,
                "series": CalibrationSeries,
                "readings": CalibrationReadings,
            },
            optional_inputs=frozenset({"readings"}),
            params=ReportParams,
        )
    )

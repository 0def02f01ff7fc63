"""Built-in plugin: free-gyro drift — calibration (seed 000), drift correction of free-gyro
surveys with in/out-run QC, Allan analysis of static records; and the stages
``read_calibration``, ``read_calibration_result`` and ``read_free_gyro``, which read a
pipeline input through a reader of that kind (the ``drift_tables`` reader of
:mod:`pipeline.io.drift_tables` reads all three; one stage per kind, because a stage's output
contract is fixed).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping

import pyarrow as pa

from pipeline.drift.allan import AllanOptions, analyse_static
from pipeline.drift.applicability import (
    CalibrationRangeError,
    calibration_caveats,
    survey_conditions,
)
from pipeline.drift.calibration import CalibrationOptions, calibrate
from pipeline.drift.correction import (
    CorrectionOptions,
    DriftRate,
    calibration_rate,
    correct_survey,
    drift_rate_of,
    survey_serial,
)
from pipeline.drift.tables import (
    AllanResult,
    CalibrationReadings,
    CalibrationResult,
    CalibrationSeries,
    CorrectedFreeGyroReadings,
    DriftStations,
    DwellRecommendation,
    InOutQc,
    NoiseParameters,
)
from pipeline.earth.site import SiteParams, resolve_site
from pipeline.errors import EmptyTableError, SurveyCheckWarning
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages.files import read_stage_def
from pipeline.tables import FreeGyroReadings, RawSamples
from pipeline.well import WellMetadata, well_of

NO_WELL = WellMetadata()
"""An empty header: ``ctx.well_for(NO_WELL)`` is the well the pipeline and the run state,
no input file's header merged in (another input's, a calibration's, is not the survey's)."""


def calibrate_stage(
    inputs: Mapping[str, pa.Table], params: CalibrationOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Calibration readings → drift estimates and series means per instrument."""
    if inputs["readings"].num_rows == 0:
        raise EmptyTableError("calibration readings", "a drift calibration needs readings")
    header = ctx.well_for(well_of(inputs["readings"]))  # the calibration file's own
    result, series = calibrate(inputs["readings"], params, header.tool_serial, header.survey_date)
    return {"result": result, "series": series}


def correct_stage(
    inputs: Mapping[str, pa.Table], params: CorrectionOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Free-gyro readings → drift-corrected readings, stations and in/out QC."""
    if inputs["readings"].num_rows == 0:
        raise EmptyTableError("free-gyro readings", "there is nothing to correct")
    if "calibration" in inputs and inputs["calibration"].num_rows == 0:
        raise EmptyTableError("calibration result", "it gives no drift rate")
    source = params.source
    if source == "auto":
        source = (
            "calibration"
            if "calibration" in inputs
            else "given"
            if params.drift_rate is not None
            else "tie_in"
        )
    rate: DriftRate | None = None
    if source == "calibration":
        if "calibration" not in inputs:
            raise ValueError("source calibration: wire a calibration result to `calibration`")
        serial = survey_serial(
            {
                "the readings' own tool serial": (
                    well_of(inputs["readings"]) or NO_WELL
                ).tool_serial,
                "the stage's instrument": params.instrument,
                "the well's tool_serial": ctx.well_for(NO_WELL).tool_serial,
            }
        )
        rate = calibration_rate(
            inputs["calibration"], serial, params.estimate, params.allow_nonlinear
        )
        rate = with_caveats(rate, serial, inputs, params, ctx)
    elif source == "given":
        if params.drift_rate is None:
            raise ValueError("source given: set drift_rate (°/h)")
        rate = DriftRate(rate=params.drift_rate, sigma=params.drift_sigma, source="given")
    survey = correct_survey(inputs["readings"], params, rate)
    return {"readings": survey.readings, "stations": survey.stations, "qc": survey.qc}


def with_caveats(
    rate: DriftRate,
    serial: str | None,
    inputs: Mapping[str, pa.Table],
    params: CorrectionOptions,
    ctx: StageContext,
) -> DriftRate:
    """``rate`` with the caveats of its calibration (:mod:`pipeline.drift.applicability`;
    and a survey whose tool serial ``serial`` is stated nowhere), each warned; refused
    (:class:`CalibrationRangeError`) when the stage is told to."""
    header = ctx.well_for(well_of(inputs["readings"]) or NO_WELL)  # the survey's, no other's
    conditions = survey_conditions(inputs["readings"], header.survey_date, header.survey_date_last)
    assert rate.instrument is not None  # a calibration's rate names its instrument
    caveats = []
    if serial is None:
        caveats.append(
            "the survey's tool serial is stated nowhere: the calibration's one instrument, "
            f"{rate.instrument!r}, was taken for the survey's tool"
        )
    caveats += calibration_caveats(
        inputs["calibration"], rate.instrument, conditions, params.max_calibration_age_days
    )
    if caveats and params.calibration_caveats == "refuse":
        raise CalibrationRangeError(f"the drift calibration: {'; '.join(caveats)}")
    for caveat in caveats:
        warnings.warn(
            f"stage {ctx.stage_id!r}: drift calibration: {caveat}", SurveyCheckWarning, stacklevel=2
        )
    return rate.model_copy(update={"caveats": tuple(caveats)})


class AllanParams(AllanOptions, SiteParams):
    """Parameters of the allan stage: the site latitude (if not the well's) and the options
    of the analysis."""


def allan_stage(
    inputs: Mapping[str, pa.Table], params: AllanParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Static raw samples → Allan deviations, noise terms and the recommended dwell."""
    if inputs["samples"].num_rows == 0:
        raise EmptyTableError("samples", "an Allan analysis needs a static record")
    site = resolve_site(ctx.well, stage="allan", latitude=params.latitude)
    allan, noise, dwell = analyse_static(inputs["samples"], params, site.latitude)
    return {"allan": allan, "noise": noise, "dwell": dwell}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    for name, kind, contract, description, default_input, into_well in (
        (
            "read_calibration",
            "calibration",
            CalibrationReadings,
            "Read free-gyro calibration readings (series × set azimuths).",
            "calibration",
            True,
        ),
        (
            "read_calibration_result",
            "calibration_result",
            CalibrationResult,
            "Read a drift calibration result written by calibrate_drift (its file's header "
            "— the calibration's date, tool serial — is the calibration's own, not the "
            "survey's: the table carries it, the run's well does not take it).",
            "calibration",
            False,
        ),
        (
            "read_free_gyro",
            "free_gyro",
            FreeGyroReadings,
            "Read free-gyro in-run/out-run station readings.",
            "readings",
            True,
        ),
    ):
        register(
            read_stage_def(name, kind, contract, description, default_input, into_well=into_well)
        )
    register(
        StageDef(
            name="calibrate_drift",
            func=calibrate_stage,
            description="Drift rate of free gyros from calibration series (seed 000): pairwise, "
            "mean, grouped, fitted and traditional estimates with σ, and a linearity verdict.",
            inputs={"readings": CalibrationReadings},
            outputs={"result": CalibrationResult, "series": CalibrationSeries},
            params=CalibrationOptions,
        )
    )
    register(
        StageDef(
            name="correct_drift",
            func=correct_stage,
            description="Remove the drift from free-gyro readings (calibrated, given or tie-in "
            "rate) with predicted σ; combined stations; in-run/out-run QC.",
            inputs={"readings": FreeGyroReadings, "calibration": CalibrationResult},
            outputs={
                "readings": CorrectedFreeGyroReadings,
                "stations": DriftStations,
                "qc": InOutQc,
            },
            params=CorrectionOptions,
            optional_inputs=frozenset({"calibration"}),
        )
    )
    register(
        StageDef(
            name="allan",
            func=allan_stage,
            description="Allan deviations of a static record, IEEE 952 noise terms per axis and "
            "the compassing dwell per frame position for a target azimuth σ (the record is "
            "taken whole: the overlapping deviation at every averaging time needs it).",
            inputs={"samples": RawSamples},
            outputs={"allan": AllanResult, "noise": NoiseParameters, "dwell": DwellRecommendation},
            params=AllanParams,
        )
    )


def calibration_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The drift calibration in the report: the paper, the estimate used, the test level."""
    from pipeline.reports.literature import DRIFT_CALIBRATION

    return MethodNote(
        "Drift calibration",
        f"drift from the means of the calibration series {ctx.cite(DRIFT_CALIBRATION)}, "
        f"estimate used: {stage.params.get('use', '?')}, linearity test at "
        f"α = {stage.params.get('alpha', '?')}",
    )


DRIFT_SOURCES = {
    "tie_in": "the misclosure at the tie-in station",
    "calibration": "the instrument's drift calibration",
    "given": "a given rate",
    "auto": "the best available source",
}
"""How the report words each drift-rate ``source``."""


def correction_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The drift correction in the report: the model and where its rate came from (as the
    corrected readings record it, else as the stage was told)."""
    applied = drift_rate_of(ctx.tables["drift"]) if "drift" in ctx.tables else None
    source = applied.source if applied is not None else str(stage.params.get("source", "?"))
    return MethodNote(
        "Drift correction", f"A − ω·(t − t₀), rate from {DRIFT_SOURCES.get(source, source)}"
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("correct_drift", method=correction_method))
    register(ReportDef("calibrate_drift", method=calibration_method))

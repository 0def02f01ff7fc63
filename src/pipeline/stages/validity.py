"""Built-in plugin: validity checks of raw sensor data (DOMAIN.md §3) as pipeline stages.

The site (latitude, longitude, elevation, survey date) comes from the well metadata
(:func:`~pipeline.earth.site.resolve_site`); the geomagnetic reference from the model chosen
in the options.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Mapping

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from pipeline.earth.frames import OMEGA_EARTH
from pipeline.earth.geomagnetic import field_model
from pipeline.earth.gravity import METHOD as GRAVITY_METHOD
from pipeline.earth.site import Site, resolve_site
from pipeline.errors import SurveyCheckWarning
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.qc.dropped import dropped_stations
from pipeline.qc.engine import drop_stations, station_checks
from pipeline.qc.options import QcOptions
from pipeline.qc.tables import MagneticAnomalies, QcResults, QcSummary
from pipeline.qc.windows import anomaly_intervals, window_checks
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages.compass import tool_errors
from pipeline.streams import Port, as_table
from pipeline.tables import PositionReadings, RawSamples

REFERENCES_KEY = b"gyropipe.references"


def station_stage(
    inputs: Mapping[str, Port], params: QcOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Check every station × frame position; the readings of dropped stations are removed.
    The raw samples (magnetometers) stream through in one pass. Unset accelerometer error
    magnitudes are the well's tool's (:func:`pipeline.stages.compass.tool_errors`)."""
    readings, samples = as_table(inputs["readings"]), inputs.get("samples")
    site = resolve_site(ctx.well, stage="validity_checks", param=None, field=_has_field(samples))
    params = params.with_defaults(tool_errors(ctx.well))
    qc, summary = station_checks(readings, site, params, samples=samples)
    qc = with_references(qc, site, params, field=_has_field(samples))
    kept = drop_stations(readings, summary)
    if readings.num_rows and not kept.num_rows:
        message = every_station_dropped(ctx.stage_id, qc, summary)
        warnings.warn(SurveyCheckWarning(message), stacklevel=2)
    return {"qc": qc, "summary": summary, "readings": kept}


def every_station_dropped(stage: str, qc: pa.Table, summary: pa.Table) -> str:
    """What to tell an engineer whose every station the checks dropped: the stations, and
    for each check that dropped them the worst value measured against its limit (the
    stage's parameter of that name: a tool whose sensors are noisier at rest than the
    limit needs its own)."""
    dropped = dropped_stations([summary])
    shown = "; ".join(f"MD {d.md:.2f} m: {d.names()}" for d in dropped)
    names = sorted({name for d in dropped for name in d.checks})
    worst = []
    for name in names:
        rows = qc.filter(pc.equal(qc.column("check"), name)).to_pylist()
        failed = [r for r in rows if r["passed"] is False and r["measured"] is not None]
        if failed:
            top = max(failed, key=lambda r: abs(r["measured"]))
            limit = top["tolerance"]
            worst.append(
                f"{name}: up to {top['measured']:.4g} {top['unit']} measured"
                + (f" against {limit:.4g} {top['unit']}" if np.isfinite(limit) else "")
            )
    return (
        f"stage {stage!r}: the checks dropped every station recorded ({len(dropped)}: {shown}), "
        "so no station is left to compass or survey"
        + (f" — {'; '.join(worst)}" if worst else "")
        + ". If the tool was still and its sensors are noisier at rest than these limits, "
        "give the stage the tool's own (its `with:` parameter of each check's name)"
    )


def window_stage(
    inputs: Mapping[str, Port], params: QcOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Check continuous samples on sliding windows, streamed a batch of windows at a time;
    list magnetic anomaly intervals (none of no samples)."""
    samples = inputs["samples"]
    site = resolve_site(ctx.well, stage="window_checks", param=None, field=_has_field(samples))
    qc = window_checks(samples, site, params)
    if qc.num_rows == 0:  # no samples
        return {"qc": qc, "anomalies": MagneticAnomalies.compiled().schema().empty_table()}
    qc = with_references(qc, site, params, field=_has_field(samples))
    return {"qc": qc, "anomalies": anomaly_intervals(qc)}


def with_references(qc: pa.Table, site: Site, options: QcOptions, *, field: bool) -> pa.Table:
    """``qc`` with the reference models used recorded in its schema metadata
    (``gyropipe.references``, JSON): Earth rate, normal gravity, geomagnetic model."""
    references = {
        "earth_rate": f"WGS84 Ω = {OMEGA_EARTH} rad/s",
        "gravity": f"{GRAVITY_METHOD}, {site.gravity:.6f} m/s² at the wellhead",
        "geomagnetic": (
            "given by the site"
            if site.magnetic is not None
            else _model_label(options)
            if field
            else "not used"
        ),
    }
    meta = {**(qc.schema.metadata or {}), REFERENCES_KEY: json.dumps(references).encode()}
    return qc.replace_schema_metadata(meta)


def _model_label(options: QcOptions) -> str:
    model = field_model(options.magnetic_model)
    return f"{model.name} ({model.version})"


def _has_field(samples: Port | None) -> bool:
    """True if the samples carry magnetometer data (then the geomagnetic model is needed)."""
    return samples is not None and "mag_x" in samples.column_names


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="validity_checks",
            func=station_stage,
            description="Validity checks of each station's readings at rest (|ω|, |g|, |B|, "
            "dip, latitude, Earth-rate invariants) with the suspected faulty sensor; passes the "
            "readings on without the stations whose checks say drop.",
            inputs={"readings": PositionReadings, "samples": RawSamples},
            optional_inputs=frozenset({"samples"}),
            streamed_inputs=frozenset({"samples"}),
            unread_inputs=frozenset({"samples"}),  # read only with magnetometers
            outputs={"qc": QcResults, "summary": QcSummary, "readings": PositionReadings},
            params=QcOptions,
        )
    )
    register(
        StageDef(
            name="window_checks",
            func=window_stage,
            description="Validity checks of continuous raw samples on sliding windows: rest "
            "detection, motion bounds, magnetic anomalies along depth.",
            inputs={"samples": RawSamples},
            outputs={"qc": QcResults, "anomalies": MagneticAnomalies},
            params=QcOptions,
            streamed_inputs=frozenset({"samples"}),
        )
    )


def validity_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The validity checks in the report: sensor triads against the site's references."""
    from pipeline.reports.literature import DATA_VALIDITY

    return MethodNote(
        "Validity checks",
        f"sensor triads at rest against the site's Earth references {ctx.cite(DATA_VALIDITY)}",
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("validity_checks", method=validity_method))
    register(ReportDef("window_checks", method=validity_method))

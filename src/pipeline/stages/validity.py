"""Built-in plugin: validity checks of raw sensor data (DOMAIN.md §3) as pipeline stages.

The site (latitude, longitude, elevation, survey date) comes from the well metadata; the
geomagnetic reference from the model chosen in the options.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import pyarrow as pa

from pipeline.hookspecs import hookimpl
from pipeline.qc.checks import QcOptions, drop_stations, site_from_well, station_checks
from pipeline.qc.tables import MagneticAnomalies, QcResults, QcSummary
from pipeline.qc.windows import anomaly_intervals, window_checks
from pipeline.registry import StageContext, StageDef
from pipeline.tables import PositionReadings, RawSamples


def station_stage(
    inputs: Mapping[str, pa.Table], params: QcOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Check every station × frame position; the readings of dropped stations are removed."""
    readings, samples = inputs["readings"], inputs.get("samples")
    site = site_from_well(ctx.well, field=_has_field(samples))
    qc, summary = station_checks(readings, site, params, samples=samples)
    return {"qc": qc, "summary": summary, "readings": drop_stations(readings, summary)}


def window_stage(
    inputs: Mapping[str, pa.Table], params: QcOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Check continuous samples on sliding windows; list magnetic anomaly intervals."""
    samples = inputs["samples"]
    qc = window_checks(samples, site_from_well(ctx.well, field=_has_field(samples)), params)
    return {"qc": qc, "anomalies": anomaly_intervals(qc)}


def _has_field(samples: pa.Table | None) -> bool:
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
        )
    )

"""Built-in plugin: gyrocompassing stages (raw samples → position readings → stations)."""

from __future__ import annotations

import functools
import warnings
from collections import Counter
from collections.abc import Callable, Mapping

import numpy as np
import pyarrow as pa

from pipeline.earth.site import SiteParams, resolve_site
from pipeline.errors import GyropipeError, SurveyCheckWarning
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.readings import ReadingOptions
from pipeline.gyrocompass.readings_stream import stream_position_readings
from pipeline.gyrocompass.recording_end import dropped_warning, recording_end
from pipeline.gyrocompass.solve import compass
from pipeline.gyrocompass.stops import unread_stops
from pipeline.gyrocompass.systematic import ToolErrors
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.sim.sensors import compass_errors, tool_preset
from pipeline.streams import TableStream
from pipeline.tables import CompassRejects, CompassStations, PositionReadings, RawSamples
from pipeline.uncertainty.engine import find_model
from pipeline.well import WellMetadata


class CompassParams(CompassOptions, SiteParams):
    """Parameters of the compass stage: the site latitude (if not the well's) and the
    compassing options."""


def readings_stage(
    inputs: Mapping[str, TableStream], params: ReadingOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """Average each station's frame positions (transients trimmed) from the streamed
    samples, a station at a time; no samples, no readings. A frame position the recording
    ended in too soon to average, and a stop the tool made without a dwell to read
    (:mod:`~pipeline.gyrocompass.stops`), are warned of (:class:`SurveyCheckWarning`)."""
    readings = stream_position_readings(inputs["samples"], params)
    end = recording_end(readings)
    said = [dropped_warning(end, params.min_dwell)] if end is not None and not end.kept else []
    said += [
        f"{stop.reason()}; it is numbered station {stop.station} and has no reading"
        for stop in unread_stops(readings)
    ]
    for text in said:
        warnings.warn(f"stage {ctx.stage_id!r}: {text}", SurveyCheckWarning, stacklevel=2)
    return {"readings": readings}


def compass_stage(
    inputs: Mapping[str, pa.Table], params: CompassParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Solve inclination, azimuth and toolfaces of every station. No readings give no
    stations; readings of which every station is rejected are an error giving the reasons
    (else they would be found only in ``rejects`` after a later stage's failure)."""
    readings = inputs["readings"]
    if readings.num_rows == 0:
        return {
            "stations": CompassStations.compiled().schema(north_reference="true").empty_table(),
            "rejects": CompassRejects.compiled().schema().empty_table(),
        }
    site = resolve_site(ctx.well, stage="compass", latitude=params.latitude, north_seeking=True)
    stations, rejects = compass(
        readings, site.latitude, params.with_defaults(tool_errors(ctx.well))
    )
    if stations.num_rows == 0:
        raise AllRejectedError(rejects)
    return {"stations": stations, "rejects": rejects}


UNDECLARED_TOOL = "GYRO-NS"
"""The tool model whose magnitudes a tool that declares none is given (ISCWSA/OWSG GYRO-NS,
Torkildsen et al., SPE 90408): read from its file, not restated here."""


def model_errors(name: str) -> ToolErrors:
    """The compassing-relevant magnitudes of a shipped tool model's terms: the transverse
    gyros' g-dependent error (GXY-G1) and the accelerometers' bias, misalignment and scale
    factor (AXYZ-ZB, AXYZ-MIS, AXYZ-SF), in :class:`ToolErrors`' units."""
    sigma = {term.name: term.sigma for term in find_model(name).terms}  # SI
    return ToolErrors(
        g_sensitivity=float(np.degrees(sigma["GXY-G1"])),  # rad/h/g → (°/h)/g
        acc_bias=sigma["AXYZ-ZB"],  # m/s²
        acc_misalignment=sigma["AXYZ-MIS"] * 1e3,  # rad → mrad
        acc_scale_factor=sigma["AXYZ-SF"] * 1e6,  # → ppm
    )


def tool_errors(well: WellMetadata) -> ToolErrors:
    """The error magnitudes of the well's survey tool that compassing cannot remove: those
    of its entry in the tool catalogue (``tool_preset``, set by the simulator; overrides of a
    plan are not known here: set the stage parameters), else those of the tool model
    :data:`UNDECLARED_TOOL`.
    A ``tool_preset`` the catalogue lacks is a ValueError listing the presets."""
    if well.tool_preset is None:
        return model_errors(UNDECLARED_TOOL)
    try:
        return _preset_errors(well.tool_preset)
    except ValueError as exc:
        raise ValueError(f"the well metadata's tool_preset: {exc}") from None


@functools.lru_cache(maxsize=16)
def _preset_errors(name: str) -> ToolErrors:
    """:func:`~pipeline.sim.sensors.compass_errors` of the catalogue's preset ``name``,
    once per process (a preset is a constant; the result is frozen)."""
    return compass_errors(tool_preset(name))


class AllRejectedError(GyropipeError):
    """Compassing rejected every station: the reasons, with how many stations each (the
    first few; a units mistake gives every station its own numbers)."""

    SHOWN = 3

    def __init__(self, rejects: pa.Table) -> None:
        self.rejects = rejects
        reasons = Counter(rejects.column("reason").to_pylist()).most_common()
        shown = "; ".join(f"{count}× {reason}" for reason, count in reasons[: self.SHOWN])
        more = f"; and {len(reasons) - self.SHOWN} more" if len(reasons) > self.SHOWN else ""
        super().__init__(
            f"compass rejected all {rejects.num_rows} stations, so its stations table would "
            f"have no rows: {shown}{more}"
        )


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
            streamed_inputs=frozenset({"samples"}),
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
            params=CompassParams,
        )
    )


def azimuth_words(method: str) -> str:
    """How the report words an ``azimuth_method``."""
    return {
        "ml": "maximum-likelihood azimuth",
        "auto": "azimuth by the better-conditioned closed form",
        "sine": "azimuth from the right-side Earth rate",
        "atan2": "azimuth from the high- and right-side Earth rates",
    }.get(method, method)


def compass_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """Gyrocompassing in the report: the multi-position paper, the azimuth solution and
    where the gyro toolface takes over."""
    from pipeline.reports.literature import MULTI_POSITION

    return MethodNote(
        "Gyrocompassing",
        f"multi-position least squares {ctx.cite(MULTI_POSITION)}, "
        f"{azimuth_words(str(stage.params.get('azimuth_method', '?')))}, gyro toolface "
        f"below {stage.params.get('vertical_below', '?')}° inclination",
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("compass", method=compass_method))

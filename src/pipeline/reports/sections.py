"""Report parts shared by the survey and calibration reports: the well header, the method
statements read from the run's stages, and the provenance section."""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import GyropipeError
from pipeline.registry import Provenance, StageSetup
from pipeline.reports.document import (
    Block,
    Column,
    Fields,
    Paragraph,
    Section,
    Table,
    fmt,
    items,
)
from pipeline.reports.literature import (
    DATA_VALIDITY,
    DRIFT_CALIBRATION,
    ERROR_MODEL,
    GYRO_ERROR_MODEL,
    MULTI_POSITION,
    Citations,
)
from pipeline.uncertainty.engine import ModelCatalogue, find_model
from pipeline.well import WellMetadata

NORTH_NAMES = {"true": "true north", "grid": "grid north", "magnetic": "magnetic north"}
UNIT_LABELS = {"deg": "°", "deg/30m": "°/30 m", "deg/h": "°/h", "deg/min": "°/min", "m2": "m²"}


def north_label(table: pa.Table, column: str) -> str:
    """'true north', 'grid north' or 'magnetic north' of an azimuth column."""
    raw = (table.schema.field(column).metadata or {}).get(NORTH_KEY, b"").decode()
    return NORTH_NAMES.get(raw, raw or "unstated north")


def unit_label(table: pa.Table, column: str) -> str:
    """The unit of a column as printed in a report (``deg`` → ``°``)."""
    raw: str = (table.schema.field(column).metadata or {}).get(UNIT_KEY, b"").decode()
    return UNIT_LABELS.get(raw, raw)


def run_time(provenance: Provenance) -> str:
    return provenance.started.strftime("%Y-%m-%d %H:%M UTC")


def footer(provenance: Provenance) -> str:
    """The provenance line printed on every page."""
    return (
        f"gyropipe {provenance.gyropipe} · pipeline {provenance.pipeline} "
        f"{provenance.pipeline_version} (sha256 {provenance.pipeline_sha256[:12]}) · "
        f"run {run_time(provenance)}"
    )


def _angle(value: float | None, positive: str, negative: str) -> str | None:
    if value is None:
        return None
    return f"{abs(value):.6f}° {positive if value >= 0 else negative}"


def site_fields(well: WellMetadata) -> Fields:
    """Well name, identifiers and wellhead position."""
    elevation = None
    if well.elevation is not None:
        ref = f" ({well.depth_reference})" if well.depth_reference else ""
        elevation = f"{fmt(well.elevation)} m above MSL{ref}"
    return Fields(
        "Well and site",
        items(
            [
                ("Well", well.well),
                ("UWI", well.uwi),
                ("Field", well.field),
                ("Operator", well.company),
                ("Service company", well.service_company),
                ("Latitude", _angle(well.latitude, "N", "S")),
                ("Longitude", _angle(well.longitude, "E", "W")),
                ("Depth reference", None if elevation else well.depth_reference),
                ("Reference elevation", elevation),
            ]
        ),
    )


def tool_fields(well: WellMetadata, provenance: Provenance, extra: list[tuple[str, str]]) -> Fields:
    """Tool and run: tool type and serial, survey date, pipeline, run time, ``extra``."""
    return Fields(
        "Tool and run",
        items(
            [
                ("Tool type", well.tool_type),
                ("Tool serial", well.tool_serial),
                ("Survey date", well.survey_date.isoformat() if well.survey_date else None),
                *extra,
                ("Pipeline", f"{provenance.pipeline} {provenance.pipeline_version}"),
                ("Processed", run_time(provenance)),
            ]
        ),
    )


def _param(stage: StageSetup, name: str, default: Any = "?") -> Any:
    return stage.params.get(name, default)


def _error_model(model: str, catalogue: ModelCatalogue) -> tuple[str, bool]:
    """The title a tool model's file gives it (the name if the file cannot be found now) and
    whether it is a gyro model (it reads the latitude)."""
    try:
        tool = find_model(model, catalogue)
    except (KeyError, GyropipeError):
        return Path(model).name, False
    return tool.title or tool.name, "latitude" in tool.needs


AZIMUTH_METHODS = {
    "ml": "maximum-likelihood azimuth",
    "auto": "azimuth by the better-conditioned closed form",
    "sine": "azimuth from the right-side Earth rate",
    "atan2": "azimuth from the high- and right-side Earth rates",
}
DRIFT_SOURCES = {
    "tie_in": "the misclosure at the tie-in station",
    "calibration": "the instrument's drift calibration",
    "given": "a given rate",
    "auto": "the best available source",
}


def _describe(
    stage: StageSetup, cite: Callable[[str], str], catalogue: ModelCatalogue
) -> tuple[str, str] | None:
    """What a known processing stage says about the method, as (label, statement), its
    published method cited through ``cite`` (tool models found in ``catalogue``)."""
    match stage.uses:
        case "minimum_curvature":
            return "Survey calculation", "minimum curvature"
        case "survey_method":
            return "Survey calculation", str(_param(stage, "method")).replace("_", " ")
        case "compass":
            method = str(_param(stage, "azimuth_method"))
            return (
                "Gyrocompassing",
                f"multi-position least squares {cite(MULTI_POSITION)}, "
                f"{AZIMUTH_METHODS.get(method, method)}, gyro toolface below "
                f"{_param(stage, 'vertical_below')}° inclination",
            )
        case "integrate_continuous":
            return (
                "Continuous survey",
                "azimuth rate integrated from a compassing stop and closed on the other "
                "stop where both give an azimuth (the QC section says where not), stations "
                f"every {_param(stage, 'spacing')} m",
            )
        case "position_uncertainty":
            confidence = float(_param(stage, "confidence", 0.0)) * 100
            title, gyro = _error_model(str(_param(stage, "model")), catalogue)
            method = f"{title} error model propagated as in {cite(ERROR_MODEL)}"
            also = f" with the gyro terms of {cite(GYRO_ERROR_MODEL)}" if gyro else ""
            return "Position uncertainty", f"{method}{also}, ellipses at {confidence:g} %"
        case "definitive_survey":
            confidence = float(_param(stage, "confidence", 0.0)) * 100
            return (
                "Definitive survey",
                "runs tied at their first station to the survey above; each run's error "
                f"model propagated as in {cite(ERROR_MODEL)} with its systematic errors "
                "correlated within the run, the tie point's uncertainty carried below it, "
                f"ellipses at {confidence:g} %",
            )
        case "acceptance_gates":
            return (
                "Acceptance",
                f"in-run against out-run: inclination within {_param(stage, 'inc_tolerance')}°, "
                f"azimuth within {_param(stage, 'azi_tolerance')}° at inclination ≥ "
                f"{_param(stage, 'low_inclination')}° and {_param(stage, 'azi_tolerance_low')}° "
                f"below, depth within {_param(stage, 'depth_tolerance')} m, at least "
                f"{_param(stage, 'min_stations')} stations",
            )
        case "correct_drift":
            source = str(_param(stage, "source"))
            return (
                "Drift correction",
                f"A − ω·(t − t₀), rate from {DRIFT_SOURCES.get(source, source)}",
            )
        case "calibrate_drift":
            return (
                "Drift calibration",
                f"drift from the means of the calibration series {cite(DRIFT_CALIBRATION)}, "
                f"estimate used: {_param(stage, 'use')}, linearity test at "
                f"α = {_param(stage, 'alpha')}",
            )
        case "north_reference":
            return "North reference conversion", f"to {_param(stage, 'target')} north"
        case "validity_checks" | "window_checks":
            return (
                "Validity checks",
                f"sensor triads at rest against the site's Earth references {cite(DATA_VALIDITY)}",
            )
    return None


def method_items(provenance: Provenance, citations: Citations) -> list[tuple[str, str]]:
    """Method statements of the run's known stages (first stage of each kind), their
    methods' papers cited in ``citations``."""
    found: dict[str, str] = {}
    catalogue = ModelCatalogue.of(provenance.tool_models)
    for stage in provenance.stages:
        probe = _describe(stage, lambda work: "", catalogue)  # cite only what is printed
        if probe is None or probe[0] in found:
            continue
        described = _describe(stage, citations.cite, catalogue)
        if described is not None:
            found[described[0]] = described[1]
    return list(found.items())


def references(table: pa.Table | None) -> list[tuple[str, str]]:
    """Reference models recorded by the validity checks in a QC table's metadata."""
    if table is None:
        return []
    raw = (table.schema.metadata or {}).get(b"gyropipe.references")
    if raw is None:
        return []
    names = {"earth_rate": "Earth rate", "gravity": "Normal gravity", "geomagnetic": "Geomagnetic"}
    recorded: Mapping[str, str] = json.loads(raw)
    return [(names.get(k, k), str(v)) for k, v in recorded.items()]


def _params_text(params: Mapping[str, Any]) -> str:
    return ", ".join(f"{k}={json.dumps(v, ensure_ascii=False)}" for k, v in params.items())


def provenance_section(provenance: Provenance) -> Section:
    """Pipeline, software, input files and every stage with its parameters."""
    run = Fields(
        "Run",
        items(
            [
                ("Pipeline", f"{provenance.pipeline} {provenance.pipeline_version}"),
                ("Pipeline file", provenance.pipeline_file),
                ("Pipeline sha256", provenance.pipeline_sha256),
                ("gyropipe", provenance.gyropipe),
                ("Run started", provenance.started.isoformat(timespec="seconds")),
            ]
        ),
    )
    inputs = Table(
        "Input files",
        (
            Column("Input", align="left"),
            Column("File", align="left", wrap=True),
            Column("Bytes"),
            Column("SHA-256", align="left", wrap=True),
        ),
        tuple((name, f.path, str(f.bytes), f.sha256) for name, f in provenance.inputs.items()),
        kind="inputs",
    )
    stages = Table(
        "Processing stages",
        (
            Column("Stage", align="left"),
            Column("Uses", align="left"),
            Column("Plugin", align="left"),
            Column("Parameters", align="left", wrap=True),
        ),
        tuple((s.id, s.uses, s.plugin, _params_text(s.params) or "—") for s in provenance.stages),
        kind="stages",
    )
    plugins = ", ".join(f"{n} {v}" for n, v in provenance.plugins.items())
    blocks: list[Block] = [run]
    blocks += [inputs] if inputs.rows else []
    blocks += [stages] if stages.rows else []
    blocks += [Paragraph(f"Plugins loaded: {plugins}.")] if plugins else []
    return Section("Provenance", tuple(blocks), key="provenance")

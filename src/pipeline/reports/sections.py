"""Report parts shared by the survey and calibration reports: the well header, the tool
model's title, and the provenance section. (What each stage states about its method is its
own: its report part, :mod:`pipeline.reports.parts`.)"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa

from pipeline.contracts import NORTH_KEY, UNIT_KEY
from pipeline.errors import GyropipeError
from pipeline.registry import Provenance
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


def bearing(value: float | None) -> str | None:
    """A correction east (+) or west (−) of true north as a report states it, deg:
    ``14.50° E``, ``1.80° W``; ``0.00°``."""
    if value is None:
        return None
    text = fmt(abs(value))
    return f"{text}°" if text == fmt(0.0) else f"{text}° {'E' if value > 0 else 'W'}"


def _map_position(well: WellMetadata) -> str | None:
    """The wellhead's map coordinates, m (either given alone is shown alone)."""
    parts = [
        f"{axis} {fmt(value)} m"
        for axis, value in (("E", well.easting), ("N", well.northing))
        if value is not None
    ]
    return ", ".join(parts) or None


def site_fields(well: WellMetadata) -> Fields:
    """Well name, identifiers, wellhead position (geodetic and map), depth datum and the
    site's magnetic declination and grid convergence."""
    elevation = None if well.elevation is None else f"{fmt(well.elevation)} m above MSL"
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
                ("Coordinate system", well.crs),
                ("Wellhead map position", _map_position(well)),
                ("Depth datum", well.depth_reference),
                ("Datum elevation", elevation),
                ("Magnetic declination", bearing(well.declination)),
                ("Grid convergence", bearing(well.grid_convergence)),
            ]
        ),
    )


def tool_fields(well: WellMetadata, provenance: Provenance, extra: list[tuple[str, str]]) -> Fields:
    """Tool and run: survey type, tool name, type and serial, run and job number, survey
    date, ``extra``, processing time (the pipeline is named in the provenance appendix)."""
    return Fields(
        "Tool and run",
        items(
            [
                ("Survey type", well.survey_type),
                ("Tool", well.tool_name),
                ("Tool type", well.tool_type),
                ("Tool serial", well.tool_serial),
                ("Run number", well.run_number),
                ("Job number", well.job_number),
                ("Survey date", well.survey_dates()),
                *extra,
                ("Processed", run_time(provenance)),
            ]
        ),
    )


def survey_tool(traj: pa.Table, well: WellMetadata) -> str | None:
    """The survey tool of ``traj``: each run's (``GYRO-1: gyro; MWD-1: MWD``) when its
    stations come from several runs (``several; see the program`` when a run names more
    than one), else the well's ``tool_type``."""
    names = traj.schema.names
    runs = traj.column("run").to_pylist() if "run" in names else []
    if len(set(runs)) < 2 or "tool_type" not in names:
        return well.tool_type
    pairs = dict.fromkeys(zip(runs, traj.column("tool_type").to_pylist(), strict=True))
    if len(pairs) > len(set(runs)):
        return "several; see the program"
    return "; ".join(f"{run}: {tool or 'not stated'}" for run, tool in pairs)


def error_model(model: str, catalogue: ModelCatalogue) -> tuple[str, bool]:
    """The title a tool model's file gives it (the name if the file cannot be found now) and
    whether it is a gyro model (it reads the latitude)."""
    try:
        tool = find_model(model, catalogue)
    except (KeyError, GyropipeError):
        return Path(model).name, False
    return tool.title or tool.name, "latitude" in tool.needs


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
    """Pipeline, software, input files, the files read through parameters by the stages
    before the report (``run.json``'s ``parameter_inputs``), and every stage with its
    parameters."""
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
    read = Table(
        "Files read through parameters",
        (
            Column("Stage", align="left"),
            Column("Parameter", align="left"),
            Column("File", align="left", wrap=True),
            Column("SHA-256", align="left", wrap=True),
        ),
        tuple((f.stage, f.param, f"{f.path} ({f.what})", f.sha256) for f in provenance.read),
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
    blocks += [read] if read.rows else []
    blocks += [stages] if stages.rows else []
    blocks += [Paragraph(f"Plugins loaded: {plugins}.")] if plugins else []
    return Section("Appendix: provenance", tuple(blocks), key="provenance")


SIGNERS = ("Prepared by", "Checked by", "Approved by")
BLANK = "_" * 20
"""A blank line to write or sign on."""


def signoff_section() -> Section:
    """The sign-off block: a row each for preparer, checker and approver with blank name,
    signature and date cells."""
    table = Table(
        "Prepared, checked and approved",
        (
            Column("Role", align="left"),
            Column("Name", align="left"),
            Column("Signature", align="left"),
            Column("Date", align="left"),
        ),
        tuple((role, BLANK, BLANK, BLANK) for role in SIGNERS),
        kind="signoff",
    )
    return Section("Sign-off", (table,), key="signoff")

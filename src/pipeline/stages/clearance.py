"""Built-in plugin: anti-collision — the ``read_offsets`` stage (a manifest of offset wells)
and the ``clearance`` stage (ISCWSA separation factor of a reference well against them)."""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, model_validator

from pipeline.anticollision.models import (
    ModelSite,
    needs,
    resolve_model,
    well_covariance,
)
from pipeline.anticollision.rule import RuleLimits, SeparationRule
from pipeline.anticollision.scan import Well, scan
from pipeline.anticollision.tables import Clearance, OffsetWells, rule_of, with_rule
from pipeline.earth.magnetic import AppliedMagnetic, applied_magnetic
from pipeline.earth.site import MagneticReference
from pipeline.errors import EmptyTableError, InputFileError
from pipeline.hashing import sha256_file
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef, pipeline_input
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages import toolmodels
from pipeline.survey.mincurve import minimum_curvature
from pipeline.survey.north import convert_azimuth
from pipeline.survey.stations import north_reference_of, survey_offsets
from pipeline.tables import Stations
from pipeline.uncertainty.engine import ModelCatalogue
from pipeline.well import Latitude, WellMetadata

STAGE = "clearance"


class ClearanceParams(BaseModel):
    """Parameters of the clearance stage (the rule's defaults are the ISCWSA rule's)."""

    model_config = ConfigDict(extra="forbid")
    reference_model: str = Field(
        "GYRO-NS",
        description="tool model of the reference survey: the name of a tool model "
        "(`gyropipe models` lists the shipped ones and those plugins add)",
    )
    reference_hole_diameter: float = Field(
        gt=0, description="hole or casing diameter of the reference well, m (no default)"
    )
    k: float = Field(3.5, gt=0, description="scaling factor of the combined σ")
    sigma_pa: float = Field(0.5, ge=0, description="1σ project-ahead uncertainty, m")
    surface_margin: float = Field(0.3, ge=0, description="surface margin S_m, m")
    stop: float = Field(1.0, description="separation factor below which the level is fail")
    caution: float = Field(1.5, description="separation factor below which the level is warn")
    latitude: Latitude | None = Field(
        None, description="latitude, deg (gyro models); default: the well's"
    )
    magnetic: MagneticReference | None = Field(
        None,
        description="geomagnetic reference at the site (MWD models); default: the well "
        "metadata's magnetic_field, magnetic_dip and declination, else WMM2025 at the well's "
        "latitude, longitude, elevation and survey date",
    )

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo) -> ClearanceParams:
        try:
            self.reference_model = resolve_model(self.reference_model, toolmodels.validating(info))
        except ValueError as exc:
            raise ValueError(
                toolmodels.disabled_message(self.reference_model, toolmodels.registry_of(info))
                or exc
            ) from None
        if self.caution < self.stop:
            raise ValueError(f"caution ({self.caution}) must not be below stop ({self.stop})")
        return self


class OffsetsReadParams(BaseModel):
    """Parameters of the read_offsets stage."""

    model_config = ConfigDict(extra="forbid")
    input: str = pipeline_input("offsets", "name of the pipeline input holding the manifest")
    reader: str = Field("auto", description="reader of the stations files, or 'auto'")


def read_offsets(
    inputs: Mapping[str, pa.Table], params: OffsetsReadParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Manifest → the offset wells (one row each) and their stations (``survey`` = well id)."""

    def read(path: Path) -> tuple[pa.Table, WellMetadata]:
        return ctx.read_file(path, "stations", reader=params.reader)

    wells, stations = offset_tables(
        ctx.input_path(params.input), read, ctx.well, toolmodels.of_run(ctx)
    )
    return {"wells": wells, "stations": stations}


def offset_tables(
    manifest: Path,
    read: Callable[[Path], tuple[pa.Table, WellMetadata]],
    well: WellMetadata,
    catalogue: ModelCatalogue,
) -> tuple[pa.Table, pa.Table]:
    """The offset wells a manifest lists (:mod:`pipeline.io.offset_manifest`; their tool
    models among ``catalogue``'s) and their stations, read by ``read``, every azimuth
    referred to the first file's north (each file's own header, else ``well``, gives the
    corrections)."""
    from pipeline.io.offset_manifest import read_offset_manifest

    entries = read_offset_manifest(manifest, functools.partial(resolve_model, catalogue=catalogue))
    tables = []
    north: str | None = None
    for entry in entries:
        if not entry.file.is_file():
            raise InputFileError(manifest, f"no stations file {entry.file}", entry.line, "file")
        table, header = read(entry.file)
        if table.num_rows < 2:
            raise InputFileError(
                entry.file, f"offset well {entry.well_id!r}: fewer than 2 stations"
            )
        azi = table.column("azi").to_numpy(zero_copy_only=False)
        own = north_reference_of(table, "azi")
        north = north or own
        known = well.merged(header)
        converted, _ = convert_azimuth(
            azi,
            own,
            north,  # type: ignore[arg-type]
            convergence_deg=known.convergence_for(own),
            declination_deg=known.declination,
        )
        tables.append((entry.well_id, table, np.where(np.isnan(azi), np.nan, converted)))
    assert north is not None
    stations = Stations.compiled().make_table(
        {
            "survey": [w for w, t, _ in tables for _ in range(t.num_rows)],
            "md": np.concatenate([t.column("md").to_numpy() for _, t, _ in tables]),
            "inc": np.concatenate([t.column("inc").to_numpy() for _, t, _ in tables]),
            "azi": np.concatenate([a for _, _, a in tables]),
        },
        north_reference=north,
    )
    wells = OffsetWells.compiled().make_table(
        {
            "offset": [e.well_id for e in entries],
            "model": [e.model for e in entries],
            "hole_diameter": [e.hole_diameter for e in entries],
            "north": [e.north for e in entries],
            "east": [e.east for e in entries],
            "tvd": [e.tvd for e in entries],
            "source": [str(e.file) for e in entries],
            "sha256": [sha256_file(e.file) for e in entries],
        }
    )
    return wells, stations


def _site(
    params: ClearanceParams, well: WellMetadata, models: set[str], catalogue: ModelCatalogue
) -> tuple[ModelSite, AppliedMagnetic | None]:
    """What the models in use need of the site, from the params or the well metadata, and
    the geomagnetic reference applied (None: no model needs one)."""
    from pipeline.earth.site import resolve_site

    latitude = None
    wanted = frozenset().union(*(needs(m, catalogue) for m in models))
    if "latitude" in wanted:
        latitude = resolve_site(
            well, stage=STAGE, latitude=params.latitude, north_seeking=True
        ).latitude
    applied = None
    if "magnetic" in wanted:
        applied = applied_magnetic(params.magnetic, well, stage=STAGE)
    magnetic = applied.reference if applied is not None else params.magnetic
    return ModelSite(latitude=latitude, magnetic=magnetic), applied


class _Frame:
    """The scan's frame: the reference's north; azimuths to true for the models and the
    models' true-north covariances rotated into the frame."""

    def __init__(
        self,
        north: str,
        well: WellMetadata,
        magnetic: MagneticReference | None,
        catalogue: ModelCatalogue,
    ):
        self.north = north
        self.catalogue = catalogue
        self.convergence = well.convergence_for(north)
        self.declination = (
            well.declination
            if well.declination is not None
            else (magnetic.declination if magnetic is not None else None)
        )
        zero, _ = convert_azimuth(0.0, "true", north, **self._corrections())  # type: ignore[arg-type]
        self.delta = np.radians(-float(zero))  # A_frame = A_true − δ

    def _corrections(self) -> dict[str, Any]:
        return {"convergence_deg": self.convergence, "declination_deg": self.declination}

    def azimuths(self, azi_deg: np.ndarray, north: str) -> np.ndarray:
        """Azimuths (deg, ``north``) in the frame's north, radians; NaN kept."""
        out, _ = convert_azimuth(azi_deg, north, self.north, **self._corrections())  # type: ignore[arg-type]
        return np.where(np.isnan(azi_deg), np.nan, np.radians(out))

    def covariance(
        self,
        model: str,
        md: np.ndarray,
        inc: np.ndarray,
        azi: np.ndarray,
        tvd: np.ndarray,
        site: ModelSite,
    ) -> np.ndarray:
        """The model's covariance (frame azimuths in rad) in the frame."""
        cov = well_covariance(model, md, inc, azi + self.delta, tvd, site, self.catalogue)
        c, s = np.cos(self.delta), np.sin(self.delta)
        rot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        out: np.ndarray = rot @ cov @ rot.T
        return out


def _well(
    name: str,
    table: pa.Table,
    frame: _Frame,
    model: str,
    diameter: float,
    tie: tuple[float, float, float | None],
    site: ModelSite,
) -> Well:
    md = table.column("md").to_numpy(zero_copy_only=False).astype(np.float64)
    inc = np.radians(table.column("inc").to_numpy(zero_copy_only=False))
    azi_deg = table.column("azi").to_numpy(zero_copy_only=False).astype(np.float64)
    azi = frame.azimuths(azi_deg, north_reference_of(table, "azi"))
    start = (tie[0], tie[1], float(md[0]) if tie[2] is None else tie[2])
    tvd = minimum_curvature(md, inc, azi, tie_tvd=start[2]).tvd
    cov = frame.covariance(model, md, inc, azi, tvd, site)
    return Well(name, md, inc, azi, start, cov, 0.5 * diameter)


def clearance(
    inputs: Mapping[str, pa.Table], params: ClearanceParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Reference stations, offset stations and offset wells → the clearance table."""
    reference, stations, wells = inputs["reference"], inputs["offsets"], inputs["wells"]
    for name, table in (("reference", reference), ("offsets", stations), ("wells", wells)):
        if table.num_rows == 0:
            raise EmptyTableError(name, "no wells to scan")
    catalogue = toolmodels.of_run(ctx)
    listed = wells.to_pylist()
    for w in listed:
        w["model"] = resolve_model(w["model"], catalogue)
    models = {params.reference_model, *(w["model"] for w in listed)}
    site, applied = _site(params, ctx.well, models, catalogue)
    frame = _Frame(north_reference_of(reference, "azi"), ctx.well, site.magnetic, catalogue)
    ref = _well(
        "reference",
        reference,
        frame,
        params.reference_model,
        params.reference_hole_diameter,
        (0.0, 0.0, None),
        site,
    )
    offsets = survey_offsets(stations)
    ids = stations.column("survey").to_pylist() if "survey" in stations.column_names else None
    blocks = {
        (ids[lo] if ids is not None else ""): stations.slice(lo, hi - lo)
        for lo, hi in itertools.pairwise(offsets)
    }
    scanned = []
    for w in listed:
        block = blocks.get(w["offset"])
        if block is None or block.num_rows < 2:
            raise ValueError(
                f"offset well {w['offset']!r}: {'no' if block is None else 'fewer than 2'} "
                "stations in the offsets table"
            )
        tie = (w["north"], w["east"], w["tvd"])
        scanned.append(_well(w["offset"], block, frame, w["model"], w["hole_diameter"], tie, site))
    result = scan(
        ref,
        scanned,
        SeparationRule(k=params.k, sigma_pa=params.sigma_pa, surface_margin=params.surface_margin),
        RuleLimits(stop=params.stop, caution=params.caution),
    )
    table = Clearance.compiled().make_table(
        {
            "offset": result.offset.tolist(),
            "md": result.md,
            "offset_md": result.offset_md,
            "distance": result.distance,
            "sigma_s": result.sigma_s,
            "sf": result.sf,
            "level": result.level.tolist(),
            "toolface": result.toolface,
        }
    )
    rule = {
        **params.model_dump(mode="json", exclude={"latitude", "magnetic"}),
        **({"magnetic": applied.model_dump(mode="json")} if applied is not None else {}),
        "wells": {
            w["offset"]: {
                **{k: w[k] for k in ("model", "hole_diameter", "source", "sha256") if w.get(k)},
                **{k: w[k] for k in ("north", "east", "tvd")},  # the slot and datum (tvd null)
            }
            for w in listed
        },
    }
    return {"clearance": with_rule(table, rule)}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="read_offsets",
            func=read_offsets,
            description="Read a manifest of offset wells (id, stations file, tool model, hole "
            "size, slot position) and their stations files.",
            outputs={"wells": OffsetWells, "stations": Stations},
            params=OffsetsReadParams,
        )
    )
    register(
        StageDef(
            name="clearance",
            func=clearance,
            description="Anti-collision scan: the ISCWSA separation factor of every reference "
            "station against the closest point of each offset well, with pass/warn/fail levels.",
            inputs={"reference": Stations, "offsets": Stations, "wells": OffsetWells},
            outputs={"clearance": Clearance},
            params=ClearanceParams,
        )
    )


def clearance_method(stage: StageSetup, ctx: ReportContext) -> MethodNote | None:
    """The geomagnetic reference the scan's MWD models applied, in the report's method
    (None: no model needed one)."""
    rule = rule_of(ctx.tables["clearance"]) if "clearance" in ctx.tables else {}
    if "magnetic" not in rule:
        return None
    applied = AppliedMagnetic.model_validate(rule["magnetic"])
    return MethodNote("Geomagnetic reference (clearance)", applied.words())


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("clearance", method=clearance_method))

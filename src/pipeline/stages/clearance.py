"""Built-in plugin: anti-collision — the ``read_offsets`` stage (a manifest of offset wells)
and the ``clearance`` stage (ISCWSA separation factor of a reference well against them)."""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, model_validator

from pipeline.anticollision.models import (
    Conventions,
    ModelSite,
    Start,
    TermEffects,
    model_survey,
    needs,
    resolve_model,
    term_effects_of,
)
from pipeline.anticollision.models import well_covariance as model_covariance
from pipeline.anticollision.offset_north import (
    TIE_COLUMNS,
    first_station,
    listed_tie,
    on_the_reference_grid,
    taken_words,
    true_azimuths,
)
from pipeline.anticollision.rule import RuleLimits, SeparationRule
from pipeline.anticollision.scan import Pair, Well, scan_pairs
from pipeline.anticollision.shared import SharedErrors
from pipeline.anticollision.sidetrack import Kickoff, common_point, cut, named_kickoff
from pipeline.anticollision.tables import Clearance, OffsetWells, rule_of, with_rule
from pipeline.earth.magnetic import AppliedMagnetic, applied_magnetic
from pipeline.earth.site import MagneticReference
from pipeline.errors import EmptyTableError, InputFileError, warn_input
from pipeline.hashing import sha256_file
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef, pipeline_input
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages import toolmodels
from pipeline.survey.mincurve import minimum_curvature
from pipeline.survey.north import convert_azimuth, turned_positions
from pipeline.survey.stations import north_reference_of, survey_offsets
from pipeline.survey.tiein import chosen_tie, listed_ties
from pipeline.tables import Stations
from pipeline.uncertainty.engine import (
    ModelCatalogue,
    OutsideValidity,
    OutsideValidityError,
    find_model,
)
from pipeline.uncertainty.frames import listing_north
from pipeline.uncertainty.tieon import TieOnRecord, outside_ties, warn_missing, with_tie_on
from pipeline.well import AGREEING, Latitude, WellMetadata, well_of

if TYPE_CHECKING:
    from pipeline.io.offset_manifest import OffsetEntry

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
    first_station_exact: bool = Field(
        True,
        description="each survey's first station has zero covariance (the ISCWSA clearance "
        "set's convention: the surface position exact); false: the surface tie-on's depth "
        "reference σ there",
    )
    level_on: Literal["course", "station"] = Field(
        "course",
        description="what the level is decided on: `course` the least SF along the course "
        "from each reference station to the next (sf_between), `station` the SF at the station",
    )
    vertical_azimuth: Literal["north", "given"] = Field(
        "north",
        description="azimuth of a vertical station in the error models: `north` 0° (the "
        "ISCWSA clearance set's and welleng's), `given` the station's own (an undefined one: "
        "the azimuth the hole leaves vertical in)",
    )
    sidetrack: Literal["zeroed", "shared"] = Field(
        "zeroed",
        description="a sidetrack's covariance below its common point: `zeroed` both wells' "
        "uncertainty zeroed there and independent below (the ISCWSA clearance set's rule); "
        "`shared` the exact relative error, the trunk's errors cancelling and each run's "
        "terms independent (less conservative; the kick-off must be a reference station)",
    )
    common_tolerance: float = Field(
        0.1,
        gt=0,
        description="an offset whose first station(s) lie within this distance (m) of the "
        "reference path shares its hole there: a sidetrack, scanned from the deepest common point",
    )
    latitude: Latitude | None = Field(
        None, description="latitude, deg (gyro models); default: the well's"
    )
    magnetic: MagneticReference | None = Field(
        None,
        description="geomagnetic reference at the site (MWD models); default: the well "
        "metadata's magnetic_field, magnetic_dip and declination, else WMM2025 at the well's "
        "latitude, longitude, elevation and survey date",
    )
    outside_validity: OutsideValidity = Field(
        "refuse",
        description="a reference or offset station outside its tool model's range: refuse "
        "(an error naming the well and station), or flag (that well's σ NaN from it down; SF "
        "NaN, level fail, and an outside_validity column)",
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
        ctx.input_path(params.input),
        read,
        ctx.well,
        toolmodels.of_run(ctx),
        functools.partial(ctx.record_file, param="input", what="offset file"),
    )
    return {"wells": wells, "stations": stations}


def _agreed(
    manifest: Path, entry: OffsetEntry, name: str, field: str, own: float | None
) -> float | None:
    """An offset well's correction ``name`` (deg; well ``field``): its file's (``own``) or
    the manifest's; both given must agree, within :data:`~pipeline.well.AGREEING`'s spread
    for ``field`` (the same 3° in rad and in deg)."""
    given: float | None = getattr(entry, name)
    if given is not None and own is not None and abs(given - own) > AGREEING[field]:
        raise InputFileError(
            manifest,
            f"offset well {entry.well_id!r}: the manifest's {name} {given} contradicts the "
            f"file's {own} ({entry.file.name}): give one of them",
            entry.line,
            name,
        )
    return given if given is not None else own


_CORRECTIONS = {
    "magnetic": ("declination", "declination"),
    "grid": ("convergence", "grid_convergence"),
}
"""North reference → the manifest column and the well field of its correction to true north."""


def _true_azimuths(
    manifest: Path,
    entry: OffsetEntry,
    table: pa.Table,
    header: WellMetadata,
    reference: WellMetadata,
) -> tuple[np.ndarray, float, float | None]:
    """An offset well's azimuths referred to true north by its own corrections, its file's
    (``header``) or the manifest's, which must agree (:func:`true_azimuths`; refused naming
    the manifest line, the reference's grid convergence taken with a warning)."""
    north = north_reference_of(table, "azi")
    column, field = _CORRECTIONS.get(north, ("", ""))
    own = header
    if column:  # magnetic or grid azimuths: the correction to true north they need
        stated = header.declination if north == "magnetic" else header.convergence_for("grid")
        value = _agreed(manifest, entry, column, field, stated)
        own = header.merged({field: value}) if value is not None else header
    where = f"offset well {entry.well_id!r} ({entry.file.name})"
    try:
        true, shift, taken = true_azimuths(table, own, reference)
    except ValueError as exc:
        raise InputFileError(
            manifest,
            f"{where}: {exc}: give it in the manifest's {column} column (deg, east positive)",
            entry.line,
            column,
        ) from None
    if taken is not None:
        warn_input(
            manifest,
            f"{where}: {taken_words(taken)} (else give the manifest's convergence column)",
            entry.line,
        )
    return true, shift, taken


def offset_tables(
    manifest: Path,
    read: Callable[[Path], tuple[pa.Table, WellMetadata]],
    reference: WellMetadata,
    catalogue: ModelCatalogue,
    hash_file: Callable[[Path], str] = sha256_file,
) -> tuple[pa.Table, pa.Table]:
    """The offset wells a manifest lists (:mod:`pipeline.io.offset_manifest`; their tool
    models among ``catalogue``'s) and their stations, read by ``read``, every azimuth
    referred to true north by its own well's corrections (:func:`_true_azimuths`;
    ``reference``: the reference well's metadata); each file's ``sha256`` by ``hash_file``
    (a stage's records it: :meth:`StageContext.record_file`), taken before the file is
    read."""
    from pipeline.io.offset_manifest import read_offset_manifest

    entries = read_offset_manifest(manifest, functools.partial(resolve_model, catalogue=catalogue))
    tables = []
    digests = []
    taken: list[float | None] = []  # the reference's grid convergence, where taken
    ties: list[dict[str, float | None]] = []  # the tie-on each file lists, true north
    for entry in entries:
        if not entry.file.is_file():
            raise InputFileError(manifest, f"no stations file {entry.file}", entry.line, "file")
        # hashed before it is read: a file changed after its read is recorded as it was
        # read (a change the next batch sees), not as the outputs never saw it
        digests.append(hash_file(entry.file))
        table, header = read(entry.file)
        if table.num_rows < 2:
            raise InputFileError(
                entry.file, f"offset well {entry.well_id!r}: fewer than 2 stations"
            )
        true, shift, convergence = _true_azimuths(manifest, entry, table, header, reference)
        tables.append((entry.well_id, table, true))
        taken.append(convergence)
        ties.append(listed_tie(table, shift))
    stations = Stations.compiled().make_table(
        {
            "survey": [w for w, t, _ in tables for _ in range(t.num_rows)],
            "md": np.concatenate([t.column("md").to_numpy() for _, t, _ in tables]),
            "inc": np.concatenate([t.column("inc").to_numpy() for _, t, _ in tables]),
            "azi": np.concatenate([a for _, _, a in tables]),
        },
        north_reference="true",
    )
    wells = OffsetWells.compiled().make_table(
        {
            "offset": [e.well_id for e in entries],
            "model": [e.model for e in entries],
            "hole_diameter": [e.hole_diameter for e in entries],
            "north": [e.north for e in entries],
            "east": [e.east for e in entries],
            "tvd": [e.tvd for e in entries],
            "parent": [e.parent for e in entries],
            "kickoff_md": [e.kickoff_md for e in entries],
            "source": [str(e.file) for e in entries],
            "sha256": digests,
            "reference_convergence": taken,
            **{name: [tie[name] for tie in ties] for name in TIE_COLUMNS},
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
        frame = listing_north(north, stage=STAGE, **self._corrections())  # refused without γ / D
        self.delta = np.radians(frame.to_true)  # A_frame = A_true − δ

    def _corrections(self) -> dict[str, Any]:
        return {"convergence_deg": self.convergence, "declination_deg": self.declination}

    def azimuths(self, azi_deg: np.ndarray, north: str) -> np.ndarray:
        """Azimuths (deg, ``north``) in the frame's north, radians; NaN kept."""
        out, _ = convert_azimuth(azi_deg, north, self.north, **self._corrections())  # type: ignore[arg-type]
        return np.where(np.isnan(azi_deg), np.nan, np.radians(out))

    def covariance(
        self,
        model: str,
        survey: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        site: ModelSite,
        start: Start,
        conventions: Conventions,
        outside: OutsideValidity,
    ) -> np.ndarray:
        """The model's covariance of a survey (MD, inclination, frame azimuth rad, TVD) in
        the frame (NaN from a flagged station down)."""
        md, inc, azi, tvd = survey
        cov = model_covariance(
            model,
            md,
            inc,
            azi + self.delta,
            tvd,
            site,
            self.catalogue,
            start=start,
            conventions=conventions,
            outside_validity=outside,
        )
        rot = self.rotation()
        out: np.ndarray = rot @ cov @ rot.T
        return out

    def positions(self, north: float, east: float) -> tuple[float, float]:
        """A horizontal position (m) referred to true north, in the frame's north."""
        shift, _ = convert_azimuth(0.0, "true", self.north, **self._corrections())  # type: ignore[arg-type]
        n, e = turned_positions(north, east, shift)
        return float(n), float(e)

    def rotation(self) -> np.ndarray:
        """True-north NEV → the frame's."""
        c, s = np.cos(self.delta), np.sin(self.delta)
        return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])

    def effects(
        self,
        model: str,
        survey: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        site: ModelSite,
        conventions: Conventions,
    ) -> TermEffects:
        """The model's term effects on a survey from its surface, in the frame."""
        md, inc, azi, tvd = survey
        fx = term_effects_of(
            model, model_survey(md, inc, azi + self.delta, tvd, conventions), site, self.catalogue
        )
        rot = self.rotation()
        return TermEffects(fx.names, fx.modes, fx.full @ rot.T, fx.star @ rot.T, fx.tie)


def _arrays(table: pa.Table, frame: _Frame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MD (m), inclination and frame azimuth (rad, NaN at vertical kept) of a stations table."""
    md = table.column("md").to_numpy(zero_copy_only=False).astype(np.float64)
    inc = np.radians(table.column("inc").to_numpy(zero_copy_only=False))
    azi_deg = table.column("azi").to_numpy(zero_copy_only=False).astype(np.float64)
    return md, inc, frame.azimuths(azi_deg, north_reference_of(table, "azi"))


@dataclass(frozen=True)
class _Survey:
    """How one well's covariance is made: its model, site, frame and conventions."""

    frame: _Frame
    site: ModelSite
    conventions: Conventions
    outside: OutsideValidity

    def well(
        self,
        name: str,
        stations: tuple[np.ndarray, np.ndarray, np.ndarray],
        start_at: tuple[float, float, float],
        model: str,
        diameter: float,
        start: Start = "surface",
    ) -> Well:
        md, inc, azi = stations
        tvd = minimum_curvature(md, inc, azi, tie_tvd=start_at[2]).tvd
        try:
            cov = self.frame.covariance(
                model, (md, inc, azi, tvd), self.site, start, self.conventions, self.outside
            )
        except OutsideValidityError as exc:
            well = "the reference" if name == "reference" else f"offset well {name!r}"
            raise OutsideValidityError(f"{well}: {exc}") from None
        return Well(name, md, inc, azi, start_at, cov, 0.5 * diameter)

    def effects(
        self, model: str, well: tuple[np.ndarray, np.ndarray, np.ndarray], tvd0: float
    ) -> TermEffects:
        """The model's term effects on a survey (MD, inclination, frame azimuth) from its
        surface (TVD ``tvd0`` there), in the frame."""
        md, inc, azi = well
        tvd = minimum_curvature(md, inc, azi, tie_tvd=tvd0).tvd
        return self.frame.effects(model, (md, inc, azi, tvd), self.site, self.conventions)


def _shared(
    make: _Survey, ref: Well, ref_model: str, off_model: str, kick: Kickoff, pair: Pair
) -> Pair:
    """The pair with the exact shared-error covariance (:mod:`pipeline.anticollision.shared`):
    the sidetrack's path is the reference's trunk to the kick-off, then its own stations."""
    at = np.flatnonzero(np.abs(ref.md - kick.reference_md) <= 1e-6)
    if not at.size:
        raise ValueError(
            f"offset well {pair.offset.name!r}: sidetrack 'shared' needs a reference station "
            f"at the kick-off MD {kick.reference_md:g} m"
        )
    k = int(at[0])
    shift = kick.reference_md - kick.offset_md  # the offset's MDs on the reference's datum
    off = pair.offset
    side = (
        np.concatenate((ref.md[: k + 1], off.md[1:] + shift)),
        np.concatenate((ref.inc[: k + 1], off.inc[1:])),
        np.concatenate((ref.azi[: k + 1], off.azi[1:])),
    )
    shared = SharedErrors(
        make.effects(ref_model, (ref.md, ref.inc, ref.azi), ref.tie[2]),
        make.effects(ref_model, side, ref.tie[2]),
        make.effects(off_model, side, ref.tie[2]),
        k,
    )

    def relative(
        k_ref: np.ndarray, f_ref: np.ndarray, k_off: np.ndarray, f_off: np.ndarray
    ) -> np.ndarray:
        return shared(k_ref + k, f_ref, k_off + k, f_off)

    return Pair(pair.reference, pair.offset, relative)


def _kickoff(
    w: dict[str, Any],
    reference: Well,
    offset: Well,
    params: ClearanceParams,
    reference_name: str | None,
) -> Kickoff | None:
    """The common point of an offset well with the reference: named by its ``parent`` /
    ``kickoff_md``, else detected (None: none)."""
    parent = w.get("parent")
    names = {"reference", *([reference_name.casefold()] if reference_name else [])}
    if parent and parent.strip().casefold() not in names:
        raise ValueError(
            f"offset well {w['offset']!r}: parent {parent!r} is not the reference well "
            f"({reference_name or 'reference'!r}); a common section with another offset well "
            "does not touch this scan: list that well's stations from its surface"
        )
    if w.get("kickoff_md") is None:
        return common_point(reference.path(), offset.path(), params.common_tolerance)
    try:
        kick = named_kickoff(reference.path(), offset.path(), float(w["kickoff_md"]))
    except ValueError as exc:
        raise ValueError(f"offset well {w['offset']!r}: {exc}") from None
    if kick.distance > params.common_tolerance:
        raise ValueError(
            f"offset well {w['offset']!r}: at its kick-off MD {kick.offset_md:g} m it is "
            f"{kick.distance:.3f} m from the reference path (common_tolerance "
            f"{params.common_tolerance:g} m): not a common point"
        )
    return kick


_UNSET = (None, None, None)
"""No tie of the stage's: the clearance scan ties each well where its file lists it."""


def _offset_tie(w: Mapping[str, Any], frame: _Frame) -> dict[str, float] | None:
    """The tie-on an offset well's stations file lists at its first station (TVD, north,
    east, m, from its own wellhead, in the frame's north; None: none listed)."""
    if w.get("tie_tvd") is None:
        return None
    north, east = frame.positions(w["tie_north"], w["tie_east"])
    return {"tvd": w["tie_tvd"], "north": north, "east": east}


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
    for model in sorted(models):  # the reference's and the manifest's (the wells' model)
        param = "reference_model" if model == params.reference_model else "wells.model"
        toolmodels.record(ctx, find_model(model, catalogue), param)
    well = ctx.well_for(well_of(reference))  # the reference file's header, not another's
    site, applied = _site(params, well, models, catalogue)
    frame = _Frame(north_reference_of(reference, "azi"), well, site.magnetic, catalogue)
    make = _Survey(
        frame,
        site,
        Conventions(
            first_station_exact=params.first_station_exact,
            vertical_azimuth=params.vertical_azimuth,
        ),
        params.outside_validity,
    )
    ref_arrays = _arrays(reference, frame)
    ref_model, ref_diameter = params.reference_model, params.reference_hole_diameter
    listed_at = listed_ties(reference, survey_offsets(reference)[:2])[0]
    ref_tie = chosen_tie("reference", float(ref_arrays[0][0]), listed_at, _UNSET)
    ref_at = (ref_tie.north, ref_tie.east, ref_tie.tvd)
    ref = make.well("reference", ref_arrays, ref_at, ref_model, ref_diameter)
    offsets = survey_offsets(stations)
    ids = stations.column("survey").to_pylist() if "survey" in stations.column_names else None
    blocks = {
        (ids[lo] if ids is not None else ""): stations.slice(lo, hi - lo)
        for lo, hi in itertools.pairwise(offsets)
    }
    pairs, kickoffs, ties = [], {}, {}
    for w in listed:
        block = blocks.get(w["offset"])
        if block is None or block.num_rows < 2:
            raise ValueError(
                f"offset well {w['offset']!r}: {'no' if block is None else 'fewer than 2'} "
                "stations in the offsets table"
            )
        on_the_reference_grid(
            w["offset"], w.get("reference_convergence"), frame.north, frame.convergence
        )
        arrays = _arrays(block, frame)
        ties[w["offset"]] = _offset_tie(w, frame)
        start_at = first_station(w, float(arrays[0][0]), ties[w["offset"]])
        offset = make.well(w["offset"], arrays, start_at, w["model"], w["hole_diameter"])
        kick = _kickoff(w, ref, offset, params, well.well)
        if kick is None:
            pairs.append(Pair(ref, offset))
            continue
        kickoffs[w["offset"]] = kick
        r_md, r_inc, r_azi, r_at = cut(ref.path(), kick.reference_md)
        o_md, o_inc, o_azi, o_at = cut(offset.path(), kick.offset_md)
        pair = Pair(
            make.well("reference", (r_md, r_inc, r_azi), r_at, ref_model, ref_diameter, "same_run"),
            make.well(
                w["offset"], (o_md, o_inc, o_azi), o_at, w["model"], w["hole_diameter"], "other_run"
            ),
        )
        if params.sidetrack == "shared":
            pair = _shared(make, ref, ref_model, w["model"], kick, pair)
        pairs.append(pair)
    firsts = {"reference": float(ref_arrays[0][0])}
    firsts |= {w["offset"]: float(blocks[w["offset"]]["md"][0].as_py()) for w in listed}
    tie_on = TieOnRecord(  # a sidetrack's σ is zeroed at its kick-off (the ISCWSA rule)
        surveys=outside_ties([(n, md) for n, md in firsts.items() if n not in kickoffs], None)
    )
    warn_missing(tie_on, ctx.stage_id, "The separation factors against it leave that out.")
    result = scan_pairs(
        pairs,
        SeparationRule(k=params.k, sigma_pa=params.sigma_pa, surface_margin=params.surface_margin),
        RuleLimits(stop=params.stop, caution=params.caution),
        params.level_on,
    )
    table = Clearance.compiled().make_table(
        {
            "offset": result.offset.tolist(),
            "md": result.md,
            "offset_md": result.offset_md,
            "distance": result.distance,
            "sigma_s": result.sigma_s,
            "sf": result.sf,
            "sf_between": result.sf_between,
            "md_between": result.md_between,
            "level": result.level.tolist(),
            "toolface": result.toolface,
            # a NaN σ where the centres are apart: a well's σ not given (flagged)
            **(
                {"outside_validity": np.isnan(result.sigma_s) & (result.distance > 0)}
                if params.outside_validity == "flag"
                else {}
            ),
        }
    )
    rule = {
        **params.model_dump(mode="json", exclude={"latitude", "magnetic"}),
        "reference_tie": ref_tie.model_dump(mode="json"),
        **({"magnetic": applied.model_dump(mode="json")} if applied is not None else {}),
        "wells": {
            w["offset"]: {
                **{k: w[k] for k in ("model", "hole_diameter", "source", "sha256") if w.get(k)},
                **{k: w[k] for k in ("north", "east", "tvd")},  # the slot and datum (tvd null)
                **({"tie_on": ties[w["offset"]]} if ties[w["offset"]] else {}),  # the file's
                **(
                    {"reference_convergence": w["reference_convergence"]}
                    if w.get("reference_convergence") is not None
                    else {}
                ),
                **(
                    {"kickoff": dataclasses.asdict(kickoffs[w["offset"]])}
                    if w["offset"] in kickoffs
                    else {}
                ),
            }
            for w in listed
        },
    }
    return {"clearance": with_tie_on(with_rule(table, rule), tie_on)}


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

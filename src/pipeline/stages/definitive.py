"""Built-in plugin: the ``definitive_survey`` stage — one survey of a well from several runs
or tools (gyro in the top hole, MWD below; in-run and out-run), with per-station provenance
and the position covariance carried across the sections (:mod:`pipeline.survey.definitive`
chooses the stations, :mod:`pipeline.uncertainty.sections` carries the covariance)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationError, ValidationInfo, model_validator

from pipeline.contracts import SOURCE_KEY, TableContract, column
from pipeline.earth.magnetic import AppliedMagnetic, applied_magnetic
from pipeline.earth.site import MagneticReference, resolve_site
from pipeline.errors import EmptyTableError, SurveyCheckWarning
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages import toolmodels
from pipeline.stages.survey import warn_other_tie
from pipeline.stages.uncertainty import (
    PositionUncertainty,
    UncertaintyParams,
    covariance_columns,
    magnetic_words,
    with_magnetic,
)
from pipeline.survey.calculation import SurveyCalculation, calculation_of, with_calculation
from pipeline.survey.definitive import OverlapRule, RunStations, plan_sections, roles
from pipeline.survey.interpolate import interpolate_md
from pipeline.survey.mincurve import closure, minimum_curvature, vertical_section
from pipeline.survey.north import convert_azimuth, turned_positions
from pipeline.survey.stations import (
    defined_azimuths,
    north_reference_of,
    station_angles,
    survey_offsets,
)
from pipeline.survey.tiein import SurveyTie, chosen_tie, listed_positions, ties_words
from pipeline.tables import DLS_COURSE_M, Stations
from pipeline.uncertainty.engine import (
    OutsideValidity,
    OutsideValidityError,
    bounded_covariance,
    configure,
    model_terms,
    within_range,
)
from pipeline.uncertainty.frames import MissingNorthError, turned_matrices
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.sections import Section as CovSection
from pipeline.uncertainty.sections import WellByWell, definitive_covariance
from pipeline.uncertainty.stated import model_words, with_statements
from pipeline.uncertainty.terms import Survey
from pipeline.uncertainty.tieon import (
    TIE_COVARIANCE,
    TieCovariance,
    TieOnRecord,
    outside_ties,
    warn_missing,
)
from pipeline.uncertainty.toolmodel import ToolModel
from pipeline.well import Latitude, NorthReference, WellMetadata, one_well, well_of

MAX_RUNS = 6
RUN_PORTS = tuple(f"run{k}" for k in range(1, MAX_RUNS + 1))


class DefinitiveSurvey(PositionUncertainty):
    """A definitive survey: the stations chosen from several runs, their positions (each
    section tied to the one above), NEV covariance carried across sections, and where every
    station comes from."""

    run: str = column(unit=None, description="run the station comes from")
    tool_model: str = column(unit=None, description="error model of the run's tool")
    source: str = column(unit=None, description="file the run was read from ('' if none)")
    section: int = column(unit=None, ge=0, description="section index, top down")


class SurveyOverlap(TableContract):
    """Stations of the runs that the definitive survey does not list, kept for QC, beside
    the definitive survey at the same MD (NaN outside it)."""

    run: str = column(unit=None, description="run the station comes from")
    role: str = column(
        unit=None,
        description="overlap (inside another run's section), excluded (outside its run's "
        "depth range) or left_out (beyond the survey's first or last listed station: a "
        "stretch at an end shorter than min_length, warned of)",
    )
    md: float = column(unit="m", description="measured depth")
    inc: float = column(unit="deg", ge=0, le=180, description="the run's inclination")
    azi: float = column(
        unit="deg",
        north_reference=True,
        undefined_at_vertical=True,
        description="the run's azimuth, in the definitive survey's north reference",
    )
    definitive_inc: float = column(
        unit="deg", finite=False, description="the definitive survey's inclination at md"
    )
    definitive_azi: float = column(
        unit="deg",
        finite=False,
        north_reference=True,
        description="the definitive survey's azimuth at md",
    )
    inc_diff: float = column(unit="deg", finite=False, description="inc − definitive_inc")
    azi_diff: float = column(
        unit="deg", finite=False, description="azi − definitive_azi, wrapped to ±180°"
    )
    source: str = column(unit=None, description="file the run was read from ('' if none)")


class RunSpec(BaseModel):
    """One run of a definitive survey (lengths m)."""

    model_config = ConfigDict(extra="forbid")
    name: str | None = Field(None, description="run id in the provenance (default: the port)")
    model: str = Field(
        "GYRO-NS",
        description="the run's error model: a tool model's name (`gyropipe models`) or the "
        "path of a tool-model file, as the position_uncertainty stage's",
    )
    tool: dict[str, float] = Field(
        default_factory=dict,
        description="term magnitudes and parameters overriding the model file's (its units)",
    )
    priority: int = Field(0, description="in an overlap the higher priority wins")
    md_from: float | None = Field(None, description="use the run from this MD, m")
    md_to: float | None = Field(None, description="use the run down to this MD, m")

    @model_validator(mode="after")
    def _valid(self, info: ValidationInfo) -> RunSpec:
        try:  # the model exists and has the tool fields
            UncertaintyParams.model_validate(
                {"model": self.model, "tool": self.tool}, context=info.context
            )
        except ValidationError as exc:
            raise ValueError(exc.errors()[0]["msg"].removeprefix("Value error, ")) from None
        if self.md_from is not None and self.md_to is not None and self.md_to <= self.md_from:
            raise ValueError(f"md_to {self.md_to} must be below md_from {self.md_from}")
        return self


class DefinitiveParams(BaseModel):
    """Parameters of the definitive-survey stage (lengths m, angles deg)."""

    model_config = ConfigDict(extra="forbid")
    runs: dict[str, RunSpec] = Field(
        default_factory=dict,
        description=f"per input port ({', '.join(RUN_PORTS)}): run id, error model, priority "
        "and depth range; a wired port without an entry takes the defaults",
    )
    overlap: OverlapRule = Field(
        "priority",
        description="who wins a depth several runs cover: priority (higher wins; equal: the "
        "run starting deeper), upper (the run above keeps it) or lower (the run below takes "
        "over from its first station)",
    )
    min_length: float = Field(
        1.0,
        ge=0,
        description="shortest stretch a run takes over, m: a shorter one (e.g. an out-run "
        "starting a few millimetres above the in-run) stays with the neighbouring run",
    )
    north_reference: NorthReference | None = Field(
        None, description="azimuths of the survey (default: the first run's)"
    )
    latitude: Latitude | None = Field(
        None, description="latitude, deg (gyro models); default: the well's"
    )
    magnetic: MagneticReference | None = Field(
        None,
        description="geomagnetic reference (MWD models, magnetic azimuths); default: the well "
        "metadata's magnetic_field, magnetic_dip and declination, else WMM2025 at the site",
    )
    basis: Literal["balanced_tangent", "min_curve"] = Field(
        "balanced_tangent", description="leg Jacobian of the error propagation"
    )
    surface_tie: bool = Field(
        True, description="ISCWSA surface tie-on allowance at the first station of the well"
    )
    tie_covariance: TieCovariance | None = Field(None, description=TIE_COVARIANCE)
    well_by_well: WellByWell = Field(
        "shared",
        description="well-by-well terms shared by every run of the well (ISCWSA) or "
        "correlated within each run only (per_run)",
    )
    confidence: float = Field(0.95, gt=0, lt=1, description="probability of the *_conf columns")
    outside_validity: OutsideValidity = Field(
        "refuse",
        description="a station outside its run's error model's range: refuse (an error "
        "naming the run and station), or flag (NaN σ from it down, through every run below, "
        "and an outside_validity column)",
    )
    vs_azimuth: float = Field(0.0, description="vertical-section azimuth, deg")
    tie_north: float | None = Field(
        None,
        description="northing of the survey's first station, m; default: the one its run's "
        "stations file lists there (with TVD and east), else 0",
    )
    tie_east: float | None = Field(
        None,
        description="easting of the survey's first station, m; default: the one its run's "
        "stations file lists there (with TVD and north), else 0",
    )
    tie_tvd: float | None = Field(
        None,
        description="TVD of the survey's first station, m; default: the one its run's "
        "stations file lists there (with north and east), else its MD. Giving any of "
        "tie_tvd, tie_north, tie_east ties the survey at the stage's (the others at their "
        "fallbacks), warned where the file lists another",
    )
    position_tolerance: float = Field(
        0.1,
        ge=0,
        description="the largest 3-D distance, m, between the stage's tie and the tie-on "
        "the file lists before a warning",
    )

    @model_validator(mode="after")
    def _ports(self) -> DefinitiveParams:
        unknown = sorted(set(self.runs) - set(RUN_PORTS))
        if unknown:
            raise ValueError(f"runs: unknown ports {unknown}; expected some of {list(RUN_PORTS)}")
        return self


@dataclass(frozen=True)
class _Run:
    port: str
    spec: RunSpec
    md: np.ndarray
    inc: np.ndarray
    azi: np.ndarray  #: deg, in the survey's north reference
    azi_true: np.ndarray  #: deg, true north (the error models')
    to_north: float  #: deg, the change true → the survey's north of its azimuths
    source: str
    tool: list[str | None]  #: each station's tool: its own, else its file header's
    listed: np.ndarray | None  #: (n, 3) TVD, north, east its file lists, m, survey's north

    @property
    def name(self) -> str:
        return self.spec.name or self.port


def definitive_survey(
    inputs: Mapping[str, pa.Table], params: DefinitiveParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Runs on ports run1…run6 → the definitive survey and the stations it does not list."""
    missing = sorted(set(params.runs) - set(inputs))
    if missing:
        raise ValueError(f"runs {missing} are configured but their ports are not wired")
    ports = [p for p in RUN_PORTS if p in inputs]
    north = params.north_reference or north_reference_of(inputs[ports[0]], "azi")
    specs = {p: params.runs.get(p, RunSpec()) for p in ports}
    one_well(
        {p if specs[p].name in (None, p) else f"{p} ({specs[p].name})": inputs[p] for p in ports}
    )
    catalogue = toolmodels.of_run(ctx)
    tools = {p: configure(spec.model, spec.tool, catalogue) for p, spec in specs.items()}
    for port, tool in tools.items():
        toolmodels.record(ctx, tool, f"runs.{port}.model")
    wells = {p: ctx.well_for(well_of(inputs[p])) for p in ports}  # each run's own header
    applied = {
        p: applied_magnetic(params.magnetic, wells[p], stage="definitive_survey")
        for p in ports
        if _needs_magnetic(tools[p], inputs[p], north)
    }
    sites = {p: _site(params, tools[p], wells[p], applied.get(p)) for p in ports}
    runs = [_read(p, inputs[p], specs[p], north, sites[p].magnetic, wells[p]) for p in ports]
    names = [r.name for r in runs]
    if len(set(names)) != len(names):
        raise ValueError(f"run names must differ; got {names}")
    _one_north(runs, north)
    _one_datum(runs, wells)
    stations = [
        RunStations(r.name, r.md, r.spec.priority, r.spec.md_from, r.spec.md_to) for r in runs
    ]
    sections = plan_sections(stations, params.overlap, params.min_length)
    station_roles = roles(stations, sections)
    _warn_left_out(runs, station_roles, params.min_length, ctx.stage_id)
    listed = [(sec, runs[sec.run]) for sec in sections]
    md = np.concatenate([run.md[sec.listed] for sec, run in listed])
    inc_deg = np.concatenate([run.inc[sec.listed] for sec, run in listed])
    azi_deg = np.concatenate([run.azi[sec.listed] for sec, run in listed])
    azi_true = np.concatenate([run.azi_true[sec.listed] for sec, run in listed])
    inc, azi = np.radians(inc_deg), np.radians(defined_azimuths(azi_deg))
    tie = _tie(listed[0], params, ctx.stage_id)
    pos = minimum_curvature(md, inc, azi, tie_north=tie.north, tie_east=tie.east, tie_tvd=tie.tvd)
    bounds = np.cumsum([0] + [sec.listed.size for sec in sections])
    survey = Survey.of(md, inc, np.radians(defined_azimuths(azi_true)), pos.tvd)
    cov = _valid_covariance(survey, listed, bounds, tools, sites, params)
    # the models' true north → the survey's (a tie_covariance is stated in the survey's)
    cov = turned_matrices(cov, np.repeat([run.to_north for _, run in listed], np.diff(bounds)))
    tie_on = TieOnRecord(surveys=outside_ties([(None, float(md[0]))], params.tie_covariance))
    if params.tie_covariance is not None:  # (outside_ties refuses one at the depth reference)
        cov = cov + params.tie_covariance.matrix()
    warn_missing(tie_on, ctx.stage_id)
    parts = {
        "md": md,
        "inc": inc_deg,
        "azi": azi_deg,
        "north": pos.north,
        "east": pos.east,
        "tvd": pos.tvd,
        "run": [run.name for sec, run in listed for _ in sec.listed],
        "tool_model": [run.spec.model for sec, run in listed for _ in sec.listed],
        "source": [run.source for sec, run in listed for _ in sec.listed],
        "tool_type": [run.tool[k] for sec, run in listed for k in sec.listed],
        "section": np.repeat(np.arange(len(sections)), np.diff(bounds)),
    }
    by_run = {run.name: applied[run.port] for run in runs if run.port in applied}
    listed_tools = [tools[run.port] for _, run in listed]
    models = ", ".join(dict.fromkeys(model_words(t.name, t.revision) for t in listed_tools))
    survey_table = with_statements(
        _survey_table(parts, cov, params, north), params.confidence, models, tie_on
    )
    survey_table = with_magnetic(survey_table, by_run)
    calculation = SurveyCalculation(
        method="minimum_curvature", vs_azimuth=params.vs_azimuth, ties=(tie,)
    )
    return {
        "survey": with_calculation(survey_table, calculation),
        "overlap": _overlap(runs, station_roles, survey_table, north),
    }


def _tie(top: tuple[Any, _Run], params: DefinitiveParams, stage: str) -> SurveyTie:
    """The survey's tie at its first listed station (``top``: the top section and its run):
    the stage's where given (warned beyond ``position_tolerance`` of the file's), else the
    TVD, north and east the run's file lists there, else TVD = MD, N = E = 0."""
    section, run = top
    first = int(section.listed[0])
    listed = None if run.listed is None else run.listed[first]
    if listed is not None and np.isnan(listed).any():
        listed = None
    given = (params.tie_tvd, params.tie_north, params.tie_east)
    tie = chosen_tie(run.name, float(run.md[first]), listed, given)
    warn_other_tie(tie, listed, params.position_tolerance, stage)
    return tie


def _listed(table: pa.Table, own: str, north: str, kw: Mapping[str, Any]) -> np.ndarray | None:
    """The TVD, north, east a run's file lists ((n, 3) m; None: none), horizontal positions
    turned from its azimuths' north ``own`` to the survey's ``north`` as its azimuths are."""
    listed = listed_positions(table)
    if listed is None or own == north:
        return listed
    shift, _ = convert_azimuth(0.0, own, north, **kw)  # type: ignore[arg-type]
    listed[:, 1], listed[:, 2] = turned_positions(listed[:, 1], listed[:, 2], shift)
    return listed


def _read(
    port: str,
    table: pa.Table,
    spec: RunSpec,
    north: str,
    magnetic: MagneticReference | None,
    well: WellMetadata,
) -> _Run:
    """A run's stations as arrays, azimuths in the survey's reference and in true north."""
    if table.num_rows == 0:
        raise EmptyTableError(f"{port} stations", "a run needs at least two stations")
    if table.num_rows < 2:
        raise ValueError(f"{port}: a run needs at least two stations; got one")
    if len(survey_offsets(table)) > 2:
        raise ValueError(f"{port}: the table holds several surveys; give one run per port")
    md, inc, azi = station_angles(table)
    own = north_reference_of(table, "azi")
    declination = None if magnetic is None else magnetic.declination
    kw = {"convergence_deg": well.convergence_for(own), "declination_deg": declination}
    for ref, value in (("grid", kw["convergence_deg"]), ("magnetic", declination)):
        if value is None and ref in (own, north):
            raise MissingNorthError("definitive_survey", ref, modelled=True, run=port)
    try:
        azi_out, _ = convert_azimuth(azi, own, north, **kw)  # type: ignore[arg-type]
        azi_true, _ = convert_azimuth(azi, own, "true", **kw)
        to_north, _ = convert_azimuth(0.0, "true", north, **kw)  # type: ignore[arg-type]
        listed = _listed(table, own, north, kw)
    except ValueError as exc:
        raise ValueError(f"{port}: {exc}") from None
    source = (table.schema.metadata or {}).get(SOURCE_KEY, b"").decode()
    header = (well_of(table) or WellMetadata()).tool_type
    tools = table.column("tool_type").to_pylist() if "tool_type" in table.column_names else []
    tool = [t or header for t in tools] if tools else [header] * table.num_rows
    azi_out = np.where(np.isnan(azi), np.nan, azi_out)
    return _Run(port, spec, md, inc, azi_out, azi_true, float(to_north), source, tool, listed)


NORTH_AGREE_DEG = 1e-9
"""deg: runs whose corrections from true to the survey's north differ by more are in
different norths"""


def _one_north(runs: list[_Run], north: str) -> None:
    """Refuse a survey in grid or magnetic north whose runs refer their azimuths to it by
    different corrections (runs surveyed years apart in magnetic north, headers stating
    different convergences): positions integrated from them would be in no one north."""
    east_of_true = {run.name: (180.0 - run.to_north) % 360.0 - 180.0 for run in runs}
    if max(east_of_true.values()) - min(east_of_true.values()) > NORTH_AGREE_DEG:
        each = ", ".join(f"{name}: {value:g}°" for name, value in east_of_true.items())
        raise ValueError(
            f"the runs' {north} norths are not one ({north} north east of true north by "
            f"{each}): a survey integrated from their azimuths would be in none of them; "
            "give the stage north_reference: true (each run's azimuths referred to true "
            "north by its own correction)"
        )


def _needs_magnetic(tool: ToolModel, table: pa.Table, north: str) -> bool:
    """Whether a run needs the geomagnetic reference: an MWD model, or magnetic azimuths
    to convert (its own or the survey's)."""
    return "magnetic" in tool.needs or "magnetic" in (north_reference_of(table, "azi"), north)


def _site(
    params: DefinitiveParams,
    tool: ToolModel,
    well: WellMetadata,
    applied: AppliedMagnetic | None,
) -> ModelSite:
    """A run's site as its error model needs it, from its own well metadata: the latitude
    (gyro models) and the geomagnetic reference applied to it (MWD models)."""
    site = ModelSite(magnetic=None if applied is None else applied.reference)
    if "latitude" not in tool.needs:
        return site
    latitude = resolve_site(
        well, stage="definitive_survey", latitude=params.latitude, north_seeking=True
    ).latitude
    return replace(site, latitude=latitude)


DATUM_TOLERANCE_M = 0.01
"""Datum elevations (m) of two runs this close are one datum (an elevation written in ft
and read back in m, rounded to 0.01 ft, differs by up to 2 mm)."""


def _one_datum(runs: list[_Run], wells: Mapping[str, WellMetadata]) -> None:
    """Refuse runs whose headers state different depth references, or datum elevations
    more than :data:`DATUM_TOLERANCE_M` apart: their MDs are not from one zero (shift one
    run's to the other's datum first). One elevation written in ft and in m is one."""
    for name in ("depth_reference", "elevation"):
        stated = {run.name: getattr(wells[run.port], name) for run in runs}
        values = [v for v in stated.values() if v is not None]
        apart = (
            max(values) - min(values) > DATUM_TOLERANCE_M
            if name == "elevation" and values
            else len({str(v).casefold() for v in values}) > 1
        )
        if apart:
            each = ", ".join(f"{run} {value}" for run, value in stated.items() if value is not None)
            raise ValueError(
                f"the runs' {name} differ ({each}): their MDs are not from one datum; refer "
                "every run to one datum before the definitive survey"
            )


def _valid_covariance(
    survey: Survey,
    listed: list[tuple[Any, Any]],
    bounds: np.ndarray,
    tools: Mapping[str, ToolModel],
    sites: Mapping[str, ModelSite],
    params: DefinitiveParams,
) -> np.ndarray:
    """The listed stations' covariance (n, 3, 3), m², each run's errors from its own model;
    NaN from the first station outside its run's model range (or beyond the physical bound)
    down, which ``outside_validity: refuse`` makes an error naming the run."""
    n = survey.size
    for (_, run), lo, hi in zip(listed, bounds[:-1], bounds[1:], strict=True):
        part = Survey.of(survey.md[lo:hi], survey.inc[lo:hi], survey.azi[lo:hi], survey.tvd[lo:hi])
        try:
            inside = within_range(part, tools[run.port], params.outside_validity)
        except OutsideValidityError as exc:
            raise OutsideValidityError(f"run {run.name!r}: {exc}") from None
        if inside < part.size:
            n = int(lo) + inside
            break
    sections = [
        CovSection(
            run.name, int(lo), int(min(hi, n)), model_terms(tools[run.port], sites[run.port])
        )
        for (_, run), lo, hi in zip(listed, bounds[:-1], bounds[1:], strict=True)
        if lo < n
    ]
    models = ", ".join(
        run.spec.model for (_, run), lo in zip(listed, bounds[:-1], strict=True) if lo < n
    )

    def compute(head: Survey) -> np.ndarray:
        return definitive_covariance(
            head,
            sections,
            basis=params.basis,
            surface_tie=params.surface_tie,
            well_by_well=params.well_by_well,
        )

    try:
        return bounded_covariance(survey, n, compute, models, params.outside_validity)
    except OutsideValidityError as exc:
        raise OutsideValidityError(f"definitive survey: {exc}") from None


def _survey_table(
    columns: dict[str, Any], cov: np.ndarray, params: DefinitiveParams, north: str
) -> pa.Table:
    """The listed stations of every section, in MD order, with their NEV covariance (m²),
    as a :class:`DefinitiveSurvey`."""
    joined = {k: np.asarray(v) for k, v in columns.items()}
    md, inc, azi = joined["md"], joined["inc"], joined["azi"]
    steps = minimum_curvature(md, np.radians(inc), np.radians(azi))
    distance, direction = closure(joined["north"], joined["east"])
    table: dict[str, object] = {
        **joined,
        "dogleg": np.degrees(steps.dogleg),
        "dls": np.degrees(steps.dls) * DLS_COURSE_M,
        "vertical_section": vertical_section(
            joined["north"], joined["east"], np.radians(params.vs_azimuth)
        ),
        "closure_distance": distance,
        "closure_direction": np.degrees(direction) % 360.0,
        **covariance_columns(cov, params.confidence, params.outside_validity),
    }
    return DefinitiveSurvey.compiled().make_table(table, north_reference=north)


def _warn_left_out(
    runs: list[_Run], station_roles: list[list[str]], min_length: float, stage: str
) -> None:
    """A :class:`~pipeline.errors.SurveyCheckWarning` for each run whose stations at the
    top or bottom of the survey are left out (role ``left_out``): their MDs and how far
    beyond the survey's first or last listed station they lie."""
    listed = np.concatenate(
        [run.md[np.array(role) == "listed"] for run, role in zip(runs, station_roles, strict=True)]
    )
    for run, role in zip(runs, station_roles, strict=True):
        out = run.md[np.array(role) == "left_out"]
        for side, end, beyond, word in (
            ("ends", listed.max(), out[out > listed.max()], "below"),
            ("starts", listed.min(), out[out < listed.min()], "above"),
        ):
            if not beyond.size:
                continue
            far = float(np.abs(beyond - end).max())
            at = ", ".join(f"{md:.2f}" for md in beyond)
            one = beyond.size == 1
            what, verb, far_word = ("station", "is", "") if one else ("stations", "are", "up to ")
            warnings.warn(
                f"stage {stage!r}: the definitive survey {side} at {end:.2f} m MD; the {what} "
                f"of run {run.name!r} at {at} m MD, {far_word}{far:.2f} m {word}, {verb} left "
                f"out (a stretch shorter than min_length {min_length:g} m that no other run "
                f"covers); set min_length below {far:.2f} m to list it",
                SurveyCheckWarning,
                stacklevel=2,
            )


def _overlap(
    runs: list[_Run], station_roles: list[list[str]], survey: pa.Table, north: str
) -> pa.Table:
    """Every station not listed, beside the definitive survey interpolated at its MD."""
    md_d = survey.column("md").to_numpy()
    inc_d = np.radians(survey.column("inc").to_numpy())
    azi_d = np.radians(defined_azimuths(survey.column("azi").to_numpy()))
    cols: dict[str, list[Any]] = {k: [] for k in ("run", "role", "md", "inc", "azi", "source")}
    for run, role in zip(runs, station_roles, strict=True):
        for k, r in enumerate(role):
            if r != "listed":
                for name, value in (
                    ("run", run.name),
                    ("role", r),
                    ("md", run.md[k]),
                    ("inc", run.inc[k]),
                    ("azi", run.azi[k]),
                    ("source", run.source),
                ):
                    cols[name].append(value)
    md = np.asarray(cols["md"], dtype=float)
    inside = (md >= md_d[0]) & (md <= md_d[-1])
    d_inc = np.full(md.size, np.nan)
    d_azi = np.full(md.size, np.nan)
    if inside.any() and md_d.size >= 2:
        at = interpolate_md(md_d, inc_d, azi_d, md[inside])
        d_inc[inside] = np.degrees(at.inc)
        d_azi[inside] = np.degrees(at.azi)
    inc = np.asarray(cols["inc"], dtype=float)
    azi = np.asarray(cols["azi"], dtype=float)
    return SurveyOverlap.compiled().make_table(
        {
            **cols,
            "md": md,
            "inc": inc,
            "azi": azi,
            "definitive_inc": d_inc,
            "definitive_azi": d_azi,
            "inc_diff": inc - d_inc,
            "azi_diff": (azi - d_azi + 180.0) % 360.0 - 180.0,
        },
        north_reference=north,
    )


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="definitive_survey",
            func=definitive_survey,
            description="One survey of a well from several runs or tools: depth ranges and "
            "priorities, tie-ins, overlap rules, provenance per station, and the position "
            "covariance carried across sections (each run's systematic errors its own).",
            inputs={port: Stations for port in RUN_PORTS},
            optional_inputs=frozenset(RUN_PORTS[1:]),
            outputs={"survey": DefinitiveSurvey, "overlap": SurveyOverlap},
            params=DefinitiveParams,
        )
    )


def definitive_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The definitive survey in the report: ties, per-run propagation, the confidence."""
    from pipeline.reports.literature import ERROR_MODEL, GYRO_ERROR_MODEL

    confidence = float(stage.params.get("confidence", 0.0)) * 100
    runs = stage.params.get("runs") or {}
    models = [str(r.get("model", RunSpec().model)) for r in runs.values()] or [RunSpec().model]
    gyro = any(ctx.error_model(m)[1] for m in models)
    cited = ctx.cite(ERROR_MODEL)
    cited += f" (the gyro terms as in {ctx.cite(GYRO_ERROR_MODEL)})" if gyro else ""
    survey = ctx.tables.get("trajectory")
    calculation = calculation_of(survey) if survey is not None else None
    tied = f"{ties_words(calculation.ties)}; " if calculation and calculation.ties else ""
    return MethodNote(
        "Definitive survey",
        f"{tied}each run tied at the last listed station of the run above, positions by minimum "
        "curvature through the listed stations; each station's errors from its own run's "
        f"error model (depth terms on the run's own MD), propagated as in "
        f"{cited} over the listed stations with a run's systematic errors "
        "correlated within the run, ellipses at "
        f"{confidence:g} %{magnetic_words(ctx)}",
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("definitive_survey", method=definitive_method))

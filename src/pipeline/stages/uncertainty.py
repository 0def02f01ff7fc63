"""Built-in plugin: the ``position_uncertainty`` stage (ISCWSA gyro and MWD error models)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Literal

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, model_validator

from pipeline.contracts import column
from pipeline.earth.magnetic import AppliedMagnetic, MissingMagneticError, applied_magnetic
from pipeline.earth.site import MagneticReference, resolve_site
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages import toolmodels
from pipeline.survey.calculation import calculation_of, record_of, with_record
from pipeline.survey.stations import defined_azimuths, north_reference_of, survey_offsets
from pipeline.tables import CompassStations, Trajectory
from pipeline.uncertainty.carried import without_uncertainty
from pipeline.uncertainty.ellipse import ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.engine import (
    PARAMETER_ALIASES,
    OutsideValidity,
    configure,
    covariance,
    term_for,
)
from pipeline.uncertainty.frames import listing_north
from pipeline.uncertainty.gyro import with_initial_azimuth, with_measured_noise
from pipeline.uncertainty.quantities import ModelSite
from pipeline.uncertainty.stated import model_words, with_statements
from pipeline.uncertainty.terms import Survey
from pipeline.uncertainty.tieon import (
    TIE_COVARIANCE,
    TieCovariance,
    TieOn,
    TieOnRecord,
    outside_ties,
    warn_missing,
)
from pipeline.uncertainty.toolmodel import ToolModel
from pipeline.well import Latitude, WellMetadata, well_of

AREA = "m2"
STAGE = "position_uncertainty"


class PositionUncertainty(Trajectory):
    """A trajectory with each station's NEV position covariance (1σ², m²; N and E referred
    to the north of its azimuths, as the ellipse azimuth is) and its horizontal error
    ellipse (semi-axes at 1σ and at the stage's confidence) and vertical σ; NaN at a
    station outside the error model's range and below it (``outside_validity``
    flag; such a station is otherwise refused)."""

    cov_nn: float = column(unit=AREA, finite=False, description="north variance")
    cov_ne: float = column(unit=AREA, finite=False, description="north-east covariance")
    cov_nv: float = column(unit=AREA, finite=False, description="north-vertical covariance")
    cov_ee: float = column(unit=AREA, finite=False, description="east variance")
    cov_ev: float = column(unit=AREA, finite=False, description="east-vertical covariance")
    cov_vv: float = column(unit=AREA, finite=False, description="vertical variance")
    ellipse_major: float = column(
        unit="m", ge=0, finite=False, description="horizontal semi-major axis, 1σ"
    )
    ellipse_minor: float = column(
        unit="m", ge=0, finite=False, description="horizontal semi-minor axis, 1σ"
    )
    ellipse_azimuth: float = column(
        unit="deg",
        ge=0,
        lt=180,
        finite=False,
        north_reference=True,
        description="azimuth of the semi-major axis, clockwise from north",
    )
    sigma_v: float = column(unit="m", ge=0, finite=False, description="vertical σ")
    ellipse_major_conf: float = column(
        unit="m",
        ge=0,
        finite=False,
        description="semi-major axis at the confidence level (χ², 2 dof)",
    )
    ellipse_minor_conf: float = column(
        unit="m",
        ge=0,
        finite=False,
        description="semi-minor axis at the confidence level (χ², 2 dof)",
    )
    vertical_conf: float = column(
        unit="m", ge=0, finite=False, description="vertical half-interval at the confidence level"
    )
    outside_validity: bool = column(
        unit=None,
        default=False,
        description="the station, or one above it, is outside the error model's range: no σ "
        "(NaN); written with outside_validity: flag",
    )


class UncertaintyParams(BaseModel):
    """Parameters of the position-uncertainty stage."""

    model_config = ConfigDict(extra="forbid")
    model: str = Field(
        "GYRO-NS",
        description="error model: the name of a tool model (`gyropipe models` lists the "
        "shipped ones and those plugins add) or the path of a tool-model file (.yaml, "
        "docs/tool-models.md)",
    )
    confidence: float = Field(
        0.95, gt=0, lt=1, description="probability content of the *_conf ellipse columns"
    )
    latitude: Latitude | None = Field(
        None, description="latitude, deg (gyro models); default: the well's"
    )
    magnetic: MagneticReference | None = Field(
        None,
        description="MWD models: geomagnetic reference at the wellhead (total field nT, dip "
        "deg, declination deg east); default: the well metadata's magnetic_field, "
        "magnetic_dip and declination, else WMM2025 at the well's latitude, longitude, "
        "elevation and survey date",
    )
    basis: Literal["balanced_tangent", "min_curve"] = Field(
        "balanced_tangent",
        description="leg Jacobian: the ISCWSA standard's balanced tangent (default, as the "
        "ISCWSA workbook) or, opt-in, the exact minimum-curvature derivative",
    )
    surface_tie: bool = Field(
        True,
        description="apply the ISCWSA Rev 5 surface tie-on allowance at the first station "
        "(the standard's default)",
    )
    measured_sigma_azi: float | None = Field(
        None,
        ge=0,
        description="measured 1σ compassing azimuth scatter, deg; sets GXY-RN when given",
    )
    init_sigma_azi: float | None = Field(
        None,
        ge=0,
        description="continuous models (those with a static end inclination): measured 1σ "
        "azimuth of the stop the continuous run starts from (the compass stage's sigma_azi), "
        "deg; replaces the stationary gyro terms and starts the continuous section at the "
        "first station",
    )
    outside_validity: OutsideValidity = Field(
        "refuse",
        description="a station outside the error model's range (its inclination limits, or "
        "a σ beyond any physical position error): refuse (an error naming it), or flag (NaN "
        "σ from it down and an outside_validity column)",
    )
    tie_covariance: TieCovariance | None = Field(None, description=TIE_COVARIANCE)
    tool: dict[str, float] = Field(
        default_factory=dict,
        description="term magnitudes and model parameters overriding the model file's, by "
        "term name (GXY-GD, AMIL) or field name (gxy_gd, amil), in the file's units (e.g. "
        "GXY-GD deg/h, GXY-GRW deg/√h, running_speed m/h, AXYZ-ZB m/s², ABZ m/s², MBZ nT, "
        "DEC-U deg, DBH-U deg·nT, AMIL nT, DSFS -, DRFR m)",
    )

    @model_validator(mode="after")
    def _model_and_fields(self, info: ValidationInfo) -> UncertaintyParams:
        try:
            tool = configure(toolmodels.find(self.model, info), self.tool)
        except KeyError as exc:  # an unknown term or parameter
            raise ValueError(f"unknown tool fields: {exc.args[0]}") from None
        gyro_only = [
            name
            for name in ("latitude", "measured_sigma_azi", "init_sigma_azi")
            if getattr(self, name) is not None
        ]
        if gyro_only and "latitude" not in tool.needs:
            raise ValueError(f"{gyro_only} apply to gyro models, not {self.model!r}")
        if self.magnetic is not None and "magnetic" not in tool.needs:
            raise ValueError(f"magnetic applies to MWD models, not {self.model!r}")
        if self.init_sigma_azi is not None and "static_end_inc" not in tool.parameters:
            raise ValueError(f"init_sigma_azi applies to continuous models, not {self.model!r}")
        return self


def position_uncertainty(
    inputs: Mapping[str, pa.Table], params: UncertaintyParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Trajectory → trajectory with NEV covariance and error ellipses per station (those a
    trajectory carries from its stations file replaced), referred to the north of its
    azimuths: the error model works in true north (grid azimuths referred to it by the
    well's grid convergence, magnetic ones by the declination: the geomagnetic reference's,
    else the well's, else the geomagnetic model's), its covariance turned back
    (:func:`~pipeline.uncertainty.frames.listing_north`) before the ellipses are derived and
    a given ``tie_covariance`` (stated in the trajectory's north) is added."""
    table = without_uncertainty(inputs["trajectory"])
    tool = configured = configure(params.model, params.tool, toolmodels.of_run(ctx))
    toolmodels.record(ctx, tool, "model")
    well = ctx.well_for(well_of(table))  # its own file's header, not another input's
    north = north_reference_of(table, "azi")
    site = ModelSite()
    applied = None
    if "magnetic" in tool.needs:
        applied = applied_magnetic(params.magnetic, well, stage=STAGE)
        site = replace(site, magnetic=applied.reference)
    elif north == "magnetic" and well.declination is None:
        applied = _modelled_declination(well)
    frame = listing_north(
        north,
        stage=STAGE,
        convergence_deg=well.convergence_for(north),
        declination_deg=well.declination if applied is None else applied.reference.declination,
        modelled=True,
    )
    azi_deg = frame.true_azimuths(table.column("azi").to_numpy())  # the model's: true north
    if "latitude" in tool.needs:
        latitude = resolve_site(
            well, stage=STAGE, latitude=params.latitude, north_seeking=True
        ).latitude
        site = replace(site, latitude=latitude)
        tool, init_sigma = _measured(
            tool, params, latitude, _start_stop_sigma(inputs.get("stops"), table)
        )
    else:
        init_sigma = None
    md = table.column("md").to_numpy()
    inc = np.radians(table.column("inc").to_numpy())
    azi = np.radians(azi_deg)
    tvd = table.column("tvd").to_numpy()
    cov = np.zeros((md.size, 3, 3))
    offsets = survey_offsets(table)
    parents = parent_surveys(table, offsets)
    paths = hole_paths(md, offsets, parents)
    for k, path in enumerate(paths):
        lo, hi = int(offsets[k]), int(offsets[k + 1])
        # an undefined azimuth (vertical) moves nothing: the error model takes the next one's
        survey = Survey.of(md[path], inc[path], defined_azimuths(azi[path]), tvd[path])
        cov[lo:hi] = covariance(
            survey,
            tool,
            site,
            basis=params.basis,
            surface_tie=params.surface_tie,
            outside_validity=params.outside_validity,
        )[path.size - (hi - lo) :]
    cov = frame.covariance(cov)  # the model's true north → the trajectory's
    ties = tie_ons(table, offsets, parents, params.tie_covariance)
    if params.tie_covariance is not None:
        for k in range(len(parents)):
            if ties.surveys[_root(parents, k)].basis == "given":
                cov[int(offsets[k]) : int(offsets[k + 1])] += params.tie_covariance.matrix()
    warn_missing(ties, ctx.stage_id)
    columns: dict[str, object] = {name: table.column(name) for name in table.column_names}
    columns.update(covariance_columns(cov, params.confidence, params.outside_validity))
    out = PositionUncertainty.compiled().make_table(columns, north_reference=north)
    out = with_statements(
        out.replace_schema_metadata(table.schema.metadata),
        params.confidence,
        _stated_model(configured, params, init_sigma),
        ties,
    )
    return {"trajectory": with_magnetic(out, applied)}


def _modelled_declination(well: WellMetadata) -> AppliedMagnetic | None:
    """The geomagnetic model's reference at the well's site and date, whose declination
    refers a gyro model's magnetic-north azimuths to true north (None: the well states no
    site for it; the frame then refuses, saying how to give the declination)."""
    try:
        return applied_magnetic(None, well, stage=STAGE)
    except MissingMagneticError:
        return None


def tie_ons(
    table: pa.Table,
    offsets: np.ndarray,
    parents: list[int | None],
    given: TieCovariance | None,
) -> TieOnRecord:
    """Each survey's :class:`~pipeline.uncertainty.tieon.TieOn`: on its parent survey, else
    as :func:`~pipeline.uncertainty.tieon.outside_ties` has it (at the wellhead, ``given``,
    or not included)."""
    if table.num_rows == 0:
        return TieOnRecord(surveys=())
    md = table.column("md").to_numpy()
    names = table.column("survey").to_pylist() if "survey" in table.column_names else None

    def name(k: int) -> str | None:
        return None if names is None else str(names[int(offsets[k])])

    def first(k: int) -> float:
        return float(md[offsets[k]])

    orphans = [k for k, parent in enumerate(parents) if parent is None]
    found = outside_ties([(name(k), first(k)) for k in orphans], given)
    outside = dict(zip(orphans, found, strict=True))
    return TieOnRecord(
        surveys=tuple(
            outside[k]
            if parent is None
            else TieOn(survey=name(k), md=first(k), basis="survey", parent=name(parent))
            for k, parent in enumerate(parents)
        )
    )


def _root(parents: list[int | None], k: int) -> int:
    """The survey at the top of survey ``k``'s hole (itself where it has no parent)."""
    while (parent := parents[k]) is not None:
        k = parent
    return k


def parent_surveys(table: pa.Table, offsets: np.ndarray) -> list[int | None]:
    """Per survey, the survey it was tied on (a sidetrack's main bore, the run it continues:
    :func:`~pipeline.survey.tiein.tie_to_parents`, as the trajectory's ties record), None
    for one tied elsewhere."""
    calculation = calculation_of(table)
    ties = calculation.ties if calculation is not None else ()
    if len(ties) != len(offsets) - 1:
        return [None] * (len(offsets) - 1)
    index = {t.survey: k for k, t in enumerate(ties)}
    return [index.get(t.parent) if t.source == "survey" else None for t in ties]


def hole_paths(
    md: np.ndarray, offsets: np.ndarray, parents: list[int | None]
) -> list[NDArray[np.intp]]:
    """Per survey, the rows of its hole from the wellhead: its own, below its parent's
    (recursively) above its first MD — so that a sidetrack's errors are those of the hole
    it was drilled from down to the kick-off, then its own, in one propagation (it was
    propagated from zero at the kick-off, as if that point were known exactly)."""
    paths: list[NDArray[np.intp] | None] = [None] * (len(offsets) - 1)
    first = [float(md[a]) if b > a else 0.0 for a, b in itertools.pairwise(offsets)]
    for k in sorted(range(len(paths)), key=first.__getitem__):
        own = np.arange(offsets[k], offsets[k + 1], dtype=np.intp)
        parent = parents[k]
        above = None if parent is None else paths[parent]
        paths[k] = own if above is None else np.concatenate([above[md[above] < md[own[0]]], own])
    return [p for p in paths if p is not None]


def covariance_columns(
    cov: np.ndarray, confidence: float, outside: OutsideValidity = "refuse"
) -> dict[str, np.ndarray]:
    """The :class:`PositionUncertainty` columns of NEV covariances (n, 3, 3) (m²): the six
    covariance entries, the 1σ ellipse, vertical σ and their sizes at ``confidence``; with
    ``outside="flag"`` the ``outside_validity`` column (NaN covariance)."""
    ell = ellipses(cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1], cov[:, 2, 2])
    k2 = horizontal_scale(confidence)
    k1 = vertical_scale(confidence)
    return {
        "cov_nn": cov[:, 0, 0],
        "cov_ne": cov[:, 0, 1],
        "cov_nv": cov[:, 0, 2],
        "cov_ee": cov[:, 1, 1],
        "cov_ev": cov[:, 1, 2],
        "cov_vv": cov[:, 2, 2],
        "ellipse_major": ell.semi_major,
        "ellipse_minor": ell.semi_minor,
        "ellipse_azimuth": np.degrees(ell.azimuth) % 180.0,
        "sigma_v": ell.sigma_v,
        "ellipse_major_conf": k2 * ell.semi_major,
        "ellipse_minor_conf": k2 * ell.semi_minor,
        "vertical_conf": k1 * ell.sigma_v,
        **({"outside_validity": np.isnan(cov[:, 0, 0])} if outside == "flag" else {}),
    }


def _start_stop_sigma(stops: pa.Table | None, trajectory: pa.Table) -> tuple[float, float] | None:
    """Azimuth σ and inclination (deg) of the compassed stop nearest the trajectory's first
    MD (the tie of a continuous run); None without stops."""
    if stops is None or stops.num_rows == 0:
        return None
    md = stops.column("md").to_numpy(zero_copy_only=False)
    first = float(trajectory.column("md")[0].as_py()) if trajectory.num_rows else 0.0
    row = int(np.argmin(np.abs(md - first)))
    return float(stops.column("sigma_azi")[row].as_py()), float(stops.column("inc")[row].as_py())


def _measured(
    tool: ToolModel,
    params: UncertaintyParams,
    latitude: float,
    start_stop: tuple[float, float] | None,
) -> tuple[ToolModel, float | None]:
    """A gyro model with what the survey measured: the compassing scatter (GXY-RN) and, for a
    continuous model, the initial azimuth σ from ``params.init_sigma_azi`` or else from the
    wired start stop's σ when that stop is inclined at least the model's static end
    inclination (a near-vertical stop's azimuth does not initialise the run: the model's
    stationary terms and its inclination gate apply, as without stops); and that initial σ
    (deg; None: none taken)."""
    if params.measured_sigma_azi is not None:
        tool = with_measured_noise(tool, params.measured_sigma_azi, latitude)
    init_sigma = params.init_sigma_azi
    gate = tool.parameters.get("static_end_inc")
    if gate is None:
        return tool, None
    if init_sigma is None and start_stop is not None and np.radians(start_stop[1]) >= gate:
        init_sigma = start_stop[0]
    return (
        (tool, None) if init_sigma is None else (with_initial_azimuth(tool, init_sigma), init_sigma)
    )


def _stated_model(tool: ToolModel, params: UncertaintyParams, init_sigma: float | None) -> str:
    """The error model as the deliverables state it: its name and revision, and what the run
    changed of it — magnitudes given (``params.tool``: a term's with its unit, a model
    parameter's in the model file's), the compassing scatter measured, the initial azimuth
    σ taken — so that no ellipse passes for the published model's when it is not.
    ``tool``: the model as configured, before what the survey measured replaced terms."""
    units = {t.name: t.unit for t in tool.terms}
    changed = []
    for key, value in params.tool.items():
        param = PARAMETER_ALIASES.get(key, key)
        if param in tool.parameters:
            changed.append(f"{param} {value:g} (the model file's unit)")
        else:
            name = term_for(tool, key)
            changed.append(f"{name} {value:g} {units[name]}")
    if params.measured_sigma_azi is not None:
        changed.append(
            f"GXY-RN from a measured azimuth scatter of {params.measured_sigma_azi:g} deg"
        )
    if init_sigma is not None:
        given = "given" if params.init_sigma_azi is not None else "the start stop's"
        changed.append(f"initial azimuth sigma {init_sigma:.4g} deg ({given})")
    stated = model_words(tool.name, tool.revision)
    return f"{stated} with {', '.join(changed)}" if changed else stated


MAGNETIC_KEY = b"gyropipe.magnetic_reference"
RUN_MAGNETIC_KEY = b"gyropipe.magnetic_reference_by_run"


class RunMagnetic(BaseModel):
    """The geomagnetic references applied to the runs of one survey, by run id, where they
    differ (runs of different dates or sites: each run's its own)."""

    model_config = ConfigDict(frozen=True, extra="forbid")
    runs: dict[str, AppliedMagnetic]


def with_magnetic(
    table: pa.Table, applied: AppliedMagnetic | Mapping[str, AppliedMagnetic] | None
) -> pa.Table:
    """``table`` with the geomagnetic reference a stage applied in its schema metadata: one,
    or by run id (a definitive survey's): one when every run's is the same."""
    if isinstance(applied, Mapping):
        distinct = list(dict.fromkeys(applied.values()))
        if len(distinct) > 1:
            return with_record(table, RUN_MAGNETIC_KEY, RunMagnetic(runs=dict(applied)))
        applied = distinct[0] if distinct else None
    return table if applied is None else with_record(table, MAGNETIC_KEY, applied)


def magnetic_of(table: pa.Table | None) -> AppliedMagnetic | None:
    """The one geomagnetic reference recorded in a table's schema metadata, if any."""
    return None if table is None else record_of(table, MAGNETIC_KEY, AppliedMagnetic)


def magnetic_words(ctx: ReportContext, port: str = "trajectory") -> str:
    """ "; geomagnetic reference: total field …, dip …, declination … (source)" of the
    report's ``port`` table, each run's where they differ ('' when it records none)."""
    table = ctx.tables.get(port)
    by_run = None if table is None else record_of(table, RUN_MAGNETIC_KEY, RunMagnetic)
    if by_run is not None:
        each = "; ".join(f"run {run}: {applied.words()}" for run, applied in by_run.runs.items())
        return f"; geomagnetic references: {each}"
    applied = magnetic_of(table)
    return "" if applied is None else f"; geomagnetic reference: {applied.words()}"


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="position_uncertainty",
            func=position_uncertainty,
            description="Propagate an ISCWSA/OWSG error model (a tool-model file, shipped "
            "or a vendor's) into NEV covariance and error ellipses per station.",
            inputs={"trajectory": Trajectory, "stops": CompassStations},
            optional_inputs=frozenset({"stops"}),
            outputs={"trajectory": PositionUncertainty},
            params=UncertaintyParams,
        )
    )


def uncertainty_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """Position uncertainty in the report: the error model by its title, the propagation
    paper (and the gyro model's for a gyro tool), the confidence of the ellipses."""
    from pipeline.reports.literature import ERROR_MODEL, GYRO_ERROR_MODEL

    confidence = float(stage.params.get("confidence", 0.0)) * 100
    title, gyro = ctx.error_model(str(stage.params["model"]))
    method = f"{title} error model propagated as in {ctx.cite(ERROR_MODEL)}"
    also = f" with the gyro terms of {ctx.cite(GYRO_ERROR_MODEL)}" if gyro else ""
    return MethodNote(
        "Position uncertainty",
        f"{method}{also}, ellipses at {confidence:g} %{magnetic_words(ctx)}",
    )


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("position_uncertainty", method=uncertainty_method))

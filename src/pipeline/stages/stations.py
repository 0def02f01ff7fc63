"""Built-in plugin: survey methods, interpolation along the path, north-reference conversion."""

from __future__ import annotations

import datetime as dt
import itertools
from collections.abc import Callable, Mapping

import numpy as np
import pyarrow as pa
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from pipeline.contracts import column
from pipeline.earth.geomagnetic import ModelKey
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.stages.survey import (
    MinCurveParams,
    calculation_note,
    checked,
    tie_ins,
    trajectory_columns,
)
from pipeline.survey.calculation import SurveyCalculation, with_calculation
from pipeline.survey.interpolate import Interpolated, interpolate_md, interpolate_tvd
from pipeline.survey.methods import Method, build_turn_rates
from pipeline.survey.north import convergence_at, convert_table, declination_at
from pipeline.survey.stations import north_reference_of, station_angles, survey_offsets
from pipeline.tables import DLS_UNIT, Stations, Trajectory
from pipeline.uncertainty.points import uncertainty_on_points
from pipeline.well import NorthReference, WellMetadata, attach, well_of


class MethodTrajectory(Trajectory):
    """A trajectory computed by a named survey method, with build and turn rates."""

    build: float = column(unit=DLS_UNIT, description="build rate ΔI/ΔMD from the previous station")
    turn: float = column(
        unit=DLS_UNIT, description="turn rate ΔA/ΔMD from the previous station (short way)"
    )


class PathPoints(Stations):
    """Points interpolated on the minimum-curvature path (positions NED from the wellhead)."""

    md: float = column(  # points, not stations: no course between them, any MD step
        unit="m", monotonic="strict", description="measured depth from the depth reference"
    )
    azi: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        undefined_at_vertical=True,
        description="azimuth in [0, 360), clockwise from north (NaN: undefined, vertical)",
    )
    tvd: float = column(unit="m", description="true vertical depth below the depth reference")
    north: float = column(unit="m", description="northing from the wellhead")
    east: float = column(unit="m", description="easting from the wellhead")
    interpolated: bool = column(
        unit=None,
        default=False,
        description="the point lies between survey stations: its uncertainty columns are NaN "
        "(written where the trajectory has them; a point at a station keeps the station's)",
    )


class TvdCrossings(PathPoints):
    """Where the path crosses requested TVDs, in MD order."""

    target_tvd: float = column(unit="m", description="the requested TVD this point crosses")


# --- survey_method ------------------------------------------------------------------------------


class SurveyMethodParams(MinCurveParams):
    """Parameters of the survey-method stage (lengths m, angles deg)."""

    method: Method = Field("minimum_curvature", description="survey calculation method")


def survey_method(
    inputs: Mapping[str, pa.Table], params: SurveyMethodParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Stations → trajectory by the chosen method, with build and turn rates."""
    stations = inputs["stations"]
    columns, ties = trajectory_columns(
        stations, params, tie_ins(stations, params, ctx), params.method
    )
    md, inc, azi = station_angles(stations)
    build, turn = (
        build_turn_rates(md, np.radians(inc), np.radians(azi), offsets=survey_offsets(stations))
        if stations.num_rows
        else (np.empty(0), np.empty(0))
    )
    table = MethodTrajectory.compiled().make_table(
        columns | {"build": build, "turn": turn},
        north_reference=north_reference_of(stations, "azi"),
    )
    calculation = SurveyCalculation(method=params.method, vs_azimuth=params.vs_azimuth, ties=ties)
    return {"trajectory": checked(with_calculation(table, calculation), stations, params, ctx)}


# --- interpolation ------------------------------------------------------------------------------


class InterpolateMdParams(BaseModel):
    """Parameters of MD interpolation: explicit MDs, a spacing, or both (merged)."""

    model_config = ConfigDict(extra="forbid")
    md: list[float] | None = Field(
        None, description="MDs to interpolate at, m; those outside a survey's range are skipped"
    )
    spacing: float | None = Field(
        None, gt=0, description="also every multiple of this spacing within each survey, m"
    )
    include_stations: bool = Field(False, description="also output the stations themselves")

    @model_validator(mode="after")
    def _something(self) -> InterpolateMdParams:
        if self.md is None and self.spacing is None and not self.include_stations:
            raise ValueError("give md, spacing or include_stations")
        return self


class InterpolateTvdParams(BaseModel):
    """Parameters of TVD interpolation."""

    model_config = ConfigDict(extra="forbid")
    tvd: list[float] = Field(min_length=1, description="TVDs whose every crossing is wanted, m")


def _per_survey(
    trajectory: pa.Table,
    solve: Callable[[np.ndarray, np.ndarray, np.ndarray, tuple[float, float, float]], Interpolated],
) -> tuple[list[Interpolated], list[int], NDArray[np.intp], NDArray[np.bool_]]:
    """The points of each survey of two stations or more, the first row of each, and per
    point (in order) the trajectory row of the station at or above it and whether it is
    that station."""
    md, inc_deg, azi_deg = station_angles(trajectory)
    north = trajectory.column("north").to_numpy()
    east = trajectory.column("east").to_numpy()
    tvd = trajectory.column("tvd").to_numpy()
    offsets = survey_offsets(trajectory)
    found: list[Interpolated] = []
    firsts: list[int] = []
    above: list[NDArray[np.intp]] = []
    for lo, hi in itertools.pairwise(offsets):
        if hi - lo < 2:
            continue
        tie = (float(north[lo]), float(east[lo]), float(tvd[lo]))
        sl = slice(int(lo), int(hi))
        points = solve(md[sl], np.radians(inc_deg[sl]), np.radians(azi_deg[sl]), tie)
        found.append(points)
        firsts.append(int(lo))
        above.append(lo + np.searchsorted(md[sl], points.md, side="right").astype(np.intp) - 1)
    rows = np.concatenate(above) if above else np.zeros(0, np.intp)
    at_station = md[rows] == (np.concatenate([p.md for p in found]) if found else np.zeros(0))
    return found, firsts, rows, at_station


def _points_table(
    trajectory: pa.Table,
    found: list[Interpolated],
    firsts: list[int],
    contract: type[PathPoints],
    extra: Mapping[str, object] | None = None,
) -> pa.Table:
    columns: dict[str, object] = {}
    if "survey" in trajectory.column_names:
        ids = trajectory.column("survey").to_pylist()
        columns["survey"] = [ids[f] for f, p in zip(firsts, found, strict=True) for _ in p.md]
    cat = {
        key: np.concatenate([getattr(p, key) for p in found]) if found else np.zeros(0)
        for key in ("md", "inc", "azi", "tvd", "north", "east")
    }
    columns.update(
        md=cat["md"],
        inc=np.degrees(cat["inc"]),
        azi=np.degrees(cat["azi"]) % 360.0,
        tvd=cat["tvd"],
        north=cat["north"],
        east=cat["east"],
    )
    columns.update(extra or {})
    return contract.compiled().make_table(
        columns, north_reference=north_reference_of(trajectory, "azi")
    )


def interpolate_md_stage(
    inputs: Mapping[str, pa.Table], params: InterpolateMdParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Trajectory → points on its minimum-curvature path at requested MDs."""
    trajectory = inputs["trajectory"]

    def solve(
        md: np.ndarray, inc: np.ndarray, azi: np.ndarray, tie: tuple[float, float, float]
    ) -> Interpolated:
        wanted = [np.asarray(params.md or [], dtype=np.float64)]
        if params.spacing is not None:
            step = params.spacing
            first = np.ceil(md[0] / step)
            last = np.floor(md[-1] / step)
            wanted.append(np.arange(first, last + 1.0) * step)
        if params.include_stations:
            wanted.append(md)
        at = np.unique(np.concatenate(wanted))
        at = at[(at >= md[0]) & (at <= md[-1])]
        return interpolate_md(md, inc, azi, at, tie=tie)

    found, firsts, above, at_station = _per_survey(trajectory, solve)
    table = _points_table(trajectory, found, firsts, PathPoints)
    return {"points": uncertainty_on_points(trajectory, table, above, at_station, ctx.stage_id)}


def interpolate_tvd_stage(
    inputs: Mapping[str, pa.Table], params: InterpolateTvdParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Trajectory → every crossing of its minimum-curvature path with each requested TVD."""
    trajectory = inputs["trajectory"]
    targets = np.unique(np.asarray(params.tvd, dtype=np.float64))

    def solve(
        md: np.ndarray, inc: np.ndarray, azi: np.ndarray, tie: tuple[float, float, float]
    ) -> Interpolated:
        return interpolate_tvd(md, inc, azi, targets, tie=tie)

    found, firsts, above, at_station = _per_survey(trajectory, solve)
    target_tvd = np.concatenate([targets[p.target] for p in found]) if found else np.zeros(0)
    table = _points_table(trajectory, found, firsts, TvdCrossings, extra={"target_tvd": target_tvd})
    return {"crossings": uncertainty_on_points(trajectory, table, above, at_station, ctx.stage_id)}


# --- north reference ----------------------------------------------------------------------------


class NorthReferenceParams(BaseModel):
    """Parameters of the north-reference conversion (angles deg). Corrections not given are
    the well's ``grid_convergence`` and ``declination`` (the site's), else derived from the
    well header: γ of grid-north azimuths from the grid convergence applied to them
    (``grid_convergence_applied``, a WITSML gridCorUsed), else from ``crs`` at the wellhead;
    D from the geomagnetic ``model`` at the wellhead on ``date`` (default: the survey date;
    refused for trajectories begun on several days, whose stations need each its own D).
    A correction applied to the azimuths is never taken for the site's: a gridCorUsed of 0 on
    true-north azimuths says no grid correction was applied, not that γ is 0. The output's
    well metadata records the new north reference, the corrections used and the ones now
    applied to the azimuths, so exports state them."""

    model_config = ConfigDict(extra="forbid")
    target: NorthReference = Field(description="north reference to convert the azimuths to")
    convergence: float | None = Field(
        None, description="grid convergence γ, deg (grid north east of true north positive)"
    )
    crs: str | None = Field(None, description="projected CRS of the grid (EPSG:…) for γ")
    declination: float | None = Field(
        None, description="magnetic declination D, deg (east positive)"
    )
    model: ModelKey = Field("wmm2025", description="geomagnetic model for D")
    date: dt.date | None = Field(None, description="date for D; default the well's survey date")


def _sources(stations: pa.Table) -> set[str]:
    """The north references of the table's azimuth columns."""
    refs: set[str] = set()
    for fld in stations.schema:
        raw = (fld.metadata or {}).get(b"north_reference")
        if raw is not None:
            refs.add(raw.decode())
    return refs


def north_reference_stage(
    inputs: Mapping[str, pa.Table], params: NorthReferenceParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Stations → the same stations with every azimuth column converted to ``target`` north."""
    stations = inputs["stations"]
    sources = _sources(stations)
    refs = sources | {params.target}
    converting = len(refs) > 1
    well = ctx.well_for(well_of(stations))  # their own file's header, not another input's
    convergence = _correction("convergence", params.convergence, well.grid_convergence)
    declination = _correction("declination", params.declination, well.declination)
    used: dict[str, object] = {"north_reference": params.target}
    if converting and "grid" in refs:
        convergence = _grid_convergence(convergence, params, well, "grid" in sources)
        used["grid_convergence"] = convergence
        used["grid_convergence_applied"] = convergence if params.target == "grid" else 0.0
    if converting and "magnetic" in refs and declination is None:
        date = params.date or well.model_date("give `declination`, or `date` (one for all)")
        if well.latitude is None or well.longitude is None or date is None:
            raise ValueError(
                "magnetic north needs `declination`, or the well's latitude, longitude "
                "and a date (`date` or the well's survey_date)"
            )
        declination = declination_at(
            well.latitude, well.longitude, date, height_m=well.elevation or 0.0, model=params.model
        )
    if converting and "magnetic" in refs:
        used["declination"] = declination
        used["declination_applied"] = 0.0 if params.target == "magnetic" else declination
    table = convert_table(
        stations, params.target, convergence_deg=convergence, declination_deg=declination
    )
    ctx.update_well(WellMetadata.model_validate(used))
    header = (well_of(stations) or WellMetadata()).merged(used)
    return {"stations": attach(table, header)}


def _correction(name: str, given: float | None, well: float | None) -> float | None:
    """The stage's correction or the well's; both given must agree (exports state one)."""
    if given is not None and well is not None and given != well:
        field = "grid_convergence" if name == "convergence" else name
        raise ValueError(f"{name} {given} contradicts the well's {field} {well}: give one of them")
    return given if given is not None else well


def _grid_convergence(
    given: float | None, params: NorthReferenceParams, well: WellMetadata, from_grid: bool
) -> float:
    """γ for a conversion to or from grid north: the one given (stage or well), else the one
    applied to grid-north azimuths, else the CRS's at the wellhead. Grid-north azimuths can
    only be taken back to true north by the γ that was applied to them."""
    applied = well.grid_convergence_applied if from_grid else None
    if given is not None and applied is not None and given != applied:
        raise ValueError(
            f"convergence {given} contradicts the grid convergence applied to these grid-north "
            f"azimuths ({applied}, the well's grid_convergence_applied): they can only be "
            "referred back to true north by the correction applied to them"
        )
    if given is not None:
        return given
    if applied is not None:
        return applied
    if params.crs is None or well.latitude is None or well.longitude is None:
        raise ValueError(
            "grid north needs `convergence`, or `crs` and the well's latitude and longitude"
        )
    return convergence_at(well.latitude, well.longitude, params.crs)


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="survey_method",
            func=survey_method,
            description="Integrate stations into a trajectory by a chosen method (minimum "
            "curvature, tangential, balanced tangential, average angle, radius of curvature), "
            "with build and turn rates.",
            inputs={"stations": Stations},
            outputs={"trajectory": MethodTrajectory},
            params=SurveyMethodParams,
        )
    )
    register(
        StageDef(
            name="interpolate_md",
            func=interpolate_md_stage,
            description="Points on the minimum-curvature path of a trajectory at given MDs "
            "or a regular spacing.",
            inputs={"trajectory": Trajectory},
            outputs={"points": PathPoints},
            params=InterpolateMdParams,
        )
    )
    register(
        StageDef(
            name="interpolate_tvd",
            func=interpolate_tvd_stage,
            description="Every crossing of the minimum-curvature path of a trajectory with "
            "given TVDs.",
            inputs={"trajectory": Trajectory},
            outputs={"crossings": TvdCrossings},
            params=InterpolateTvdParams,
        )
    )
    register(
        StageDef(
            name="north_reference",
            func=north_reference_stage,
            description="Convert the azimuth columns of stations to true, grid or magnetic "
            "north (γ from a CRS, D from a geomagnetic model, or given).",
            inputs={"stations": Stations},
            outputs={"stations": Stations},
            params=NorthReferenceParams,
        )
    )


def calculation_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The survey calculation in the report: the method chosen, in words."""
    return calculation_note(str(stage.params.get("method", "?")).replace("_", " "), ctx)


def north_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The north reference conversion in the report."""
    return MethodNote("North reference conversion", f"to {stage.params.get('target', '?')} north")


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("survey_method", method=calculation_method))
    register(ReportDef("north_reference", method=north_method))

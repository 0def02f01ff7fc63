"""Built-in plugin: survey integration stages and survey QC checks."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.contracts import SOURCE_KEY
from pipeline.errors import SurveyCheckWarning, warn_input
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.registry import CheckDef, StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.survey.calculation import SurveyCalculation, calculation_of, with_calculation
from pipeline.survey.crosscheck import check_positions, position_check_of, with_position_check
from pipeline.survey.methods import Method, survey_positions
from pipeline.survey.mincurve import closure, vertical_section
from pipeline.survey.stations import north_reference_of, station_angles, survey_offsets
from pipeline.survey.tiein import (
    SurveyTie,
    chosen_tie,
    listed_ties,
    parent_of,
    tie_difference,
    tie_to_parents,
    ties_words,
)
from pipeline.tables import (
    DLS_COURSE_M,
    DLS_UNIT,
    STATION_TEXT_COLUMNS,
    CheckResults,
    Stations,
    Trajectory,
)
from pipeline.uncertainty.carried import carried_uncertainty
from pipeline.uncertainty.stated import is_carried, statement_of
from pipeline.well import WellMetadata


class MinCurveParams(BaseModel):
    """Parameters of the minimum-curvature stage (lengths m, angles deg)."""

    model_config = ConfigDict(extra="forbid")
    vs_azimuth: float = Field(
        0.0, description="vertical-section plane azimuth, deg, same north reference as the survey"
    )
    tie_north: float | None = Field(
        None,
        description="northing of each survey's first station from the wellhead, m; default: "
        "the stations file's own where it lists TVD, north and east there, else 0",
    )
    tie_east: float | None = Field(
        None,
        description="easting of each survey's first station from the wellhead, m; default: "
        "the stations file's own where it lists TVD, north and east there, else 0",
    )
    tie_tvd: float | None = Field(
        None,
        description="TVD of each survey's first station, m; default: the stations file's own "
        "where it lists TVD, north and east there, else its MD (straight vertical hole above "
        "the first station). Giving any of tie_tvd, tie_north, tie_east ties every survey "
        "at the stage's (the others at their fallbacks), warned where the file lists another",
    )
    position_tolerance: float = Field(
        0.1,
        ge=0,
        description="where the stations file lists its own TVD/north/east: the largest 3-D "
        "difference from the recomputed position at a survey's first station (and from the "
        "stage's tie, where given), m, before a warning (a vendor's listing rounds positions "
        "to 0.01 m or 0.1 ft)",
    )
    position_tolerance_rel: float = Field(
        1e-4,
        ge=0,
        description="… plus this much per m of MD from the first station (1e-4: 0.1 m per "
        "km, what angles rounded to 0.01° allow)",
    )


def tie_ins(stations: pa.Table, params: MinCurveParams, ctx: StageContext) -> tuple[SurveyTie, ...]:
    """Where each survey of ``stations`` is tied: at the stage's tie where any of
    ``tie_tvd``, ``tie_north``, ``tie_east`` is given (a :class:`SurveyCheckWarning` where
    the file lists a tie-on more than ``position_tolerance`` from it), else at the TVD,
    north and east the file lists at its first station, else at TVD = MD, N = E = 0."""
    if stations.num_rows == 0:
        return ()
    offsets = survey_offsets(stations)
    md = stations.column("md").to_numpy(zero_copy_only=False).astype(float)
    names = stations.column("survey").to_pylist() if "survey" in stations.column_names else None
    given = (params.tie_tvd, params.tie_north, params.tie_east)
    ties = []
    for lo, listed in zip(offsets[:-1].tolist(), listed_ties(stations, offsets), strict=True):
        survey = None if names is None else str(names[lo])
        tie = chosen_tie(survey, float(md[lo]), listed, given)
        if listed is not None:
            warn_other_tie(tie, listed, params.position_tolerance, ctx.stage_id)
        ties.append(tie)
    return tuple(ties)


def warn_other_tie(
    tie: SurveyTie, listed: np.ndarray | None, tolerance: float, stage_id: str
) -> None:
    """Warn where the stage's ``tie`` lies more than ``tolerance`` (m) from the tie-on the
    stations file lists (TVD, north, east, m; None: it lists none)."""
    if tie.source != "pipeline" or listed is None:
        return
    gap = tie_difference(tie, listed)
    if gap <= tolerance:
        return
    named = f"survey {tie.survey!r}" if tie.survey is not None else "the survey"
    warnings.warn(
        f"stage {stage_id!r}: {named} is tied at the stage's tie_tvd, tie_north, tie_east "
        f"(TVD {tie.tvd:.2f} m, N {tie.north:.2f} m, E {tie.east:.2f} m at MD {tie.md:.2f} m), "
        f"{gap:.3f} m from the tie-on its stations file lists there (TVD {listed[0]:.2f} m, "
        f"N {listed[1]:.2f} m, E {listed[2]:.2f} m; position_tolerance {tolerance:g} m): the "
        "stage's applied (leave the three unset to tie at the file's)",
        SurveyCheckWarning,
        stacklevel=3,
    )


def trajectory_columns(
    stations: pa.Table,
    params: MinCurveParams,
    ties: tuple[SurveyTie, ...],
    method: Method = "minimum_curvature",
) -> tuple[dict[str, object], tuple[SurveyTie, ...]]:
    """Trajectory columns of every survey of ``stations`` by ``method``, each tied at its
    tie of ``ties`` (:func:`tie_ins`), in one call (none of no stations: an empty table is
    a legal stage output), and the ties applied: where the stage gives no tie, a survey
    whose file lists none that begins within another survey's depths (a sidetrack, a run
    continuing another) is tied on that survey (:func:`~pipeline.survey.tiein.tie_to_parents`;
    it was left at TVD = MD, N = E = 0 with a warning)."""
    if stations.num_rows == 0:
        empty: dict[str, object] = {
            c.name: np.empty(0) for c in Trajectory.compiled().columns if c.required
        }
        if "survey" in stations.column_names:
            empty = {"survey": stations.column("survey"), **empty}
        return empty, ties
    md, inc_deg, azi_deg = station_angles(stations)
    offsets = survey_offsets(stations)
    inc, azi = np.radians(inc_deg), np.radians(azi_deg)
    result = survey_positions(
        method,
        md,
        inc,
        azi,
        offsets=offsets,
        tie_north=np.array([t.north for t in ties]),
        tie_east=np.array([t.east for t in ties]),
        tie_tvd=np.array([t.tvd for t in ties]),
    )
    position = np.column_stack([result.tvd, result.north, result.east])
    if len(ties) > 1 and all(
        v is None for v in (params.tie_tvd, params.tie_north, params.tie_east)
    ):
        ties = tie_to_parents(md, inc, azi, offsets, position, ties)
    tvd, north, east = position.T
    distance, direction = closure(north, east)
    columns: dict[str, object] = {
        "md": md,
        "inc": inc_deg,
        "azi": azi_deg,
        "tvd": tvd,
        "north": north,
        "east": east,
        "dogleg": np.degrees(result.dogleg),
        "dls": np.degrees(result.dls) * DLS_COURSE_M,
        "vertical_section": vertical_section(north, east, np.radians(params.vs_azimuth)),
        "closure_distance": distance,
        "closure_direction": np.degrees(direction) % 360.0,
    }
    if "survey" in stations.column_names:
        columns = {"survey": stations.column("survey"), **columns}
    for name in STATION_TEXT_COLUMNS:
        if name in stations.column_names:
            columns[name] = stations.column(name)
    return columns, ties


def checked(
    trajectory: pa.Table, stations: pa.Table, params: MinCurveParams, ctx: StageContext
) -> pa.Table:
    """``trajectory`` with the position uncertainty its stations file states carried
    (:func:`carry`) and the check of the file's own TVD/north/east against its positions
    recorded (:mod:`pipeline.survey.crosscheck`; none if the file lists none); a
    :class:`~pipeline.errors.SurveyCheckWarning` names the first station beyond tolerance
    (and, where uncertainty was carried, that it was computed for the file's positions)."""
    trajectory = carry(trajectory, stations, ctx)
    check = check_positions(
        stations,
        survey_offsets(stations),
        tuple(trajectory.column(c).to_numpy() for c in ("tvd", "north", "east")),
        params.position_tolerance,
        params.position_tolerance_rel,
    )
    if check is None:
        return trajectory
    if check.beyond_md:
        other = (
            "; the position uncertainty the file states was computed for its own positions, "
            "not for these (carried as it states it)"
            if is_carried(trajectory)
            else ""
        )
        warnings.warn(
            f"stage {ctx.stage_id!r}: {check.summary()}{other}", SurveyCheckWarning, stacklevel=2
        )
    return with_position_check(trajectory, check)


def carry(trajectory: pa.Table, stations: pa.Table, ctx: StageContext) -> pa.Table:
    """``trajectory`` (of ``stations``' rows, in their order) with the uncertainty columns
    its stations file states, by :func:`~pipeline.uncertainty.carried.carried_uncertainty`;
    an :class:`~pipeline.errors.InputFileWarning` naming the file and the columns of each
    part of it refused."""
    found = carried_uncertainty(stations)
    source = (stations.schema.metadata or {}).get(SOURCE_KEY, b"").decode() or "the stations"
    for reason in found.refused:
        warn_input(
            source,
            f"stage {ctx.stage_id!r}: of the position uncertainty the file states, not carried "
            f"to the trajectory: {reason}",
        )
    return found.onto(trajectory)


def min_curve(
    inputs: Mapping[str, pa.Table], params: MinCurveParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Stations → trajectory by minimum curvature, every survey of the table in one call,
    each tied at its tie-on (:func:`tie_ins`), checked against the positions the stations
    file lists (:func:`checked`)."""
    stations = inputs["stations"]
    columns, ties = trajectory_columns(stations, params, tie_ins(stations, params, ctx))
    table = Trajectory.compiled().make_table(
        columns, north_reference=north_reference_of(stations, "azi")
    )
    calculation = SurveyCalculation(
        method="minimum_curvature", vs_azimuth=params.vs_azimuth, ties=ties
    )
    warn_detached(table, ctx)
    return {"trajectory": checked(with_calculation(table, calculation), stations, params, ctx)}


DETACHED_M = 1.0
"""Distance (m) between a survey's tie-in and where another survey of the table puts the
hole at its first MD beyond which :func:`warn_detached` warns (positions interpolated
linearly between the other's stations: centimetres off along a curve)."""


def warn_detached(trajectory: pa.Table, ctx: StageContext) -> None:
    """Warn of each survey that begins within another survey's depths
    (:func:`~pipeline.survey.tiein.parent_of`) — a sidetrack listed beside its main bore, a
    second run continuing the first — yet is tied elsewhere (at the stage's tie, or at the
    tie-on its file lists) more than :data:`DETACHED_M` from where the other survey puts
    the hole at that MD; one tied on the other (:func:`trajectory_columns`) is not."""
    if "survey" not in trajectory.column_names:
        return
    offsets = survey_offsets(trajectory)
    md = trajectory.column("md").to_numpy()
    xyz = np.stack([trajectory.column(c).to_numpy() for c in ("tvd", "north", "east")], axis=1)
    names = trajectory.column("survey")
    for k, lo in enumerate(offsets[:-1].tolist()):
        parent = parent_of(md, offsets, k)
        if parent is None:
            continue
        a, b = int(offsets[parent]), int(offsets[parent + 1])
        there = np.array([np.interp(md[lo], md[a:b], xyz[a:b, i]) for i in range(3)])
        gap = float(np.linalg.norm(there - xyz[lo]))
        if gap > DETACHED_M:
            warnings.warn(
                f"stage {ctx.stage_id!r}: survey {names[lo].as_py()!r} begins at MD "
                f"{md[lo]:.2f} m, where survey {names[a].as_py()!r} puts the hole at about "
                f"TVD {there[0]:.2f} m, N {there[1]:.2f} m, E {there[2]:.2f} m, but is tied at "
                f"TVD {xyz[lo, 0]:.2f} m, N {xyz[lo, 1]:.2f} m, E {xyz[lo, 2]:.2f} m "
                f"({gap:.2f} m away): its positions are not its hole's. Give its tie-in: "
                "its stations file's TVD, north and east at its first station, or the "
                "stage's tie_tvd, tie_north and tie_east with a stations file of that "
                "survey alone",
                SurveyCheckWarning,
                stacklevel=2,
            )


class DlsLimitParams(BaseModel):
    """Parameters of the dogleg-severity check."""

    model_config = ConfigDict(extra="forbid")
    limit: float = Field(10.0, gt=0, description=f"largest plausible dogleg severity, {DLS_UNIT}")


def dls_limit(table: pa.Table, params: DlsLimitParams, well: WellMetadata) -> pa.Table:
    """Flag stations whose dogleg severity exceeds a limit (survey busts, bad stations)."""
    dls = table.column("dls").to_numpy()
    n = len(dls)
    return CheckResults.compiled().make_table(
        {
            "check": ["dls_limit"] * n,
            "row": np.arange(n),
            "md": table.column("md"),
            "value": dls,
            "limit": np.full(n, params.limit),
            "unit": [DLS_UNIT] * n,
            "passed": dls <= params.limit,
        }
    )


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="minimum_curvature",
            func=min_curve,
            description="Integrate stations into a trajectory by minimum curvature "
            "(TVD, north, east, dogleg, DLS, vertical section, closure).",
            inputs={"stations": Stations},
            outputs={"trajectory": Trajectory},
            params=MinCurveParams,
        )
    )


@hookimpl
def gyropipe_register_checks(register: Callable[[CheckDef], None]) -> None:
    register(
        CheckDef(
            name="dls_limit",
            description="dogleg severity of each station within a plausible limit",
            contract=Trajectory,
            func=dls_limit,
            params=DlsLimitParams,
        )
    )


def calculation_note(method: str, ctx: ReportContext) -> MethodNote:
    """The survey calculation ``method`` (in words) in the report, where each survey was
    tied on, and the check against the stations file's own positions when there was one."""
    trajectory = ctx.tables.get("trajectory")
    check = position_check_of(trajectory) if trajectory is not None else None
    calculation = calculation_of(trajectory) if trajectory is not None else None
    parts = [method]
    if calculation is not None and calculation.ties:
        parts.append(ties_words(calculation.ties))
    if check is not None:
        parts.append(check.summary())
    note = "; ".join(parts)
    stated = statement_of(trajectory) if trajectory is not None else None
    if stated is not None and (carried := stated.source_words()):
        note = f"{note}. {carried}"
    return MethodNote("Survey calculation", note)


def mincurve_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The survey calculation in the report."""
    return calculation_note("minimum curvature", ctx)


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("minimum_curvature", method=mincurve_method))

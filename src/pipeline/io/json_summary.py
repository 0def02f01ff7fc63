"""Built-in plugin: the JSON summary of a survey, for machines (writer ``json_summary``).

One JSON object (:class:`SurveySummary`, JSON Schema in ``schemas/writers/``): the well
header, the run's provenance, the azimuths' north reference, the calculation method, and per
survey the station count, MD range, the final station's position, the largest dogleg
severity over the courses of at least 10 m, or the run's survey report's
``min_course_length`` (the report's rule: a shorter course's DLS is a spike of angle errors,
not the hole's curvature) and, when the trajectory carries position
uncertainty, the error ellipse at TD; the uncertainty as its columns state it
(``uncertainty``: error model, confidence, the σ convention of each column family, the
largest horizontal semi-major axis and TD's; absent without uncertainty columns); then QC
counts per check (with ``file_positions``: the stations file's own positions against the
recomputed ones, when the trajectory records that check), flagged and rejected stations,
and every station recorded but dropped (by the validity checks or compassing: MD, what
dropped it, why). Lengths in m, angles in degrees, DLS in °/30 m, drift rates in °/h
(``units`` says so in the document too).

Through the ``export`` stage it takes the tables ``trajectory`` (required), ``qc``,
``qc_summary`` (the validity checks' verdict per station), ``stations``, ``rejects``,
``drift`` (a free-gyro survey's corrected readings: the drift rate applied, its σ, source
and caveats) and ``inout`` (its in-run/out-run comparison, counted as two checks);
through ``write`` one trajectory table.
"""

from __future__ import annotations

import datetime as dt
import itertools
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from pydantic import BaseModel, ConfigDict, Field

from pipeline.contracts import NORTH_KEY
from pipeline.drift.correction import DriftRate, drift_rate_of
from pipeline.errors import EmptyTableError
from pipeline.hookspecs import hookimpl
from pipeline.qc.dropped import dropped_stations, is_rejects
from pipeline.qc.verdict import inout_checks
from pipeline.registry import Provenance, WriterDef
from pipeline.survey.calculation import SurveyCalculation, calculation_of
from pipeline.survey.courses import MIN_COURSE, max_dls
from pipeline.survey.crosscheck import position_check_of
from pipeline.survey.stations import survey_offsets
from pipeline.tables import Trajectory
from pipeline.uncertainty.stated import interpolated_rows, statement_of
from pipeline.uncertainty.tieon import TieOn
from pipeline.version import __version__
from pipeline.well import NorthReference, WellMetadata

FORMAT: Final = "gyropipe.survey-summary"
FORMAT_VERSION: Final = "1.0"
ELLIPSE_COLUMNS = ("ellipse_major", "ellipse_minor", "ellipse_azimuth", "sigma_v")


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Units(_Model):
    """Units of the document's numbers."""

    length: Literal["m"] = "m"
    angle: Literal["deg"] = "deg"
    dls: Literal["deg/30m"] = "deg/30m"
    drift_rate: Literal["deg/h"] = "deg/h"


class Station(_Model):
    """A station's position: NED from the wellhead, TVD below the depth reference."""

    md: float = Field(description="measured depth, m")
    inc: float = Field(description="inclination, deg")
    azi: float | None = Field(
        description="azimuth, deg, in the document's north reference (null: undefined, the "
        "station is vertical)"
    )
    tvd: float = Field(description="true vertical depth, m")
    north: float = Field(description="northing from the wellhead, m")
    east: float = Field(description="easting from the wellhead, m")
    vertical_section: float = Field(description="vertical section, m")
    closure_distance: float = Field(description="horizontal distance from the wellhead, m")
    closure_direction: float = Field(description="direction of the closure, deg")


class MaxDls(_Model):
    """The largest dogleg severity of a survey over its courses of at least
    ``min_course_length`` (the survey report's rule, :func:`pipeline.survey.courses.max_dls`)
    and where it is."""

    dls: float = Field(description="dogleg severity, deg/30m")
    md: float = Field(description="measured depth of the station ending that course, m")
    min_course_length: float = Field(
        description="m: the DLS of a shorter course (a spike from angle errors over a few "
        "metres) is not counted"
    )
    courses_not_counted: int = Field(ge=0, description="courses shorter than that, left out")
    all_courses_short: bool = Field(
        description="every course is shorter than min_course_length, so every one was counted"
    )


class Uncertainty(_Model):
    """Horizontal error ellipse and vertical σ of the final station (null: no σ there, the
    station outside the error model's range or below one)."""

    md: float = Field(description="measured depth, m")
    semi_major: float | None = Field(description="semi-major axis at 1σ, m")
    semi_minor: float | None = Field(description="semi-minor axis at 1σ, m")
    azimuth: float | None = Field(description="azimuth of the semi-major axis, deg")
    sigma_vertical: float | None = Field(description="vertical σ, m")
    confidence: float | None = Field(
        None, description="probability content of the *_conf values (null: not stated)"
    )
    semi_major_conf: float | None = Field(None, description="semi-major axis at confidence, m")
    semi_minor_conf: float | None = Field(None, description="semi-minor axis at confidence, m")
    vertical_conf: float | None = Field(None, description="vertical half-interval, m")


class Survey(_Model):
    """One survey (a block of rows with one ``survey`` id)."""

    survey: str | None = Field(description="survey id (null: the table has one survey)")
    station_count: int = Field(ge=1)
    md_start: float = Field(description="first station MD, m")
    md_end: float = Field(description="last station MD, m")
    final: Station = Field(description="the last station (TD)")
    max_dls: MaxDls | None = Field(description="null: the survey has no course with a DLS")
    uncertainty_at_td: Uncertainty | None = Field(
        None, description="position uncertainty of the last station, when computed"
    )


class ColumnFamily(_Model):
    """Uncertainty columns of one σ convention."""

    family: Literal["covariance", "ellipse", "ellipse_conf", "vertical_conf"]
    columns: list[str] = Field(description="the trajectory's columns of the family")
    scale: Literal["1 sigma squared", "1 sigma", "confidence"] = Field(
        description="1 sigma squared: variances and covariances (m2); 1 sigma: semi-axes and "
        "vertical σ (m), the major axis' azimuth (deg); confidence: sizes at the confidence "
        "level (m)"
    )
    region: Literal["2-D, chi-square of 2 dof", "1-D, two-sided normal"] | None = Field(
        None, description="how a size at the confidence level was scaled from 1σ"
    )


class SemiMajor(_Model):
    """The horizontal error ellipse's semi-major axis at one station."""

    md: float = Field(description="measured depth, m")
    survey: str | None = Field(None, description="survey id (null: the table has one survey)")
    semi_major: float | None = Field(description="at 1σ, m (null: no σ at the station)")
    semi_major_conf: float | None = Field(
        description="at the confidence level, m (null: no σ, or no such column)"
    )


class UncertaintyStatement(_Model):
    """What the trajectory's uncertainty columns state of themselves."""

    error_model: str | None = Field(
        description="error model name and revision as the columns state it, with what the "
        "run changed of it (null: not stated)"
    )
    confidence: float | None = Field(
        description="probability content of the *_conf columns (null: not stated)"
    )
    columns: list[ColumnFamily] = Field(description="σ convention of each column family")
    largest: SemiMajor | None = Field(
        description="the station of the largest horizontal semi-major axis (null: no station "
        "has a σ)"
    )
    at_td: SemiMajor = Field(description="the deepest station's")
    stations_without_sigma: int = Field(
        ge=0, description="stations without a σ (outside the error model's range, or below one)"
    )
    tie_on: list[TieOn] = Field(
        default_factory=list,
        description="each survey's first station and whether the uncertainty of its position "
        "is in the σ: `wellhead` (within 1 m of MD 0), `survey` (carried down through "
        "`parent`), `given` (the run was given it), `not included` (tied on a position from "
        "outside the run, taken as exactly known)",
    )
    from_stations_file: bool = Field(
        False,
        description="true: the columns are the stations file's, carried with its stations as "
        "it stated them, not computed in this run; false: computed in this run",
    )
    interpolated_points: int = Field(
        0,
        ge=0,
        description="rows flagged `interpolated`: points between survey stations, without σ "
        "and not stations (not in stations_without_sigma, largest or at_td)",
    )


class CheckCount(_Model):
    """Evaluations of one QC check."""

    check: str
    evaluated: int = Field(ge=0)
    passed: int = Field(ge=0)
    failed: int = Field(ge=0)
    not_evaluated: int = Field(ge=0, description="rows the check could not evaluate")


class DroppedStation(_Model):
    """A station recorded but not in the trajectory: dropped by the validity checks (its
    readings removed before compassing) or not solved by compassing."""

    md: float = Field(description="measured depth, m")
    station: int = Field(ge=0, description="station index in the readings")
    dropped_by: Literal["validity", "compassing"]
    checks: list[str] = Field(description="the failed validity checks (empty: compassing)")
    reason: str = Field(description="why compassing could not solve it ('' for validity)")


class Qc(_Model):
    """QC counts."""

    checks: list[CheckCount] = Field(description="per check, in name order")
    failed: int = Field(ge=0, description="failed evaluations over all checks")
    not_evaluated: int = Field(ge=0)
    flagged_stations: int | None = Field(
        None, description="stations with a warning flag (null: no stations table given)"
    )
    rejected_stations: int | None = Field(
        None, description="stations compassing rejected (null: no rejects table given)"
    )
    dropped_stations: int | None = Field(
        None,
        description="stations recorded but not in the trajectory: dropped by the validity "
        "checks or rejected by compassing (null: neither a qc_summary nor a rejects table "
        "given)",
    )
    dropped: list[DroppedStation] = Field(
        default_factory=list, description="each station dropped, in MD order"
    )


class Run(_Model):
    """The run that produced the results."""

    pipeline: str
    pipeline_version: str
    pipeline_sha256: str
    started: dt.datetime = Field(description="UTC start of the run")
    gyropipe: str = Field(description="gyropipe version")
    plugins: dict[str, str] = Field(description="plugin name → version")
    inputs: dict[str, str] = Field(description="pipeline input → SHA-256 of the file")


class SurveySummary(_Model):
    """Machine-readable summary of a processed survey."""

    format: Literal["gyropipe.survey-summary"] = FORMAT
    format_version: Literal["1.0"] = FORMAT_VERSION
    gyropipe: str = Field(description="version of gyropipe that wrote the document")
    well: WellMetadata
    run: Run | None = Field(description="provenance (null: written outside a pipeline run)")
    north_reference: NorthReference = Field(description="north reference of every azimuth")
    calculation: SurveyCalculation | None = Field(
        description="survey calculation method and vertical-section azimuth (null: unknown)"
    )
    units: Units = Units()
    station_count: int = Field(
        ge=0, description="survey stations over all surveys (interpolated points not counted)"
    )
    interpolated_points: int = Field(
        0,
        ge=0,
        description="rows of the trajectory flagged `interpolated` (points between survey "
        "stations): left out of every survey's station count, MD range, TD, maximum DLS and "
        "uncertainty",
    )
    surveys: list[Survey]
    uncertainty: UncertaintyStatement | None = Field(
        None, description="the trajectory's position uncertainty (absent: none computed)"
    )
    qc: Qc | None = Field(
        None, description="QC counts (null: no QC table given, no position check recorded)"
    )
    drift: DriftRate | None = Field(
        None,
        description="the drift correction a free-gyro survey's readings were corrected with: "
        "rate and σ in deg/h, its source (calibration, given, tie_in), the calibration's "
        "instrument, estimate, day and linearity verdict, and each caveat where the "
        "calibration does not cover the survey (null: no corrected readings given)",
    )


def summarize(
    tables: Mapping[str, pa.Table], well: WellMetadata, provenance: Provenance | None
) -> SurveySummary:
    """The summary of a run's ``trajectory`` and its ``qc``, ``qc_summary``, ``stations``,
    ``rejects`` and drift-corrected readings (``drift``)."""
    if "trajectory" not in tables:
        raise ValueError("the JSON summary needs the trajectory (wire the port 'trajectory')")
    trajectory = tables["trajectory"]
    Trajectory.validate_table(trajectory)
    if trajectory.num_rows == 0:
        raise EmptyTableError("trajectory", "a survey summary needs at least one station")
    stations = _stations(trajectory)
    north = (trajectory.schema.field("azi").metadata or {})[NORTH_KEY].decode()
    stated = statement_of(trajectory)
    return SurveySummary(
        gyropipe=__version__,
        well=well,
        run=_run(provenance) if provenance is not None else None,
        north_reference=north,
        calculation=calculation_of(trajectory),
        station_count=stations.num_rows,
        interpolated_points=trajectory.num_rows - stations.num_rows,
        surveys=_surveys(
            stations,
            stated.confidence if stated is not None else None,
            _min_course(provenance),
        ),
        uncertainty=(
            UncertaintyStatement.model_validate(stated.as_dict()) if stated is not None else None
        ),
        qc=_qc(tables) if _has_qc(tables) else None,
        drift=_drift(tables["drift"]) if "drift" in tables else None,
    )


def _stations(trajectory: pa.Table) -> pa.Table:
    """The survey stations of ``trajectory``: its rows less the points between stations
    (:data:`~pipeline.uncertainty.stated.INTERPOLATED_COLUMN`). On the minimum-curvature
    arc a point splits, each piece's DLS is the course's, so a station's ``dls`` stays its
    course's. A survey of points only is refused: it has no station to summarize."""
    between = interpolated_rows(trajectory)
    if not between.any():
        return trajectory
    stations = trajectory.filter(pa.array(~between))
    if "survey" not in trajectory.column_names:
        if stations.num_rows == 0:
            raise ValueError(
                f"every one of the trajectory's {trajectory.num_rows} rows is flagged "
                "interpolated (a point between survey stations): a survey summary needs at "
                "least one station"
            )
        return stations
    kept = set(stations.column("survey").to_pylist())
    for name in dict.fromkeys(trajectory.column("survey").to_pylist()):
        if name not in kept:
            raise ValueError(
                f"every row of the trajectory's survey {name!r} is flagged interpolated (a "
                "point between survey stations): a survey summary needs each survey's stations"
            )
    return stations


def _drift(readings: pa.Table) -> DriftRate:
    """The rate the corrected readings record; refused if they record none (a table of
    other readings wired to the port: no rate is better than one made up)."""
    rate = drift_rate_of(readings)
    if rate is None:
        raise ValueError(
            "the JSON summary's drift port takes correct_drift's readings (they record the "
            "rate applied); the table wired records none"
        )
    return rate


def _run(provenance: Provenance) -> Run:
    return Run(
        pipeline=provenance.pipeline,
        pipeline_version=provenance.pipeline_version,
        pipeline_sha256=provenance.pipeline_sha256,
        started=provenance.started,
        gyropipe=provenance.gyropipe,
        plugins=dict(provenance.plugins),
        inputs={name: file.sha256 for name, file in provenance.inputs.items()},
    )


def _min_course(provenance: Provenance | None) -> float:
    """m: the shortest course whose DLS the maximum counts — the run's survey report's
    ``min_course_length`` (the last report's, as the fleet page takes it), else the
    report's default: so summary.json and the report state one maximum DLS."""
    stated = [
        float(value)
        for stage in (provenance.stages if provenance is not None else ())
        if isinstance(value := stage.params.get("min_course_length"), int | float)
    ]
    return stated[-1] if stated else MIN_COURSE


def _surveys(trajectory: pa.Table, confidence: float | None, min_course: float) -> list[Survey]:
    """Each survey's summary; ``confidence``: the one the *_conf columns state, if any;
    the largest DLS over courses at least ``min_course`` m long."""
    cols = {
        name: trajectory.column(name).to_numpy(zero_copy_only=False)
        for name in Station.model_fields
    }
    dls = trajectory.column("dls").to_numpy(zero_copy_only=False)
    ids = trajectory.column("survey").to_pylist() if "survey" in trajectory.column_names else None
    found = []
    for lo, hi in itertools.pairwise(survey_offsets(trajectory).tolist()):
        worst = max_dls(cols["md"][lo:hi], dls[lo:hi], (0, hi - lo), min_course)
        found.append(
            Survey(
                survey=ids[lo] if ids else None,
                station_count=hi - lo,
                md_start=float(cols["md"][lo]),
                md_end=float(cols["md"][hi - 1]),
                final=Station(**{name: _defined(v[hi - 1]) for name, v in cols.items()}),
                max_dls=None
                if worst is None
                else MaxDls(
                    dls=worst.dls,
                    md=float(cols["md"][lo + worst.row]),
                    min_course_length=min_course,
                    courses_not_counted=worst.left_out,
                    all_courses_short=worst.all_short,
                ),
                uncertainty_at_td=_uncertainty(trajectory, hi - 1, confidence),
            )
        )
    return found


def _defined(value: float) -> float | None:
    """A value, None where it is undefined (NaN: the azimuth of a vertical station)."""
    return None if np.isnan(value) else float(value)


def _uncertainty(trajectory: pa.Table, row: int, stated: float | None) -> Uncertainty | None:
    """The ellipse at ``row``; its confidence the ``stated`` one, else the ratio of the
    *_conf semi-major axis to the 1σ one tells it."""
    if not set(ELLIPSE_COLUMNS) <= set(trajectory.column_names):
        return None
    at: dict[str, Any] = {
        name: _value(trajectory.column(name)[row].as_py()) for name in trajectory.column_names
    }
    conf = at.get("ellipse_major_conf")
    major = at["ellipse_major"]
    # the stage scales the 1σ ellipse by k = √(−2 ln(1 − p)) (χ², 2 dof): p = 1 − e^(−k²/2)
    confidence = (
        stated
        if stated is not None
        else float(-np.expm1(-0.5 * (conf / major) ** 2))
        if conf is not None and major
        else None
    )
    return Uncertainty(
        md=at["md"],
        semi_major=major,
        semi_minor=at["ellipse_minor"],
        azimuth=at["ellipse_azimuth"],
        sigma_vertical=at["sigma_v"],
        confidence=confidence,
        semi_major_conf=conf,
        semi_minor_conf=at.get("ellipse_minor_conf"),
        vertical_conf=at.get("vertical_conf"),
    )


def _value(value: object) -> object:
    """A cell as the document holds it: a float that is NaN (no σ) as None, like a null."""
    return None if isinstance(value, float) and np.isnan(value) else value


def _has_qc(tables: Mapping[str, pa.Table]) -> bool:
    given = {"qc", "qc_summary", "stations", "rejects", "inout"} & set(tables)
    return bool(given) or position_check_of(tables["trajectory"]) is not None


def _qc(tables: Mapping[str, pa.Table]) -> Qc:
    """Counts of the ``qc`` table's checks, of a free gyro's in-run/out-run comparison
    (``inout``: ``in_out_inclination``, ``in_out_azimuth``) and of the trajectory's position
    check, by name, as the run's verdict line counts them; flagged, rejected and dropped
    stations."""
    checks: list[CheckCount] = []
    positions = position_check_of(tables["trajectory"])
    if positions is not None:
        failed = len(positions.beyond_md)
        checks.append(
            CheckCount(
                check="file_positions",
                evaluated=positions.compared,
                passed=positions.compared - failed,
                failed=failed,
                not_evaluated=tables["trajectory"].num_rows - positions.compared,
            )
        )
    if "qc" in tables:
        qc = tables["qc"]
        names = qc.column("check")
        passed = qc.column("passed")
        for name in sorted(set(names.to_pylist())):
            rows = passed.filter(pc.equal(names, name))
            true = int(pc.sum(rows).as_py() or 0)
            checks.append(
                CheckCount(
                    check=name,
                    evaluated=len(rows) - rows.null_count,
                    passed=true,
                    failed=len(rows) - rows.null_count - true,
                    not_evaluated=rows.null_count,
                )
            )
    if "inout" in tables:
        inout = tables["inout"]
        for name, compared, failed_md in inout_checks(inout):
            checks.append(
                CheckCount(
                    check=name,
                    evaluated=compared,
                    passed=compared - len(failed_md),
                    failed=len(failed_md),
                    not_evaluated=inout.num_rows - compared,
                )
            )
    checks.sort(key=lambda c: c.check)
    stations = tables.get("stations")
    flagged = None
    if stations is not None and "flags" in stations.column_names:
        flags = stations.column("flags")
        empty = "" if pa.types.is_string(flags.type) else 0
        flagged = int(pc.sum(pc.not_equal(flags, empty)).as_py() or 0)
    rejects = tables.get("rejects")
    if rejects is not None and not is_rejects(rejects):
        raise ValueError(
            "the JSON summary's rejects port takes the stations compassing rejected (columns "
            f"station, md, reason); the table wired has {', '.join(rejects.column_names)}"
        )
    dropping = [tables.get("qc_summary"), rejects]
    dropped = [
        DroppedStation(
            md=d.md, station=d.station, dropped_by=d.by, checks=list(d.checks), reason=d.reason
        )
        for d in dropped_stations([*dropping, tables.get("qc")])
    ]
    return Qc(
        checks=checks,
        failed=sum(c.failed for c in checks),
        not_evaluated=sum(c.not_evaluated for c in checks),
        flagged_stations=flagged,
        rejected_stations=rejects.num_rows if rejects is not None else None,
        dropped_stations=len(dropped) if any(t is not None for t in dropping) else None,
        dropped=dropped,
    )


def write_tables(
    tables: Mapping[str, pa.Table], path: Path, well: WellMetadata, provenance: Provenance
) -> None:
    """Write the summary of the run's tables as JSON."""
    _write(summarize(tables, well, provenance), path)


def write(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write the summary of one trajectory (no provenance, no QC) as JSON."""
    _write(summarize({"trajectory": table}, well, None), path)


def _write(summary: SurveySummary, path: Path) -> None:
    doc = summary.model_dump(mode="json")
    if summary.uncertainty is None:  # no uncertainty columns: the document says nothing of it
        del doc["uncertainty"]
    path.write_text(json.dumps(doc, indent=2, allow_nan=False) + "\n", encoding="utf-8")


@hookimpl
def gyropipe_register_writers(register: Callable[[WriterDef], None]) -> None:
    register(
        WriterDef(
            name="json_summary",
            description="machine-readable JSON summary: well, run, north reference, final "
            "position, max DLS, uncertainty at TD and as stated (error model, confidence, "
            "σ conventions, largest ellipse), QC counts, the drift correction applied",
            extension="json",
            write=write,
            write_tables=write_tables,
            schema=SurveySummary,
        )
    )

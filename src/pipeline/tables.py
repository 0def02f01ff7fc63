"""The core table contracts exchanged by built-in stages.

Canonical units: lengths in metres, angles in degrees, dogleg severity in °/30 m. Azimuth
columns state their north reference (true, grid or magnetic) in field metadata.
"""

from __future__ import annotations

from dataclasses import replace
from typing import ClassVar

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from pipeline.contracts import (
    SOURCE_KEY,
    SOURCE_LINE,
    UNIT_KEY,
    TableContract,
    column,
    rule_failure,
)
from pipeline.errors import ContractViolation, RuleFailure, UnitError
from pipeline.units import conversion_factor

DLS_COURSE_M = 30.0
"""Course length of the dogleg severity unit, m."""
DLS_UNIT = "deg/30m"


class AnyTable(TableContract):
    """Any table (writers and generic stages)."""


MIN_COURSE_M = 5e-4
"""Shortest course between two stations of a survey, m: MDs are recorded to a centimetre
or a millimetre, so stations half a millimetre apart are one station repeated (over a
course of a few ulp, 4.9e-324 m, the dogleg severity would be infinite), and five steps of
the 0.1 mm an export writes keep every course of a copy positive."""
MIN_TIME_STEP_S = 5e-6
"""Shortest step between two samples' or two dwells' times, s: five steps of the 1 µs an
export writes (faster than any survey tool samples), so a copy's times still increase."""
MIN_DURATION_S = 1e-6
"""Shortest averaging time of a reading, s: the 1 µs an export writes, so a copy's
durations stay positive."""


class Stations(TableContract):
    """Survey stations, one row per station, in increasing MD (per survey when ``survey``
    is present: several surveys may share one table, each a contiguous block of rows)."""

    group_by = "survey"

    survey: str | None = column(
        unit=None, description="survey id when a table holds several surveys", default=None
    )
    md: float = column(
        unit="m",
        monotonic="strict",
        min_step=MIN_COURSE_M,
        description="measured depth from the depth reference",
    )
    inc: float = column(unit="deg", ge=0, le=180, description="inclination from vertical")
    azi: float = column(
        unit="deg",
        north_reference=True,
        undefined_at_vertical=True,
        description="azimuth, clockwise from north (NaN: undefined, only at vertical)",
    )
    tool_type: str | None = column(
        unit=None, description="survey tool of the station, as the file names it", default=None
    )
    station_type: str | None = column(
        unit=None, description="station type as the file names it (tie in point…)", default=None
    )


STATION_TEXT_COLUMNS = ("tool_type", "station_type")
"""Per-station text columns a trajectory keeps from its stations."""


class Trajectory(Stations):
    """Stations with integrated positions (NED: north, east, TVD down) relative to the
    wellhead, dogleg, vertical section and closure."""

    azi: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        undefined_at_vertical=True,
        description="azimuth in [0, 360), clockwise from north (NaN: undefined, only at vertical)",
    )
    tvd: float = column(unit="m", description="true vertical depth below the depth reference")
    north: float = column(unit="m", description="northing from the wellhead")
    east: float = column(unit="m", description="easting from the wellhead")
    dogleg: float = column(
        unit="deg", ge=0, le=180, description="dogleg angle from the previous station"
    )
    dls: float = column(unit=DLS_UNIT, ge=0, description="dogleg severity")
    vertical_section: float = column(
        unit="m", description="horizontal displacement projected on the section azimuth"
    )
    closure_distance: float = column(
        unit="m", ge=0, description="horizontal distance from the wellhead"
    )
    closure_direction: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        description="direction of the closure, clockwise from north",
    )


class CheckResults(TableContract):
    """Results of QC checks, one row per checked row."""

    check: str = column(unit=None, description="check name")
    row: int = column(unit=None, ge=0, description="row index in the checked table")
    md: float | None = column(unit="m", description="measured depth of the row, if known")
    value: float = column(unit=None, finite=False, description="checked quantity (in `unit`)")
    limit: float = column(unit=None, description="tolerance (in `unit`)")
    unit: str = column(unit=None, description="unit of value and limit")
    passed: bool = column(unit=None, description="value within tolerance")


class AcceptanceGates(TableContract):
    """Acceptance gates of a survey (e.g. in-run against out-run): one row per gate, its
    worst value against its limit (both in ``unit``) and its status (``pass``, ``fail`` or
    ``not evaluated``). ``run.json`` records every such table a run produces."""

    decides_acceptance: ClassVar[bool] = True

    gate: str = column(unit=None, description="gate name")
    value: float = column(unit=None, finite=False, description="worst value (NaN: none)")
    limit: float = column(unit=None, description="limit of the gate (in `unit`)")
    unit: str = column(unit=None, description="unit of value and limit")
    status: str = column(unit=None, description="pass, fail or not evaluated")
    description: str = column(unit=None, description="what the gate compares")


RATE_UNIT = "deg/h"
ACCEL_UNIT = "m/s2"
FIELD_UNIT = "nT"


class RawSamples(TableContract):
    """Raw sensor samples in the canonical body frame (DOMAIN.md §2): gyros in °/h,
    accelerometers in m/s² with the gravity sign convention (a tool at rest reads
    C_n^b·(0, 0, g)), magnetometers in nT. Axes a tool lacks are absent."""

    time: float = column(
        unit="s", monotonic="strict", min_step=MIN_TIME_STEP_S, description="time since the start"
    )
    md: float | None = column(
        unit="m", description="measured depth from the odometer (absent: no depth)", default=None
    )
    frame_angle: float | None = column(
        unit="deg",
        ge=0,
        lt=360,
        description="angle of the sensor frame relative to the housing (absent: fixed frame)",
        default=None,
    )
    gyro_x: float = column(unit=RATE_UNIT, description="angular rate about frame x")
    gyro_y: float | None = column(unit=RATE_UNIT, description="rate about y", default=None)
    gyro_z: float | None = column(unit=RATE_UNIT, description="rate about z", default=None)
    acc_x: float = column(unit=ACCEL_UNIT, description="acceleration along x")
    acc_y: float = column(unit=ACCEL_UNIT, description="acceleration along y")
    acc_z: float = column(unit=ACCEL_UNIT, description="acceleration along z (tool axis)")
    mag_x: float | None = column(unit=FIELD_UNIT, description="magnetic field x", default=None)
    mag_y: float | None = column(unit=FIELD_UNIT, description="magnetic field y", default=None)
    mag_z: float | None = column(unit=FIELD_UNIT, description="magnetic field z", default=None)
    station: int | None = column(
        unit=None, ge=0, description="station index while stopped at a station", default=None
    )
    position: int | None = column(
        unit=None, ge=0, description="frame position index while dwelling", default=None
    )


class SimTruth(TableContract):
    """What the simulator's tool truly did at each sample (azimuths true north)."""

    time: float = column(
        unit="s", monotonic="strict", min_step=MIN_TIME_STEP_S, description="time since the start"
    )
    md: float = column(unit="m", description="true measured depth")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination")
    azi: float = column(unit="deg", ge=0, lt=360, north_reference=True, description="azimuth")
    toolface: float = column(
        unit="deg", ge=0, lt=360, description="gravity toolface of the frame x axis"
    )
    housing_toolface: float = column(
        unit="deg", ge=0, lt=360, description="gravity toolface of the housing"
    )
    frame_angle: float = column(unit="deg", ge=0, lt=360, description="true frame angle")
    north: float = column(unit="m", description="northing from the wellhead")
    east: float = column(unit="m", description="easting from the wellhead")
    tvd: float = column(unit="m", description="true vertical depth")


class FreeGyroReadings(TableContract):
    """Station readings of a free (directional) gyro, in time order: the in-run down the
    hole, then the out-run back up. ``azi`` is the gyro's reading, drift included."""

    run: str = column(unit=None, description="'in' or 'out'")
    station: int = column(unit=None, ge=0, description="station index along the in-run")
    time: float = column(unit="s", monotonic="strict", description="time of the reading")
    md: float = column(unit="m", description="measured depth")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination reading")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="azimuth reading (drifts)"
    )
    temperature: float | None = column(
        unit="degC", description="tool temperature at the reading", default=None
    )
    true_inc: float | None = column(
        unit="deg", ge=0, le=180, description="true inclination (simulations)", default=None
    )
    true_azi: float | None = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        description="true azimuth (simulations)",
        default=None,
    )


class ErrorBudget(TableContract):
    """Predicted 1σ errors of each station of a planned survey (degrees)."""

    md: float = column(unit="m", ge=0, monotonic="strict", description="station MD")
    inc: float = column(unit="deg", ge=0, le=180, description="planned inclination")
    azi: float = column(
        unit="deg", ge=0, lt=360, north_reference=True, description="planned azimuth"
    )
    sigma_inc: float = column(unit="deg", ge=0, description="inclination σ")
    sigma_azi: float = column(unit="deg", ge=0, finite=False, description="azimuth σ (total)")
    sigma_azi_gyro: float = column(
        unit="deg", ge=0, finite=False, description="azimuth σ from the gyro noise"
    )
    sigma_azi_g: float = column(
        unit="deg",
        ge=0,
        finite=False,
        description="azimuth σ from the gyro's g-dependent bias (not removed by compassing)",
    )
    sigma_azi_accel: float = column(
        unit="deg", ge=0, finite=False, description="azimuth σ from the accelerometers"
    )
    mirror: float = column(
        unit=None,
        ge=0,
        le=1,
        description="probability that the planned readings put the azimuth across east–west "
        "(180° − A); above the compass stage's ambiguity it rejects the station, and the σ "
        "columns are NaN",
    )


class PositionReadings(TableContract):
    """Pre-averaged readings of a point survey: one row per station × frame position, in
    time order (the documented input of compassing; also what raw samples reduce to).
    Rates in °/h, accelerations in m/s² (gravity sign convention), time in s."""

    station: int = column(unit=None, ge=0, description="station index")
    md: float = column(unit="m", description="measured depth of the station")
    position: int = column(unit=None, ge=0, description="frame position index within the station")
    t: float = column(
        unit="s", monotonic="strict", min_step=MIN_TIME_STEP_S, description="mid-time of the dwell"
    )
    frame_angle: float | None = column(
        unit="deg",
        ge=0,
        lt=360,
        description="frame angle sensor (absent: fixed frame)",
        default=None,
    )
    gyro_x: float = column(unit=RATE_UNIT, description="mean rate about frame x")
    gyro_y: float | None = column(unit=RATE_UNIT, description="mean rate about y", default=None)
    gyro_z: float | None = column(unit=RATE_UNIT, description="mean rate about z", default=None)
    acc_x: float = column(unit=ACCEL_UNIT, description="mean acceleration along x")
    acc_y: float = column(unit=ACCEL_UNIT, description="mean acceleration along y")
    acc_z: float = column(unit=ACCEL_UNIT, description="mean acceleration along z")
    gyro_x_std: float | None = column(
        unit=RATE_UNIT, ge=0, description="sample standard deviation of gyro_x", default=None
    )
    gyro_y_std: float | None = column(
        unit=RATE_UNIT, ge=0, description="std of gyro_y", default=None
    )
    gyro_z_std: float | None = column(
        unit=RATE_UNIT, ge=0, description="std of gyro_z", default=None
    )
    acc_x_std: float | None = column(
        unit=ACCEL_UNIT, ge=0, description="std of acc_x", default=None
    )
    acc_y_std: float | None = column(
        unit=ACCEL_UNIT, ge=0, description="std of acc_y", default=None
    )
    acc_z_std: float | None = column(
        unit=ACCEL_UNIT, ge=0, description="std of acc_z", default=None
    )
    n: int | None = column(unit=None, ge=1, description="samples averaged", default=None)
    duration: float | None = column(
        unit="s", ge=MIN_DURATION_S, description="averaging time", default=None
    )


class CompassStations(Stations):
    """Stations solved by gyrocompassing (azimuths true north; toolfaces of the frame x
    axis at the station's first position)."""

    station: int = column(unit=None, ge=0, description="station index")
    azi: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        undefined_at_vertical=True,
        description="azimuth, true north (NaN where flagged azimuth_undefined: at vertical)",
    )
    gyro_toolface: float = column(
        unit="deg", ge=0, lt=360, description="north-referenced (gyro) toolface"
    )
    highside_toolface: float = column(
        unit="deg",
        ge=0,
        lt=360,
        undefined_at_vertical=True,
        description="gravity (high-side) toolface (NaN where flagged azimuth_undefined)",
    )
    sigma_inc: float = column(unit="deg", ge=0, description="predicted σ of inc")
    sigma_azi: float = column(unit="deg", ge=0, finite=False, description="predicted σ of azi")
    sigma_toolface: float = column(
        unit="deg", ge=0, finite=False, description="predicted σ of gyro_toolface"
    )
    bias: float = column(unit=RATE_UNIT, description="estimated bias of gyro x")
    trend: float = column(unit="deg/h2", description="estimated linear trend of gyro x, °/h per h")
    residual_rms: float = column(unit=RATE_UNIT, ge=0, description="RMS of the fit residuals")
    chi2: float = column(unit=None, ge=0, description="χ² of the residuals against the σ")
    positions: int = column(unit=None, ge=1, description="frame positions used")
    solver: str = column(unit=None, description="ml, sine, atan2 or toolface")
    mode: str = column(unit=None, description="inclined or near-vertical")
    flags: str = column(
        unit=None,
        description="comma-separated warnings (inconsistent, frame_mismatch, poor_azimuth, "
        "azimuth_from_toolface, azimuth_undefined, bias_not_removed, fewer_positions: fewer "
        "frame positions than the survey's most common number)",
    )
    time: float = column(unit="s", description="mid-time of the station")


class CompassRejects(TableContract):
    """Stations compassing could not solve, and why."""

    station: int = column(unit=None, ge=0, description="station index")
    md: float = column(unit="m", description="measured depth")
    reason: str = column(unit=None, description="why the station was not solved")


class LogTable(TableContract):
    """A well log as read: the index (depth, time or what the file is indexed by) first,
    then any curves, each with the unit its file gives in the field's ``unit`` metadata
    (not converted); float64 curves hold NaN for no value, text curves null. No column is
    required: a log has whatever curves it was logged with.

    The index is a log's key: numbers, finite and strictly monotonic (increasing, or
    decreasing throughout: a log recorded upwards), never null; text only where its unit is
    no length or time (a time of day, ``HHMMSS``). A float curve holds no ±inf (NaN is its
    only marker of no value)."""

    @classmethod
    def validate_table(cls, table: pa.Table) -> None:
        super().validate_table(table)
        failures = _log_failures(table)
        if failures:
            if SOURCE_LINE in table.column_names:
                lines = table.column(SOURCE_LINE)
                failures = [
                    replace(f, lines=tuple(int(lines[i].as_py()) for i, _ in f.examples))
                    for f in failures
                ]
            source = (table.schema.metadata or {}).get(SOURCE_KEY, b"")
            raise ContractViolation("LogTable", failures, source=source.decode("utf-8", "replace"))


FINITE_NUMBER = r"^\s*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?\s*$"
"""A text cell spelling a number (not inf or NaN)."""


def _log_failures(table: pa.Table) -> list[RuleFailure]:
    """The rules a log's index (its first column) and float curves break (:class:`LogTable`)."""
    names = [n for n in table.column_names if n != SOURCE_LINE]
    failures = []
    if names and table.num_rows:
        failure = _index_failure(table.schema.field(names[0]), table.column(names[0]))
        if failure is not None:
            failures.append(failure)
    for name in names[1:]:
        col = table.column(name)
        if pa.types.is_floating(col.type) and _holds_infinity(col):
            bad = np.isinf(col.to_numpy(zero_copy_only=False))
            failures.append(rule_failure(name, "finite", "numbers or NaN (no ±inf)", bad, col))
    return failures


def _holds_infinity(col: pa.ChunkedArray) -> bool:
    """Whether a float column holds ±inf among its values (not its nulls): chunk by chunk,
    a chunk without nulls read in place (no copy of the column; a log's curve read from
    LAS comes in a chunk per block), one with nulls as NumPy with NaN for them."""
    return any(
        np.isinf(chunk.to_numpy(zero_copy_only=chunk.null_count == 0)).any() for chunk in col.chunks
    )


def _index_failure(field: pa.Field, col: pa.ChunkedArray) -> RuleFailure | None:
    """Why ``col`` cannot index a log, or None."""
    expected = "finite, strictly monotonic numbers (the log's index)"
    if pa.types.is_string(col.type) or pa.types.is_large_string(col.type):
        if not _measured(field):
            return None  # a time of day, a date: the index as written
        number = pc.match_substring_regex(col, FINITE_NUMBER).fill_null(False)
        return rule_failure(
            field.name, "index", expected, ~number.to_numpy(zero_copy_only=False), col
        )
    if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
        return None
    values = col.to_numpy(zero_copy_only=False).astype(np.float64, copy=False)
    bad = ~np.isfinite(values)
    if bad.any():
        return rule_failure(field.name, "index", expected, bad, col)
    steps = np.greater(values[1:], values[:-1]).astype(np.int8) - np.less(
        values[1:], values[:-1]
    )  # the sign of each step (a difference may pass the float range)
    moving = steps[steps != 0]
    direction = moving[0] if moving.size else 1.0  # decreasing throughout: recorded upwards
    bad[1:] = steps != direction
    return rule_failure(field.name, "index", expected, bad, col) if bad.any() else None


def _measured(field: pa.Field) -> bool:
    """Whether a field's unit is a length or a time (its values must be numbers)."""
    raw = (field.metadata or {}).get(UNIT_KEY)
    unit = raw.decode("utf-8", "replace") if raw else ""
    for quantity in ("length", "time"):
        try:
            conversion_factor(unit, quantity)
        except UnitError:
            continue
        return bool(unit)
    return False

"""Angle plausibility of survey stations as read, the one rule every reader's stations pass
through (:func:`pipeline.read_checks.check_read`), in canonical degrees after the reader's
unit conversion:

* an inclination outside [0, 180] or an azimuth outside [−360, 720) is an error at its line
  — a null marker or a unit mistake, never a value to wrap. When more than half the column
  (and :data:`RADIAN_STATIONS` stations or more) is out of range and every angle would fit
  once divided by 180/π, the message says the values look like degrees declared as radians;
* an azimuth in [−360, 0) or [360, 720) is read as the same direction in [0, 360), with a
  warning naming its line;
* inclinations and azimuths that all fit radians — at least :data:`RADIAN_STATIONS`
  stations, none inclined more than π (3.14°), every azimuth within [0, 2π] (6.28°), some
  not zero — are radians read as degrees (a 3,510 m well "with a maximum inclination of
  0.95°" heading due north throughout): an error naming both columns, unless the reader's
  option ``angle_unit_confirmed`` says the degrees are meant.

A station without an inclination, or without an azimuth away from vertical, is the
contract's error at its line, unless the reader's option ``null_stations`` is ``drop``:
then :func:`without_null_stations` leaves it out, with a warning.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import pyarrow as pa
from pydantic import Field

from pipeline.contracts import SOURCE_LINE, VERTICAL_TOLERANCE
from pipeline.errors import InputFileError, warn_input

INC_RANGE = (0.0, 180.0)
"""Inclinations allowed, deg (both ends included)."""
AZI_RANGE = (-360.0, 720.0)
"""Azimuths allowed, deg (the upper end excluded): a bearing written once around either way."""
RADIAN_STATIONS = 5
"""Fewest stations whose angles all fitting radians is taken for radians read as degrees."""
CONFIRM = "angle_unit_confirmed"
"""The reader option confirming degrees that look like radians."""
DROP = "null_stations"
"""The reader option that, set to ``drop``, leaves out stations missing an angle."""
_PER_RAD = 180.0 / math.pi

AngleUnitConfirmed = Annotated[
    bool,
    Field(
        description="the inclinations and azimuths are in the unit declared although they all "
        "fit radians (pipeline.plausibility)"
    ),
]
"""A reader option: confirms a declared angle unit the plausibility check doubts."""
NullStations = Annotated[
    Literal["error", "drop"],
    Field(
        description="a station without inclination, or without azimuth away from vertical (an "
        "empty cell or a null marker, -999.25…): 'error' (default) refuses the file at its "
        "line; 'drop' leaves the station out, with a warning naming its line"
    ),
]
"""A reader option: what a station missing an angle is ."""
SurveyStations = Annotated[
    Literal["survey", "all"],
    Field(
        description="'survey' (default): read the survey's stations only — a station the "
        "file marks as none (a projection, an interpolation, a marker, a rejected or planned "
        "one: the reader's documentation lists the marks it reads) is left out with a warning "
        "at its line, a trajectory it marks as a plan refused; 'all': read every station as "
        "it is"
    ),
]
"""A reader option: whether the stations a file marks as none of the survey's are read."""


def check_angles(path: Path, table: pa.Table, *, confirmed: bool = False) -> None:
    """Raise an :class:`InputFileError` at the first implausible angle of a stations table
    (columns ``inc`` and ``azi``, deg) read from ``path``; warn of azimuths outside [0, 360)
    it lets through. ``confirmed``: the reader was told the degrees are meant."""
    if "inc" not in table.column_names or "azi" not in table.column_names:
        return
    inc = _floats(table, "inc")
    azi = _floats(table, "azi")
    lines = table.column(SOURCE_LINE).to_pylist() if SOURCE_LINE in table.column_names else None
    missing = _missing(inc, azi)
    if missing.any():
        first = int(np.flatnonzero(missing)[0])
        name, what = ("inc", "inclination") if np.isnan(inc[first]) else ("azi", "azimuth")
        raise InputFileError(
            path,
            f"station at md {_md(table, first)} has no {what}"
            " (an empty cell or a null marker; an azimuth may be missing only at vertical): "
            f"expected a value, or the reader option {DROP}: drop to leave such stations out"
            + (f" ({int(missing.sum())} such stations)" if missing.sum() > 1 else ""),
            _line(lines, first),
            column=name,
        )
    with np.errstate(invalid="ignore"):
        bad_inc = (inc < INC_RANGE[0]) | (inc > INC_RANGE[1])
        bad_azi = (azi < AZI_RANGE[0]) | (azi >= AZI_RANGE[1])
        wrapped = ~bad_azi & ((azi < 0.0) | (azi >= 360.0))
    for name, values, bad, allowed in (
        ("inc", inc, bad_inc, "[0, 180]"),
        ("azi", azi, bad_azi, "[-360, 720)"),
    ):
        if bad.any():
            raise _refusal(path, name, values, bad, allowed, lines, inc, azi)
    if wrapped.any():
        first = int(np.flatnonzero(wrapped)[0])
        warn_input(
            path,
            f"azi {float(azi[first])!r}° read as {float(azi[first] % 360.0)!r}°, the same "
            "direction (an azimuth in [-360, 720) is wrapped into [0, 360), one outside it "
            "refused)"
            + (f"; {int(wrapped.sum())} azimuths outside [0, 360)" if wrapped.sum() > 1 else ""),
            _line(lines, first),
        )
    if not confirmed and _radians(inc, azi):
        raise InputFileError(
            path,
            f"inc and azi look like radians read as degrees: over {inc.size} stations the "
            f"largest inclination is {np.nanmax(inc):.4g}° and every azimuth lies within "
            f"[0, 2π] (the largest {np.nanmax(azi):.4g}°); declare the unit rad, or set the "
            f"reader option {CONFIRM}: true if these are degrees",
            _line(lines, int(np.nanargmax(inc))),
            column="inc",
        )


def without_null_stations(path: Path, table: pa.Table) -> pa.Table:
    """The stations less those without an inclination, or without an azimuth away from
    vertical (null or NaN, as a reader leaves a null marker), with a warning naming their
    lines (the reader option ``null_stations: drop``)."""
    if "inc" not in table.column_names or "azi" not in table.column_names:
        return table
    missing = _missing(_floats(table, "inc"), _floats(table, "azi"))
    if not missing.any():
        return table
    lines = table.column(SOURCE_LINE).to_pylist() if SOURCE_LINE in table.column_names else None
    rows = np.flatnonzero(missing)
    shown = ", ".join(str(_line(lines, int(r))) for r in rows[:10])
    warn_input(
        path,
        f"{rows.size} station(s) without inclination or azimuth left out ({DROP}: drop)"
        + (f"; lines {shown}" if lines is not None else ""),
        _line(lines, int(rows[0])),
    )
    return table.filter(pa.array(~missing))


def _missing(inc: np.ndarray, azi: np.ndarray) -> np.ndarray:
    """Stations without an inclination, or without an azimuth away from vertical."""
    with np.errstate(invalid="ignore"):
        vertical = np.minimum(np.abs(inc), np.abs(180.0 - inc)) <= VERTICAL_TOLERANCE
    missing: np.ndarray = np.isnan(inc) | (np.isnan(azi) & ~vertical)
    return missing


def _floats(table: pa.Table, name: str) -> np.ndarray:
    column = table.column(name)
    if not pa.types.is_floating(column.type) and not pa.types.is_integer(column.type):
        return np.full(table.num_rows, np.nan)  # the contract names the wrong type
    return np.asarray(column.to_numpy(zero_copy_only=False), dtype=np.float64)


def _md(table: pa.Table, row: int) -> str:
    return repr(table.column("md")[row].as_py()) if "md" in table.column_names else "?"


def _line(lines: list[int] | None, row: int) -> int:
    return int(lines[row]) if lines is not None else 0


def _refusal(
    path: Path,
    name: str,
    values: np.ndarray,
    bad: np.ndarray,
    allowed: str,
    lines: list[int] | None,
    inc: np.ndarray,
    azi: np.ndarray,
) -> InputFileError:
    rows = np.flatnonzero(bad)
    first = int(rows[0])
    what = "inclination" if name == "inc" else "azimuth"
    more = f" ({rows.size} such values)" if rows.size > 1 else ""
    hint = ""
    with np.errstate(invalid="ignore"):
        if (
            rows.size >= RADIAN_STATIONS
            and 2 * rows.size > np.isfinite(values).sum()
            and np.all(np.isnan(inc) | (inc / _PER_RAD <= INC_RANGE[1]))
            and np.all(np.isnan(azi) | (np.abs(azi / _PER_RAD) < 360.0))
        ):
            hint = (
                f"; {values[first] / _PER_RAD:.6g} would be a plausible {what} in degrees: "
                "the column looks like degrees declared as radians"
            )
    return InputFileError(
        path,
        f"{what} {float(values[first])!r}° is outside {allowed}{more}: a null marker or a wrong "
        f"unit, never a value to wrap{hint}",
        _line(lines, first),
        column=name,
    )


def _radians(inc: np.ndarray, azi: np.ndarray) -> bool:
    """Whether the angles all fit radians (see the module's docstring)."""
    both = np.isfinite(inc) & np.isfinite(azi)
    if both.sum() < RADIAN_STATIONS:
        return False
    i, a = inc[both], azi[both]
    return bool(
        np.max(i) <= math.pi
        and np.min(a) >= 0.0
        and np.max(a) <= 2.0 * math.pi
        and np.max(i) > 0.0
        and np.max(a) > 0.0
    )

"""Whether a drift calibration fits the survey it corrects.

A calibration saw the instrument's drift over its own readings: the time from the first to
the last (``time_span``), at the temperatures they were taken at (``temperature_min`` …
``temperature_max``, when stated), on the day it was recorded (``calibration_date``). A
survey that runs longer than that span, or reads temperatures beyond that range, has the
drift rate extrapolated to it; a calibration recorded more than ``max_age_days`` (default
:data:`MAX_AGE_DAYS`, 180 days) before or after the survey may no longer be the
instrument's. Each is a caveat of the correction, worded for the client's report: warned
and stated, not a refusal unless one is asked for (:class:`CalibrationRangeError`). What
the calibration or the survey does not state is not checked (the report says "not stated").
Times in seconds, temperatures in °C.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.errors import GyropipeError

MAX_AGE_DAYS = 180.0
"""Days between a calibration and the survey beyond which the calibration is old."""


class CalibrationRangeError(GyropipeError, ValueError):
    """A drift calibration does not cover the survey (asked to refuse rather than warn), or
    states its date so that it cannot be checked."""


@dataclass(frozen=True)
class SurveyConditions:
    """What a survey ran through: its time span (s), the range of its readings'
    temperatures (°C; None: not stated) and its first and last days (None: not stated)."""

    span: float
    temperature: tuple[float, float] | None
    days: tuple[dt.date, dt.date] | None


def survey_conditions(
    readings: pa.Table, first_day: dt.date | None, last_day: dt.date | None
) -> SurveyConditions:
    """The conditions of free-gyro ``readings`` surveyed from ``first_day`` to ``last_day``
    (None: the first day alone)."""
    time = readings.column("time").to_numpy().astype(float)
    heat = np.array([], dtype=float)
    if "temperature" in readings.column_names:
        heat = readings.column("temperature").to_numpy(zero_copy_only=False).astype(float)
        heat = heat[np.isfinite(heat)]
    return SurveyConditions(
        span=float(np.ptp(time)),
        temperature=(float(heat.min()), float(heat.max())) if len(heat) else None,
        days=(first_day, last_day or first_day) if first_day is not None else None,
    )


def calibration_caveats(
    calibration: pa.Table, instrument: str, survey: SurveyConditions, max_age_days: float
) -> list[str]:
    """Where the calibration of ``instrument`` (a :class:`CalibrationResult` table's rows of
    it: their ranges are the instrument's) does not cover ``survey``, one sentence each."""
    rows = [r for r in calibration.to_pylist() if r["instrument"] == instrument]
    row = rows[0]
    caveats: list[str] = []
    span = row.get("time_span")
    if span is not None and survey.span > span:
        caveats.append(
            f"the survey's readings span {survey.span / 3600:.2f} h, beyond the "
            f"{span / 3600:.2f} h over which the calibration of {instrument} saw its drift: "
            "the drift rate is extrapolated in time"
        )
    low, high = row.get("temperature_min"), row.get("temperature_max")
    if survey.temperature is not None and low is not None and high is not None:
        t_low, t_high = survey.temperature
        if t_low < low or t_high > high:
            caveats.append(
                f"the survey read temperatures of {_celsius(t_low)} to {_celsius(t_high)} °C, "
                f"beyond the {_celsius(low)} to {_celsius(high)} °C of the calibration of "
                f"{instrument}: the drift rate is extrapolated in temperature"
            )
    age = _age(row.get("calibration_date"), instrument, survey.days)
    if age is not None and abs(age) > max_age_days:
        when = "before" if age > 0 else "after"
        caveats.append(
            f"the calibration of {instrument} ({row['calibration_date']}) was recorded "
            f"{abs(age)} days {when} the survey, beyond the {max_age_days:g} days a "
            "calibration is taken to hold"
        )
    return caveats


def _age(stated: str | None, instrument: str, days: tuple[dt.date, dt.date] | None) -> int | None:
    """Days from the calibration to the survey day furthest from it (negative: the
    calibration came after the survey); None where either date is not stated."""
    if stated is None or days is None:
        return None
    try:
        day = dt.date.fromisoformat(stated)
    except ValueError:
        raise CalibrationRangeError(
            f"the calibration of {instrument} states its date as {stated!r}, not a day "
            "(2026-05-12): its age cannot be checked"
        ) from None
    first, last = days
    if day <= first:
        return (last - day).days
    if day >= last:
        return -(day - first).days
    return 0


def _celsius(value: float) -> str:
    return f"{value:.1f}"

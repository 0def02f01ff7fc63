"""Courses between the stations of a trajectory: their lengths, the short ones, and the
largest dogleg severity over the courses long enough to count — the one rule the survey
report and the fleet page state their maximum DLS by.

A short course (e.g. to an end stop close below the last station) divides angle errors by a
few metres: its DLS is a spike, not the hole's curvature, so it is left out of the maximum.
MD in metres; DLS in whatever unit the caller's column has (canonically °/30 m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Floats = npt.NDArray[np.float64]

MIN_COURSE = 10.0
"""Default minimum course length, m: dogleg severity over a shorter course is not counted
in the maximum."""
TOLERANCE = 1e-6
"""m: a course this close to the limit counts as long enough (MD written to a few decimals)"""


def course_lengths(md: Floats, offsets: tuple[int, ...]) -> Floats:
    """Each station's course from the previous station of its survey, m (0 at the first
    station of a survey: it has no course); ``offsets``: CSR offsets of the surveys
    (:func:`pipeline.survey.stations.survey_offsets`)."""
    course: Floats = np.diff(md, prepend=md[:1])
    course[list(offsets[:-1])] = 0.0
    return course


def short_courses(md: Floats, offsets: tuple[int, ...], min_course: float) -> npt.NDArray[np.bool_]:
    """Stations whose course from the previous station of their survey is shorter than
    ``min_course`` m (the first station of a survey has no course)."""
    course = course_lengths(md, offsets)
    short: npt.NDArray[np.bool_] = (course > 0) & (course < min_course - TOLERANCE)
    return short


@dataclass(frozen=True)
class MaxDls:
    """The largest DLS of a trajectory by :func:`max_dls`."""

    row: int
    """the station at the end of its course"""
    dls: float
    left_out: int
    """short courses not counted"""
    all_short: bool
    """every course is shorter than the limit, so every one was counted"""


def max_dls(
    md: Floats,
    dls: Floats,
    offsets: tuple[int, ...],
    min_course: float,
) -> MaxDls | None:
    """The largest finite DLS over the courses at least ``min_course`` m long (0: every
    course); where every course is shorter, over them all (``all_short``). The first station
    of a survey ends no course and does not count. None where no course has a finite DLS."""
    course = course_lengths(md, offsets)
    ends = (course > 0) & np.isfinite(dls)
    counted = ends & (course >= min_course - TOLERANCE)
    all_short = not counted.any()
    if all_short:
        counted = ends
    if not counted.any():
        return None
    row = int(np.flatnonzero(counted)[np.argmax(dls[counted])])
    left_out = 0 if all_short else int(short_courses(md, offsets, min_course).sum())
    return MaxDls(row, float(dls[row]), left_out, all_short)

"""The largest DLS over courses long enough (:func:`pipeline.survey.courses.max_dls`), the
rule the survey report and the fleet page both state their maximum DLS by."""

from __future__ import annotations

import math

import numpy as np

from pipeline.survey.courses import max_dls


def test_a_short_course_s_spike_is_left_out():
    md = np.array([0.0, 30.0, 60.0, 62.0, 90.0])
    dls = np.array([0.0, 1.0, 2.0, 40.0, 3.0])
    found = max_dls(md, dls, (0, 5), 10.0)
    assert found is not None and (found.row, found.dls, found.left_out) == (4, 3.0, 1)
    assert not found.all_short
    every = max_dls(md, dls, (0, 5), 0.0)
    assert every is not None and (every.row, every.dls, every.left_out) == (3, 40.0, 0)


def test_a_course_at_the_limit_counts():
    md = np.array([0.0, 10.0, 20.0])
    found = max_dls(md, np.array([0.0, 5.0, 1.0]), (0, 3), 10.0)
    assert found is not None and found.dls == 5.0 and found.left_out == 0


def test_the_first_station_of_each_survey_ends_no_course():
    """Two surveys: the 2 m step from the first survey's last station to the second's first
    is no course, so its DLS (as large as a bug would make it) is not counted or left out."""
    md = np.array([0.0, 30.0, 60.0, 62.0, 92.0])
    dls = np.array([0.0, 1.0, 2.0, 50.0, 3.0])
    found = max_dls(md, dls, (0, 3, 5), 10.0)
    assert found is not None and (found.row, found.dls, found.left_out) == (4, 3.0, 0)


def test_every_course_short_counts_them_all_and_says_so():
    md = np.array([0.0, 4.0, 8.0])
    found = max_dls(md, np.array([0.0, 6.0, 9.0]), (0, 3), 10.0)
    assert found is not None and found.all_short and (found.row, found.dls) == (2, 9.0)


def test_undefined_dls_is_not_a_maximum():
    md = np.array([0.0, 30.0, 60.0])
    found = max_dls(md, np.array([0.0, math.nan, 2.0]), (0, 3), 10.0)
    assert found is not None and found.dls == 2.0
    assert max_dls(np.array([0.0]), np.array([0.0]), (0, 1), 10.0) is None  # no course
    assert max_dls(md, np.array([0.0, math.nan, math.nan]), (0, 3), 10.0) is None

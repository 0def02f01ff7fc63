"""How reports print σ and azimuths: the rules, and a report of a well drilled due north
(azimuth 359.999°, vertical section at 359.9999°) written through ``gp.report``, where no
azimuth may print as 360 (issue #18, items 5 and 8)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from report_support import figure_svg, inspect, pdf_pages, svg_texts

import pipeline as gp
from pipeline.reports.numbers import (
    fmt,
    fmt_azimuth,
    fmt_azimuths,
    fmt_each,
    fmt_inches,
    fmt_measured,
    fmt_sigma,
    fmt_sigmas,
)


@pytest.mark.parametrize(
    ("sigma", "text"),
    [
        (4.2e-5, "4.2e−5"),
        (0.00012, "0.00012"),
        (0.0306, "0.031"),
        (0.0996, "0.10"),
        (1.187, "1.2"),
        (17.265, "17"),
        (123.4, "123"),
        (0.0, "0"),
        (float("inf"), "undefined"),
        (float("nan"), "undefined"),
        (None, ""),
    ],
)
def test_sigma_has_two_significant_digits(sigma: float | None, text: str):
    assert fmt_sigma(sigma) == text


@pytest.mark.parametrize(
    ("value", "sigma", "decimals", "text"),
    [
        (0.5234, 0.021, 3, "0.523"),  # σ coarser than the decimals: the decimals
        (1.2346, 0.31, 3, "1.235"),
        (0.00412, 0.00021, 3, "0.00412"),  # σ 0.00021: down to its second digit
        (4.1e-6, 2.0e-7, 3, "0.00000410"),
        (-4.1e-6, 2.0e-7, 2, "−0.00000410"),
        (0.0004, 0.03, 3, "0.000"),  # not known better than 0.03: zero at 3 decimals
        (2.5, float("nan"), 2, "2.50"),  # σ undefined: the usual decimals
        (2.5, 0.0, 2, "2.50"),
        (None, 0.1, 2, ""),
    ],
)
def test_a_measured_value_prints_down_to_its_sigma(
    value: float | None, sigma: float, decimals: int, text: str
):
    assert fmt_measured(value, sigma, decimals) == text


@pytest.mark.parametrize(
    ("azimuth", "decimals", "text"),
    [
        (-1e-13, 2, "0.00"),
        (359.996, 2, "0.00"),
        (359.994, 2, "359.99"),
        (359.96, 1, "0.0"),
        (360.0, 2, "0.00"),
        (725.5, 1, "5.5"),
        (-0.004, 2, "0.00"),
        (-0.006, 2, "359.99"),
        (37.0, 2, "37.00"),
    ],
)
def test_azimuth_that_rounds_to_360_prints_as_0(azimuth: float, decimals: int, text: str):
    assert fmt_azimuth(azimuth, decimals) == text


@pytest.mark.parametrize(
    ("metres", "text"),
    [
        (0.3112, "12¼"),  # 12.252 in: the bit size, as drilled
        (0.2159, "8½"),
        (0.4445, "17½"),
        (0.9144, "36"),
        (0.0127, "½"),
        (0.1556, "6 1/8"),  # an odd eighth: no such glyph in the report fonts
        (0.0032, "1/8"),
        (0.3137, "12.350"),  # no whole eighth: decimals
        (None, ""),
    ],
)
def test_hole_sizes_print_in_inches_as_the_industry_writes_them(metres: float | None, text: str):
    assert fmt_inches(metres) == text


def test_due_north_well_prints_no_azimuth_of_360(browser: Any, tmp_path: Path):
    md = np.arange(0.0, 1001.0, 100.0)
    stations = pd.DataFrame(
        {"md": md, "inc": np.linspace(0.0, 20.0, md.size), "azi": np.full(md.size, 359.999)}
    )
    well = {"north_reference": "true", "latitude": 61.25, "well": "due-north"}
    trajectory = gp.minimum_curvature(stations, well=well, vs_azimuth=359.9999)
    html, pdf = gp.report(trajectory, tmp_path / "report", well=well)

    page = inspect(browser, html)
    text = " ".join(page.text.split())
    assert "Vertical section azimuth 0.00° true north" in text
    assert re.search(r"Closure at TD [\d.]+ m @ 0\.00° true north", text)
    header = page.headers["listing"]
    assert page.units["listing"][header.index("VS")] == "m @ 0.0°"
    azimuths = [r[header.index("AZI")] for r in page.tables["listing"]]
    assert azimuths == ["0.00"] * md.size
    for key in ("plan", "section"):
        labels = " ".join(svg_texts(browser, figure_svg(html, key), "text"))
        assert "@ 0.00°" in labels and "360.0" not in labels
    assert not re.search(r"360\.0", text)

    words = " ".join(w[0] for p in pdf_pages(pdf, tmp_path) for w in p.words)
    assert "0.00° true north" in words and not re.search(r"360\.0", words)


FLOAT_COLUMNS = arrays(
    np.float64, st.integers(0, 300), elements=st.floats(allow_nan=True, allow_infinity=True)
)
"""Columns of up to 300 doubles of any value: NaN, ±∞, subnormals and −0 included."""


@settings(max_examples=200, deadline=None)
@given(FLOAT_COLUMNS, st.integers(0, 3))
def test_numbers_printed_together_read_as_each_printed_alone(values: np.ndarray, decimals: int):
    """``fmt_each`` (one ``%`` of a column) writes each number as ``fmt`` does: NaN, ±∞,
    negatives, −0 and the values that round to −0 among them."""
    values = np.concatenate([values, [-0.0, -0.004, -1e-300, np.nan, -np.inf, 2.675, 0.125]])
    assert fmt_each(values, decimals) == [fmt(v, decimals) for v in values.tolist()]


@settings(max_examples=200, deadline=None)
@given(FLOAT_COLUMNS)
def test_sigmas_printed_together_read_as_each_printed_alone(values: np.ndarray):
    """``fmt_sigmas`` (one ``%`` of a column, then one per count of decimals) writes each σ
    as ``fmt_sigma`` does: both notations, the roundings that carry into the next decade
    (9.96e−5 → 1.0e−4 prints fixed), zero, negatives, NaN and ±∞."""
    edges = [0.0, -0.0, 9.95e-5, 9.96e-5, 1e-4, 0.0996, 0.95, 9.96, 99.5, -2.0, -3e-6, 5e-324]
    values = np.concatenate([values, edges, [np.nan, np.inf, -np.inf]])
    assert fmt_sigmas(values) == [fmt_sigma(v) for v in values.tolist()]


@settings(max_examples=200, deadline=None)
@given(FLOAT_COLUMNS, st.integers(0, 3))
def test_azimuths_printed_together_read_as_each_printed_alone(values: np.ndarray, decimals: int):
    """``fmt_azimuths`` (a column wrapped and printed at once) writes each azimuth as
    ``fmt_azimuth`` does: wrapped into [0, 360), never 360 nor −0 (359.996 and −1e−13 print
    as 0), NaN as undefined, ±∞ as themselves."""
    edges = [0.0, -0.0, -1e-13, 359.995, 359.9949999, 359.95, 359.96, 360.0, 720.0, -360.0]
    values = np.concatenate([values, edges, [1e300, -1e300, np.nan, np.inf, -np.inf]])
    assert fmt_azimuths(values, decimals) == [fmt_azimuth(v, decimals) for v in values.tolist()]

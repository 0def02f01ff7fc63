"""Coordinates written in bulk (charts/fixed.py) read exactly as Python writes each number:
rounding ties (exact binary halves and three-decimal values near them), negative zero,
values that round to zero from below, NaN, and large and tiny magnitudes."""

from __future__ import annotations

import re
from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pipeline.reports.charts.fixed import BULK, path_texts, rows, runs
from pipeline.reports.charts.pdf import CIRCLE
from pipeline.reports.charts.scene import Path


def python(template: str, values: np.ndarray, decimals: int) -> str:
    """``str.format`` of each row (its fields ``{}`` or numbered ``{j}``)."""
    each = re.sub(r"\{(\d*)\}", rf"{{\1:.{decimals}f}}", template)
    return "".join(each.format(*row) for row in values.tolist())


CASES = {
    "uniform": np.random.default_rng(1).uniform(-1000.0, 1000.0, (300, 2)),
    "binary halves": np.arange(-400, 400).reshape(-1, 2) / 8.0,
    "three decimals": np.round(np.random.default_rng(2).uniform(-50.0, 50.0, (300, 2)), 3),
    "near zero": np.random.default_rng(3).uniform(-1.0, 1.0, (300, 2)) * 1e-3,
    "large": np.random.default_rng(4).uniform(0.0, 1e7, (300, 2)),
}


@pytest.mark.parametrize("decimals", [0, 1, 2, 3])
@pytest.mark.parametrize("case", sorted(CASES))
def test_rows_read_as_python_writes_each_number(case: str, decimals: int):
    values = CASES[case].copy()
    values[0, 0], values[1, 1] = -0.0, -0.004
    assert values.size >= BULK
    for template in ("{} {} l ", "M{},{}a1,1 0 1,0 2,0"):
        assert rows(template, values, decimals) == python(template, values, decimals)


def test_a_nan_is_written_as_python_writes_it():
    values = np.full((BULK, 2), 1.25)
    values[3, 1] = np.nan
    assert rows("{} {} ", values, 2) == python("{} {} ", values, 2)
    assert "nan" in rows("{} {} ", values, 2)


@settings(max_examples=200, deadline=None)
@given(
    arrays(np.float64, st.tuples(st.integers(1, 200), st.integers(1, 3)),
           elements=st.floats(-1e6, 1e6, allow_nan=False)),
    st.integers(0, 3),
)  # fmt: skip
def test_any_coordinates_read_as_python_writes_them(values: np.ndarray, decimals: int):
    template = "<" + "|".join(["{}"] * values.shape[1]) + ">"
    assert rows(template, values, decimals) == python(template, values, decimals)


@pytest.mark.parametrize("count", [300, 40])
def test_runs_cut_one_call_into_subpaths_as_python_writes_each_point(count: int):
    """The points of several subpaths written in one call (in bulk for many numbers, by
    Python's ``%`` for few) and cut back into the subpaths: each point as Python writes it,
    single points and empty runs too."""
    values = CASES["three decimals"][:count].copy()
    values[0, 0] = -0.0
    lengths = [1, 2, 0, count - 5, 1, 1]
    assert (values.size >= BULK) == (count == 300)
    found = runs("{} {} l ", values, 2, lengths)
    starts = np.cumsum([0, *lengths])
    assert found == [
        "".join(f"{x:.2f} {y:.2f} l " for x, y in values[a:b].tolist())
        for a, b in pairwise(starts.tolist())
    ]
    assert runs("{},{} ", values[:3], 1, [3]) == [
        "".join(f"{x:.1f},{y:.1f} " for x, y in values[:3])
    ]


@pytest.mark.parametrize("decimals", [0, 1, 2, 3])
def test_many_columns_between_texts_of_any_length_read_as_python_writes_them(decimals: int):
    """A row of many numbers (a marker's outline: 26) between texts of differing lengths,
    none at either end."""
    values = np.random.default_rng(6).uniform(-700.0, 700.0, (40, 13))
    values[5, 7] = -0.0
    template = "".join(f"{{}}{' ' * (j % 3)}{'c' * (j % 2)}" for j in range(13))
    assert values.size >= BULK and not template.startswith(" ")
    assert rows(template, values, decimals) == python(template, values, decimals)


@pytest.mark.parametrize("count", [BULK, 3])
@pytest.mark.parametrize("decimals", [0, 2])
def test_numbered_fields_write_their_column_wherever_they_appear(count: int, decimals: int):
    """``{j}`` fields (a circle's 26 numbers from its 10 columns, the PDF's template), in
    bulk and by Python: each as ``str.format`` writes it, a column left unwritten too."""
    values = np.random.default_rng(7).uniform(-700.0, 700.0, (count, 10))
    values[1, 3], values[2, 9] = -0.0, -0.004
    assert rows(CIRCLE, values, decimals) == python(CIRCLE, values, decimals)
    assert rows("{2}|{0}|{2}\n", values[:, :3], decimals) == python(
        "{2}|{0}|{2}\n", values[:, :3], decimals
    )


def test_a_percent_sign_in_the_template_is_text_in_the_few_numbers_path():
    """Fewer numbers than :data:`BULK` are written by Python's ``%``: a ``%`` of the
    template stays a character."""
    values = np.array([[1.005, -0.0], [np.inf, 250.5]])
    assert values.size < BULK
    assert rows("{}% of {}%%\n", values, 2) == "1.00% of -0.00%%\ninf% of 250.50%%\n"


def test_path_texts_write_each_path_as_python_writes_each_point():
    """The paths of a scene written in one call: each subpath's points as Python writes
    them (mapped first), empty subpaths left out; the short paths in bulk with a long one,
    rounding ties too, and by Python's ``%`` when all are short."""
    rng = np.random.default_rng(8)
    short = Path((rng.uniform(0, 500, (2, 2)), np.zeros((0, 2)), rng.uniform(0, 500, (5, 2))))
    single = Path((np.array([[18.125, -0.0]]),))  # mapped: a rounding tie, and −0
    empty = Path((np.zeros((0, 2)),))
    long = Path((rng.uniform(0, 500, (BULK // 2, 2)),))

    def python(path: Path) -> list[str]:
        parts = [part for part in path.parts if len(part)]
        return ["".join(f"{2 * x:.1f},{2 * y:.1f} " for x, y in part.tolist()) for part in parts]

    for paths in ([short, long, single, empty], [short, single, empty]):
        found = path_texts(paths, "{},{} ", 1, lambda p: p * 2.0)
        assert found == {id(path): python(path) for path in paths}
    assert path_texts([empty], "{} {} l ", 2) == {id(empty): []}

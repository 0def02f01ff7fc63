"""Drawn coordinates as text in bulk: each row of an array written into a template with a
fixed number of decimals — the same text as Python's ``f"{v:.2f}"``, its digits made by
integer arithmetic on the whole array (a long line or many markers cost a few array
operations, not a formatted string per number)."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Sequence
from functools import cache

import numpy as np
from numpy.typing import NDArray

from pipeline.reports.charts.scene import Path

BULK = 512
"""Arrays of fewer numbers are formatted by Python (the array operations cost more: some
60 µs a call, against 0.15 µs a number so)."""
LIMIT = 1e9
"""Largest scaled magnitude (value × 10^decimals) written from its digits: the product is
then within 1.2e-7 of exact, so rounding it to the nearest integer rounds the exact value."""
TIE = 1e-6
"""A scaled magnitude closer than this to a half (a rounding tie, to the product's error)
is rounded as Python rounds it (half to even on the exact value), from its own text."""


def rows(template: str, values: NDArray[np.float64], decimals: int) -> str:
    """Each row of ``values`` (n × k) written into ``template`` with ``decimals`` decimals,
    the rows one after the other. The template's fields are its k columns in order
    (``{}``) or numbered as ``str.format``'s (``{j}``: column j, written wherever it
    appears, each column's digits made once); plain text otherwise."""
    if values.size >= BULK:
        scaled = np.abs(values) * 10.0**decimals
        if scaled.max() < LIMIT:  # False for NaN
            units = np.rint(scaled)
            for i in np.flatnonzero(np.abs(scaled - np.floor(scaled) - 0.5) <= TIE).tolist():
                units.flat[i] = float(f"{abs(values.flat[i]):.{decimals}f}".replace(".", ""))
            return _digits(template, values, units, decimals)
    printf, fields = _printf(template, decimals)
    if fields is not None:
        values = values[:, fields]
    return printf * len(values) % tuple(values.ravel().tolist())


def point_texts(
    points: NDArray[np.float64], lengths: Sequence[int], decimals: int, sep: str
) -> list[list[str]]:
    """The rows (x, y) of ``points`` as ``f"{x:.2f}{sep}{y:.2f}"`` (``decimals`` decimals:
    :func:`rows`' text), in one call for all of them, cut into runs of ``lengths`` rows
    (the subpaths of a path laid end to end)."""
    texts = rows(f"{{}}{sep}{{}}\n", points, decimals).split("\n")
    runs, start = [], 0
    for length in lengths:
        runs.append(texts[start : start + length])
        start += length
    return runs


Few = dict[int, list[list[str]]]
"""The point texts of a scene's short paths' subpaths, by the path's ``id``."""


def few_point_texts(
    paths: Iterable[Path],
    decimals: int,
    sep: str,
    mapped: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
) -> Few:
    """:func:`point_texts` of the subpaths of each of ``paths`` with fewer than :data:`BULK`
    numbers (by ``id`` of the path; empty subpaths left out; ``mapped`` applied to the points
    first, row by row), in one call for all: a figure's many short paths (ticks, grid lines,
    frames) cost one formatting of all their numbers — in bulk — not a call each."""
    few = [
        (id(path), parts)
        for path in paths
        if 2 * sum(map(len, parts := [part for part in path.parts if len(part)])) < BULK
    ]
    lengths = [len(part) for _, parts in few for part in parts]
    if not lengths:
        return {key: [] for key, _ in few}
    points = np.concatenate([part for _, parts in few for part in parts])
    runs = iter(point_texts(mapped(points) if mapped else points, lengths, decimals, sep))
    return {key: [next(runs) for _ in parts] for key, parts in few}


def _digits(
    template: str, values: NDArray[np.float64], rounded: NDArray[np.float64], decimals: int
) -> str:
    """:func:`rows` from the digits of ``rounded`` (|values| × 10^decimals rounded to whole
    numbers as Python rounds them, each below :data:`LIMIT`): each number's characters in
    a field of one width (NUL where it has none), the template's text beside them, gathered
    into the rows. The characters are made a column of the fields at a time, each column one
    contiguous row of ``planes`` (a strided store of bytes costs some 2 ns each, a contiguous
    one a tenth of that), and the rows transposed once at the end."""
    n, k = values.shape
    units = rounded.T.astype(np.uint32, order="C")  # < LIMIT < 2³²; (k, n)
    digits = max(len(str(int(units.max()))), decimals + 1)  # one at least before the point
    point = 1 if decimals else 0
    width = 1 + digits + point
    index, text = _layout(template, k, width)
    planes = np.empty((k * width + len(text), n), np.uint8)  # a character column a row
    planes[k * width :] = np.frombuffer(text, np.uint8)[:, None]
    field = planes[: k * width].reshape(k, width, n)
    np.multiply(np.signbit(values.T), ord("-"), out=field[:, 0], casting="unsafe")  # "-0.0" too
    if decimals:
        field[:, width - 1 - decimals] = ord(".")
    rest = units
    for place in range(digits):  # from the last decimal leftwards
        column = width - 1 - place - (point if place >= decimals else 0)
        quotient = rest // np.uint32(10)  # a divmod's remainder costs 5× this division
        digit = rest - quotient * np.uint32(10)
        digit += np.uint32(ord("0"))
        if place > decimals:  # a leading zero is no character
            digit *= units >= 10**place
        field[:, column] = digit
        rest = quotient
    return planes[index].T.tobytes().translate(None, b"\0").decode("ascii")  # NULs dropped


FIELD = re.compile(r"\{(\d*)\}")
"""A template's field: ``{}`` (the next column) or ``{j}`` (column j)."""


@cache
def _fields(template: str) -> tuple[list[str], tuple[int, ...]]:
    """``template``'s text between its fields (one more piece than fields) and the column
    each field writes."""
    parts = FIELD.split(template)
    numbers = parts[1::2]
    if all(numbers):
        fields = tuple(map(int, numbers))
    else:
        assert not any(numbers), "fields all numbered or none"
        fields = tuple(range(len(numbers)))
    return parts[::2], fields


@cache
def _printf(template: str, decimals: int) -> tuple[str, list[int] | None]:
    """``template`` as a ``%`` format of its fields with ``decimals`` decimals (``"%.2f"``
    prints a float as ``f"{v:.2f}"`` does, NaN, infinities and −0 alike; one ``%`` of all the
    rows at once costs half a ``str.format`` call per row), and the column of each field
    (None: the columns in order)."""
    pieces, fields = _fields(template)
    ordered = fields == tuple(range(len(fields)))
    return f"%.{decimals}f".join(p.replace("%", "%%") for p in pieces), (
        None if ordered else list(fields)
    )


@cache
def _layout(template: str, k: int, width: int) -> tuple[NDArray[np.intp], bytes]:
    """A row of ``template`` as the character columns it is gathered from, of ``k`` fields
    of ``width`` characters (one a column) followed by the template's text."""
    pieces, fields = _fields(template)
    assert all(f < k for f in fields), "a field of each column"
    index: list[int] = []
    at = k * width
    for j, piece in enumerate(pieces):
        index.extend(range(at, at + len(piece)))
        at += len(piece)
        if j < len(fields):
            index.extend(range(fields[j] * width, (fields[j] + 1) * width))
    return np.array(index, np.intp), "".join(pieces).encode("ascii")

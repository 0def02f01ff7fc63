"""Drawn coordinates as text in bulk: each row of an array written into a template with a
fixed number of decimals — the same text as Python's ``f"{v:.2f}"``, its digits made by
integer arithmetic on the whole array (a long line or many markers cost a few array
operations, not a formatted string per number)."""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Sequence
from functools import cache
from itertools import accumulate, pairwise

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
    units = _units(values, decimals)
    if units is not None:
        return _text(_digits(template, values, units, decimals))
    printf, fields = _printf(template, decimals)
    if fields is not None:
        values = values[:, fields]
    return printf * len(values) % tuple(values.ravel().tolist())


def runs(
    template: str, values: NDArray[np.float64], decimals: int, lengths: Sequence[int]
) -> list[str]:
    """:func:`rows`' text of ``values`` cut into runs of ``lengths`` rows (laid end to end),
    in one call for all of them: each run the text of its rows, one after the other."""
    bounds = list(accumulate(lengths, initial=0))
    units = _units(values, decimals)
    if units is None:
        printf, fields = _printf(template, decimals)
        numbers = (values if fields is None else values[:, fields]).ravel().tolist()
        k = len(numbers) // len(values) if len(values) else 0  # numbers a row
        return [printf * (b - a) % tuple(numbers[k * a : k * b]) for a, b in pairwise(bounds)]
    chars = _digits(template, values, units, decimals)
    ends = np.concatenate([[0], np.cumsum(np.count_nonzero(chars, axis=0))])  # row by row
    text = _text(chars)
    return [text[a:b] for a, b in pairwise(ends[bounds].tolist())]


def path_texts(
    paths: Iterable[Path],
    template: str,
    decimals: int,
    mapped: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None,
) -> dict[int, list[str]]:
    """The text of each of ``paths``' subpaths (its points as :func:`rows` writes them into
    ``template``; empty subpaths left out; ``mapped`` applied to the points first, row by
    row), by ``id`` of the path, in one call for all: a figure's lines and its many short
    paths (ticks, grid lines, frames) cost one formatting of all their numbers, in bulk."""
    found = [(id(path), [part for part in path.parts if len(part)]) for path in paths]
    lengths = [len(part) for _, parts in found for part in parts]
    if not lengths:
        return {key: [] for key, _ in found}
    points = np.concatenate([part for _, parts in found for part in parts])
    texts = iter(runs(template, mapped(points) if mapped else points, decimals, lengths))
    return {key: [next(texts) for _ in parts] for key, parts in found}


def _units(values: NDArray[np.float64], decimals: int) -> NDArray[np.float64] | None:
    """|values| × 10^decimals rounded to whole numbers as Python rounds them, for
    :func:`_digits`; None where Python writes them (fewer than :data:`BULK`, NaN, a
    magnitude of :data:`LIMIT` or more)."""
    if values.size < BULK:
        return None
    scaled = np.abs(values) * 10.0**decimals
    if not scaled.max() < LIMIT:  # NaN too
        return None
    units = np.rint(scaled)
    for i in np.flatnonzero(np.abs(scaled - np.floor(scaled) - 0.5) <= TIE).tolist():
        units.flat[i] = float(f"{abs(values.flat[i]):.{decimals}f}".replace(".", ""))
    return units


def _text(chars: NDArray[np.uint8]) -> str:
    """The rows of :func:`_digits`' characters one after the other, NULs dropped."""
    return chars.T.tobytes().translate(None, b"\0").decode("ascii")


def _digits(
    template: str, values: NDArray[np.float64], rounded: NDArray[np.float64], decimals: int
) -> NDArray[np.uint8]:
    """The characters of :func:`rows` from the digits of ``rounded`` (:func:`_units`), a
    column a row (NUL where a field has no character): each number's characters in a
    field of one width, the template's text beside them, gathered into the rows. The
    characters are made a column of the fields at a time, each column one contiguous row
    of ``planes`` (a strided store of bytes costs some 2 ns each, a contiguous one a tenth
    of that); :func:`_text` transposes the rows once at the end."""
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
    return planes[index]


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

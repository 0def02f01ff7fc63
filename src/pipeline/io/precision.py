"""The precision exports write each column at: decimals fit for its unit, so a file holds
``914.4`` and ``30``, not ``914.4000000000001`` and ``29.999999847691296``.

Every step is finer than any survey measurement resolves (0.1 mm, 0.000001°, 1 µs,
0.1 ng…), so a value read back differs from the computed one by at most half a step of
its unit (``0.5 * 10**-DECIMALS[unit]``, plus the float's own rounding); columns whose unit
is not listed (and integer or text columns) keep their full, shortest round-trip, precision.
``source_line`` (the lines of a file read, an internal column of a read table) is never
written: :func:`for_export` leaves it out, for every text export (CSV, LAS).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TypeVar

import numpy as np
import pyarrow as pa

from pipeline.contracts import SOURCE_LINE, UNIT_KEY

DECIMALS: dict[str, int] = {
    "m": 4,  # 0.1 mm
    "m2": 8,  # (0.1 mm)², the length step squared: small covariances keep their digits
    "deg": 6,  # 0.0036″
    "deg/30m": 4,
    "deg/h": 6,
    "deg/h2": 6,
    "deg/min": 8,  # finer than deg/h's step (1e-6 °/h ≈ 1.7e-8 °/min)
    "m/s2": 9,  # ≈ 0.1 ng
    "nT": 3,
    "s": 6,  # 1 µs
    "degC": 3,
}
"""Canonical unit → decimals written."""
FULL_TURN = 360.0
"""deg: an angle below it stays below it when rounded (azimuths, toolfaces and frame angles
are [0, 360) by contract), so 359.9999997 is written 359.999999, not 360."""

_EXACT = 2.0**52
"""From this magnitude on, a float64 is a whole number: rounding leaves it as it is."""
BLOCK_VALUES = 1 << 16
"""The most values of several columns stacked into one array (:func:`blocks`)."""
T = TypeVar("T")


def for_export(table: pa.Table) -> pa.Table:
    """``table`` as an export writes it: without ``source_line`` (the line numbers of the
    file it was read from mean nothing in another file), every float column of a listed
    unit rounded to its decimals (half to even; −0 written as 0; NaN, ±inf and nulls as
    they are; an angle below 360° stays below it, one step under, :data:`FULL_TURN`). The
    columns of one rounding are rounded together, as rows of one array (:func:`blocks`; the
    same numbers: every step is elementwise)."""
    if SOURCE_LINE in table.column_names:
        table = table.drop_columns([SOURCE_LINE])
    columns = list(table.columns)
    rounding: dict[tuple[int, float | None], list[int]] = {}
    for i, field in enumerate(table.schema):
        unit = (field.metadata or {}).get(UNIT_KEY, b"").decode()
        decimals = DECIMALS.get(unit)
        if decimals is not None and pa.types.is_floating(field.type):
            below = FULL_TURN if unit == "deg" else None
            rounding.setdefault((decimals, below), []).append(i)
    for (decimals, below), same in rounding.items():
        for at in blocks(same, table.num_rows):
            arrays = [columns[i].combine_chunks() for i in at]
            for i, array in zip(at, _rounded(arrays, decimals, below), strict=True):
                columns[i] = array
    return pa.Table.from_arrays(columns, schema=table.schema)


def blocks(columns: list[T], rows: int) -> Iterator[list[T]]:
    """``columns`` (of ``rows`` values each) in blocks to be stacked into one array of at
    most :data:`BLOCK_VALUES` values (a column alone if longer): the columns of a small
    table in one step, a long one's one at a time, so no copy of a long table is made."""
    step = max(1, BLOCK_VALUES // max(rows, 1))
    for start in range(0, len(columns), step):
        yield columns[start : start + step]


def _rounded(arrays: list[pa.Array], decimals: int, below: float | None) -> list[pa.Array]:
    """``arrays`` (floats, of one length) rounded to ``decimals``. numpy scales, rounds and
    divides back, so a value is the float nearest its decimal text (pyarrow's round keeps
    ``914.4000000000001``). A value under ``below`` that would round up to it is written one
    step under it."""
    values = [array.to_numpy(zero_copy_only=False) for array in arrays]
    wide = np.stack(values).astype(np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        rounded = np.where(np.abs(wide) < _EXACT, np.round(wide, decimals), wide) + 0.0
        if below is not None:
            under = np.round(below - 10.0**-decimals, decimals)
            rounded = np.where((wide < below) & (rounded >= below), under, rounded)
    return [
        pa.array(
            row.astype(column.dtype),
            type=array.type,
            mask=array.is_null().to_numpy(zero_copy_only=False) if array.null_count else None,
        )
        for row, column, array in zip(rounded, values, arrays, strict=True)
    ]

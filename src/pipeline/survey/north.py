"""Azimuth north references: true (gyro), grid and magnetic. Angles in degrees.

Sign conventions (both corrections clockwise positive, i.e. east of true north):

* declination D — magnetic north east of true north:  A_true = A_mag + D,  A_mag = A_true − D
* convergence γ — grid north east of true north (:func:`pipeline.earth.grid.grid_convergence`):
  A_grid = A_true − γ,  A_true = A_grid + γ

So grid ↔ magnetic goes through true: A_grid = A_mag + D − γ. Results are wrapped to [0, 360).
"""

from __future__ import annotations

import datetime as dt
from typing import get_args

import numpy as np
import pyarrow as pa
from numpy.typing import ArrayLike

from pipeline.contracts import NORTH_KEY
from pipeline.earth.frames import FloatArray
from pipeline.earth.geomagnetic import ModelKey, reference_field
from pipeline.earth.grid import grid_convergence
from pipeline.well import NorthReference

__all__ = [
    "NORTH_REFERENCES",
    "convergence_at",
    "convert_azimuth",
    "convert_table",
    "declination_at",
    "turned_positions",
    "wrap_360",
]

NORTH_REFERENCES: tuple[str, ...] = get_args(get_args(NorthReference)[0])


def wrap_360(azimuth_deg: ArrayLike) -> FloatArray:
    """Azimuths wrapped into [0, 360)."""
    wrapped = np.mod(np.asarray(azimuth_deg, dtype=np.float64), 360.0)
    # mod of a tiny negative number rounds up to 360
    out: FloatArray = np.where(wrapped >= 360.0, 0.0, wrapped)
    return out


def _offset_from_true(
    reference: str, convergence_deg: ArrayLike | None, declination_deg: ArrayLike | None
) -> FloatArray:
    """δ such that A_ref = A_true − δ (0 true, γ grid, D magnetic)."""
    if reference == "true":
        return np.zeros(())
    if reference == "grid":
        if convergence_deg is None:
            raise ValueError("grid north needs the grid convergence γ (deg)")
        return np.asarray(convergence_deg, dtype=np.float64)
    if reference == "magnetic":
        if declination_deg is None:
            raise ValueError("magnetic north needs the magnetic declination D (deg)")
        return np.asarray(declination_deg, dtype=np.float64)
    raise ValueError(f"unknown north reference {reference!r}; expected one of {NORTH_REFERENCES}")


def convert_azimuth(
    azimuth_deg: ArrayLike,
    source: str,
    target: NorthReference,
    *,
    convergence_deg: ArrayLike | None = None,
    declination_deg: ArrayLike | None = None,
) -> tuple[FloatArray, NorthReference]:
    """Azimuths referred to ``source`` north, converted to ``target`` north, in [0, 360), with
    the new reference label. γ (``convergence_deg``) is needed when grid is involved and D
    (``declination_deg``, east positive) when magnetic is; scalars or per-azimuth arrays.

    Raises:
        ValueError: an unknown reference or a missing correction.
    """
    a = np.asarray(azimuth_deg, dtype=np.float64)
    if source == target:
        _offset_from_true(source, convergence_deg, declination_deg)  # still validates the name
        return wrap_360(a), target
    true = a + _offset_from_true(source, convergence_deg, declination_deg)
    return wrap_360(true - _offset_from_true(target, convergence_deg, declination_deg)), target


def declination_at(
    latitude_deg: float,
    longitude_deg: float,
    date: dt.date,
    *,
    height_m: float = 0.0,
    model: ModelKey = "wmm2025",
) -> float:
    """Magnetic declination D (deg, east positive) of ``model`` at a point and date."""
    field = reference_field(latitude_deg, longitude_deg, height_m, date, model=model)
    return float(field.declination.reshape(()))


def convergence_at(latitude_deg: float, longitude_deg: float, crs: str | int) -> float:
    """Grid convergence γ (deg, grid north east of true north positive) of ``crs`` at a point."""
    return float(grid_convergence(latitude_deg, longitude_deg, crs))


def convert_table(
    table: pa.Table,
    target: NorthReference,
    *,
    convergence_deg: float | None = None,
    declination_deg: float | None = None,
) -> pa.Table:
    """``table`` with every column whose field states a north reference converted to
    ``target`` (values wrapped to [0, 360), metadata relabelled), and the positions a
    stations file lists (``north``, ``east``: in the azimuths' reference) turned with them;
    other columns untouched."""
    columns: list[pa.Array | pa.ChunkedArray] = []
    fields: list[pa.Field] = []
    turned = _turned_positions(table, target, convergence_deg, declination_deg)
    for name in table.column_names:
        fld = table.schema.field(name)
        meta = dict(fld.metadata or {})
        column = table.column(name)
        if name in turned:
            column = pa.array(turned[name], type=fld.type)
        elif NORTH_KEY in meta:
            values, label = convert_azimuth(
                column.to_numpy(),
                meta[NORTH_KEY].decode(),
                target,
                convergence_deg=convergence_deg,
                declination_deg=declination_deg,
            )
            meta[NORTH_KEY] = label.encode()
            column = pa.array(values, type=fld.type)
            fld = fld.with_metadata(meta)
        columns.append(column)
        fields.append(fld)
    return pa.Table.from_arrays(columns, schema=pa.schema(fields, metadata=table.schema.metadata))


def _turned_positions(
    table: pa.Table,
    target: NorthReference,
    convergence_deg: float | None,
    declination_deg: float | None,
) -> dict[str, FloatArray]:
    """``north`` and ``east`` (a horizontal position, m, referred to the north of the
    ``azi`` column) referred to ``target`` north: turned by the azimuths' change δ
    (A' = A + δ), so N' = N cos δ − E sin δ, E' = E cos δ + N sin δ. Nothing to turn: {}."""
    names = table.column_names
    if not {"azi", "north", "east"} <= set(names):
        return {}
    meta = table.schema.field("azi").metadata or {}
    if NORTH_KEY not in meta or any(
        NORTH_KEY in (table.schema.field(c).metadata or {}) for c in ("north", "east")
    ):
        return {}
    zero = np.zeros(table.num_rows)
    shift, _ = convert_azimuth(
        zero,
        meta[NORTH_KEY].decode(),
        target,
        convergence_deg=convergence_deg,
        declination_deg=declination_deg,
    )
    north, east = turned_positions(
        table.column("north").to_numpy(zero_copy_only=False).astype(float),
        table.column("east").to_numpy(zero_copy_only=False).astype(float),
        shift,
    )
    return {"north": north, "east": east}


def turned_positions(
    north: ArrayLike, east: ArrayLike, shift_deg: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Horizontal positions (m) referred to the north whose azimuths are A' = A + δ
    (``shift_deg``: δ, deg, the change :func:`convert_azimuth` makes to an azimuth):
    N' = N cos δ − E sin δ, E' = E cos δ + N sin δ."""
    n, e = np.asarray(north, dtype=np.float64), np.asarray(east, dtype=np.float64)
    delta = np.radians(shift_deg)
    return n * np.cos(delta) - e * np.sin(delta), e * np.cos(delta) + n * np.sin(delta)

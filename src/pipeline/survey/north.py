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


AXIS_COLUMNS = ("ellipse_azimuth",)
"""Columns of an axis's direction (the error ellipse's major axis), in [0, 180)."""


def convert_table(
    table: pa.Table,
    target: NorthReference,
    *,
    convergence_deg: float | None = None,
    declination_deg: float | None = None,
) -> pa.Table:
    """``table`` with every column whose field states a north reference converted to
    ``target`` (values wrapped to [0, 360), an axis's, :data:`AXIS_COLUMNS`, to [0, 180);
    metadata relabelled), and the positions and position covariances a stations file lists
    (``north``, ``east``, ``cov_*``: in the azimuths' reference) turned with them; other
    columns untouched."""
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
            column = pa.array(values % 180.0 if name in AXIS_COLUMNS else values, type=fld.type)
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
    (A' = A + δ), so N' = N cos δ − E sin δ, E' = E cos δ + N sin δ; and the NEV position
    covariance (``cov_nn`` … ``cov_vv``, m², the file's uncertainty in the same frame) turned
    with them (:func:`turned_covariance`). Nothing to turn: {}."""
    names = set(table.column_names)
    meta = (table.schema.field("azi").metadata or {}) if "azi" in names else {}
    if NORTH_KEY not in meta:
        return {}
    shift, _ = convert_azimuth(
        np.zeros(table.num_rows),
        meta[NORTH_KEY].decode(),
        target,
        convergence_deg=convergence_deg,
        declination_deg=declination_deg,
    )

    def values(name: str) -> FloatArray:
        found: FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
        return found

    turned: dict[str, FloatArray] = {}
    if {"north", "east"} <= names and not any(
        NORTH_KEY in (table.schema.field(c).metadata or {}) for c in ("north", "east")
    ):
        turned["north"], turned["east"] = turned_positions(values("north"), values("east"), shift)
    if set(COVARIANCE_COLUMNS) <= names:
        cov = turned_covariance([values(c) for c in COVARIANCE_COLUMNS], shift)
        turned.update(zip(COVARIANCE_COLUMNS, cov, strict=True))
    return turned


COVARIANCE_COLUMNS = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
"""The NEV position covariance columns (m²) a stations file may list."""


def turned_covariance(cov: list[FloatArray], shift_deg: ArrayLike) -> tuple[FloatArray, ...]:
    """The NEV covariance entries ``cov`` (nn, ne, nv, ee, ev, vv; m²) referred to the north
    whose azimuths are A' = A + δ (``shift_deg``): C' = R C Rᵀ with R turning (N, E) as
    :func:`turned_positions` does; the vertical variance is unchanged."""
    nn, ne, nv, ee, ev, vv = cov
    delta = np.radians(shift_deg)
    c, s = np.cos(delta), np.sin(delta)
    return (
        c * c * nn - 2 * c * s * ne + s * s * ee,
        c * s * (nn - ee) + (c * c - s * s) * ne,
        c * nv - s * ev,
        s * s * nn + 2 * c * s * ne + c * c * ee,
        s * nv + c * ev,
        vv,
    )


def turned_positions(
    north: ArrayLike, east: ArrayLike, shift_deg: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Horizontal positions (m) referred to the north whose azimuths are A' = A + δ
    (``shift_deg``: δ, deg, the change :func:`convert_azimuth` makes to an azimuth):
    N' = N cos δ − E sin δ, E' = E cos δ + N sin δ."""
    n, e = np.asarray(north, dtype=np.float64), np.asarray(east, dtype=np.float64)
    delta = np.radians(shift_deg)
    return n * np.cos(delta) - e * np.sin(delta), e * np.cos(delta) + n * np.sin(delta)

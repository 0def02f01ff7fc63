"""Vendor conventions, declared per source and converted once, at ingest, to the canonical
frame of DOMAIN.md §2 (body z along the tool axis downhole; gyros right-handed; the
accelerometers in the gravity sign convention, reading C_n^b·(0, 0, g) at rest; toolface
clockwise looking downhole from the high side).

A source declares how its axes relate to the canonical ones as a signed permutation, e.g.
``axes: ["y", "-x", "z"]`` (canonical x = vendor y, canonical y = −vendor x, canonical z =
vendor z); a left-handed vendor frame is a permutation with determinant −1 (``["x", "y",
"-z"]`` for a tool whose z points up-hole with x, y kept).
"""

from __future__ import annotations

import re
from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, field_validator

from pipeline.earth.frames import FloatArray

AXES = ("x", "y", "z")
_AXIS = re.compile(r"^[+-]?[xyz]\Z")


class Conventions(BaseModel):
    """How a source's sensor data differ from the canonical conventions (defaults: none)."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    axes: tuple[str, str, str] = Field(
        ("x", "y", "z"),
        description="vendor axis giving each canonical axis x, y, z, with an optional '-'",
    )
    accelerometer: Literal["gravity", "specific_force"] = Field(
        "gravity",
        description="'specific_force' if the tool reads −g at rest (it is then negated)",
    )
    gyro_rotation: Literal["right_hand", "left_hand"] = Field(
        "right_hand", description="'left_hand' if positive rates turn clockwise about the axis"
    )
    toolface_direction: Literal["clockwise", "counterclockwise"] = Field(
        "clockwise", description="direction toolface grows, looking downhole"
    )
    toolface_offset: float = Field(
        0.0, description="vendor toolface at the canonical zero (high side), deg"
    )
    frame_angle_direction: Literal["clockwise", "counterclockwise"] = Field(
        "clockwise", description="direction the frame angle grows, looking downhole"
    )

    @field_validator("axes")
    @classmethod
    def _signed_permutation(cls, axes: tuple[str, str, str]) -> tuple[str, str, str]:
        cleaned = tuple(a.strip().lower() for a in axes)
        if not all(_AXIS.match(a) for a in cleaned) or sorted(
            a.lstrip("+-") for a in cleaned
        ) != list(AXES):
            raise ValueError(f"axes must be a signed permutation of x, y, z, got {list(axes)}")
        return (cleaned[0], cleaned[1], cleaned[2])

    def matrix(self) -> FloatArray:
        """M with canonical = M · vendor, a signed permutation matrix."""
        m = np.zeros((3, 3))
        for row, name in enumerate(self.axes):
            m[row, AXES.index(name.lstrip("+-"))] = -1.0 if name.startswith("-") else 1.0
        return m


def to_canonical(table: pa.Table, conventions: Conventions) -> pa.Table:
    """The table with sensor triads, toolface and frame angle in the canonical conventions
    (columns keep their names, units and metadata). A permutation that mixes axes needs
    all three columns of each triad present."""
    if conventions == Conventions():
        return table
    m = conventions.matrix()
    mixes = not np.array_equal(np.abs(m), np.eye(3))
    signs = {
        "gyro": -1.0 if conventions.gyro_rotation == "left_hand" else 1.0,
        "acc": -1.0 if conventions.accelerometer == "specific_force" else 1.0,
        "mag": 1.0,
    }
    for triad, sign in signs.items():
        names = [f"{triad}_{a}" for a in AXES]
        present = [n in table.column_names for n in names]
        if not any(present):
            continue
        if mixes and not all(present):
            raise ValueError(
                f"axes {list(conventions.axes)} mix axes: {triad} needs columns {names}"
            )
        vendor = [
            table.column(n).to_numpy(zero_copy_only=False) if p else None
            for n, p in zip(names, present, strict=True)
        ]
        for i, name in enumerate(names):
            if present[i]:
                j = int(np.flatnonzero(m[i])[0])
                table = _replace(table, name, sign * m[i, j] * vendor[j])
    for column, direction, offset in (
        ("toolface", conventions.toolface_direction, conventions.toolface_offset),
        ("frame_angle", conventions.frame_angle_direction, 0.0),
    ):
        if column in table.column_names and (direction != "clockwise" or offset):
            values = table.column(column).to_numpy(zero_copy_only=False)
            sign = -1.0 if direction == "counterclockwise" else 1.0
            angle = np.mod(sign * (values - offset), 360.0)
            table = _replace(table, column, np.where(angle >= 360.0, 0.0, angle))
    return table


def _replace(table: pa.Table, name: str, values: FloatArray) -> pa.Table:
    """Replace a column's values, keeping its field (units) and its nulls."""
    index = table.schema.get_field_index(name)
    column = table.column(name)
    mask = column.is_null().to_numpy(zero_copy_only=False) if column.null_count else None
    return table.set_column(index, table.schema.field(name), pa.array(values, mask=mask))

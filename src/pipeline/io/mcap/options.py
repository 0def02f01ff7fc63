"""Options of the MCAP reader (:mod:`pipeline.io.mcap`): the topics to read, the message key
and unit of a canonical column, keys to skip, vendor conventions and how topics are joined;
checked against the raw-samples columns and triads."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from pipeline.errors import UnitError
from pipeline.io.conventions import Conventions
from pipeline.io.mnemonics import CURVES
from pipeline.tables import RawSamples
from pipeline.units import conversion_factor

SAMPLE_COLUMNS = tuple(c.name for c in RawSamples.compiled().columns)
TRIADS = ("gyro", "acc", "mag")


class McapOptions(BaseModel):
    """Options of the MCAP reader; gyropipe's own files need none."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    topics: list[str] | None = Field(
        None, description="topics to read (default: every channel readable as samples)"
    )
    columns: dict[str, str] = Field(
        default_factory=dict,
        description="message key of a canonical column (JSON/protobuf), e.g. {gyro_x: wx}",
    )
    units: dict[str, str] = Field(
        default_factory=dict,
        description="unit of a canonical column or of a whole triad (gyro, acc, mag), "
        "e.g. {gyro: rad/s, time: s}; wins over units declared in the file",
    )
    ignore: list[str] = Field(
        default_factory=list, description="message keys to skip (with their sub-keys)"
    )
    conventions: Conventions | None = Field(
        None,
        description="vendor conventions of the sensor data (default: canonical, except ROS "
        "Imu accelerometers: specific force)",
    )
    join: Literal["exact", "interpolate"] = Field(
        "exact", description="how other topics join the base topic's sample times"
    )

    @field_validator("columns")
    @classmethod
    def _canonical(cls, columns: dict[str, str]) -> dict[str, str]:
        unknown = sorted(set(columns) - set(SAMPLE_COLUMNS))
        if unknown:
            raise ValueError(
                f"unknown columns {unknown}; raw-samples columns: {list(SAMPLE_COLUMNS)}"
            )
        return columns

    @field_validator("units")
    @classmethod
    def _units(cls, units: dict[str, str]) -> dict[str, str]:
        for name, unit in units.items():
            curve = CURVES.get(f"{name}_x" if name in TRIADS else name)
            if curve is None or curve.quantity is None or curve.name not in SAMPLE_COLUMNS:
                raise ValueError(f"units: {name!r} is not a raw-samples column with a unit")
            try:
                conversion_factor(unit, curve.quantity)
            except UnitError as exc:
                raise ValueError(f"units: {name}: {exc}") from None
        return units

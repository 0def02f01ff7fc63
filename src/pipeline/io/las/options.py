"""Options of the LAS reader (:mod:`pipeline.io.las`): the curve and unit of a canonical
column, the azimuths' north reference, vendor conventions of the sensor curves and values
meaning 'no value'."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, field_validator

from pipeline.errors import UnitError
from pipeline.io.conventions import Conventions
from pipeline.io.mnemonics import CURVES
from pipeline.plausibility import AngleUnitConfirmed, NullStations
from pipeline.units import conversion_factor
from pipeline.well import DefaultNorthReference, NorthReference


class LasOptions(BaseModel):
    """Options of the LAS reader; every one may be left to the file."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    columns: dict[str, str] = Field(
        default_factory=dict,
        description="curve mnemonic of a canonical column, e.g. {md: DEPT, gyro_x: GYRO1}",
    )
    units: dict[str, str] = Field(
        default_factory=dict,
        description="unit of a canonical column's curve, e.g. {md: ft}; overrides the file's",
    )
    north_reference: NorthReference | None = Field(
        None, description="north reference of the azimuths (true, grid or magnetic)"
    )
    default_north_reference: DefaultNorthReference = None
    angle_unit_confirmed: AngleUnitConfirmed = False
    null_stations: NullStations = "error"
    conventions: Conventions = Field(
        default_factory=Conventions,
        description="vendor axis and sign conventions of the sensor curves (samples)",
    )
    null_values: list[float] = Field(
        default_factory=list, description="values meaning 'no value' besides the file's NULL"
    )

    @field_validator("columns")
    @classmethod
    def _known_columns(cls, columns: dict[str, str]) -> dict[str, str]:
        unknown = sorted(set(columns) - set(CURVES))
        if unknown:
            raise ValueError(f"unknown column(s) {unknown}; known: {', '.join(CURVES)}")
        return columns

    @field_validator("units")
    @classmethod
    def _valid_units(cls, units: dict[str, str]) -> dict[str, str]:
        for name, unit in units.items():
            curve = CURVES.get(name)
            if curve is None or curve.quantity is None:
                raise ValueError(f"{name!r} is not a canonical column with a unit")
            try:
                conversion_factor(unit, curve.quantity)
            except UnitError as exc:
                raise ValueError(f"{name}: {exc}") from None
        return units

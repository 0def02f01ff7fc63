"""The core table contracts exchanged by built-in stages.

Canonical units: lengths in metres, angles in degrees, dogleg severity in °/30 m. Azimuth
columns state their north reference (true, grid or magnetic) in field metadata.
"""

from __future__ import annotations

from pipeline.contracts import TableContract, column

DLS_UNIT = "deg/30m"


class AnyTable(TableContract):
    """Any table (writers and generic stages)."""


class Stations(TableContract):
    """Survey stations, one row per station, in increasing MD (per survey when ``survey``
    is present: several surveys may share one table, each a contiguous block of rows)."""

    group_by = "survey"

    survey: str | None = column(
        unit=None, description="survey id when a table holds several surveys", default=None
    )
    md: float = column(unit="m", ge=0, monotonic="strict", description="measured depth")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination from vertical")
    azi: float = column(
        unit="deg", north_reference=True, description="azimuth, clockwise from north"
    )


class Trajectory(Stations):
    """Stations with integrated positions (NED: north, east, TVD down) relative to the
    wellhead, dogleg, vertical section and closure."""

    azi: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        description="azimuth in [0, 360), clockwise from north",
    )
    tvd: float = column(unit="m", description="true vertical depth below the depth reference")
    north: float = column(unit="m", description="northing from the wellhead")
    east: float = column(unit="m", description="easting from the wellhead")
    dogleg: float = column(
        unit="deg", ge=0, le=180, description="dogleg angle from the previous station"
    )
    dls: float = column(unit=DLS_UNIT, ge=0, description="dogleg severity")
    vertical_section: float = column(
        unit="m", description="horizontal displacement projected on the section azimuth"
    )
    closure_distance: float = column(
        unit="m", ge=0, description="horizontal distance from the wellhead"
    )
    closure_direction: float = column(
        unit="deg",
        ge=0,
        lt=360,
        north_reference=True,
        description="direction of the closure, clockwise from north",
    )


class CheckResults(TableContract):
    """Results of QC checks, one row per checked row."""

    check: str = column(unit=None, description="check name")
    row: int = column(unit=None, ge=0, description="row index in the checked table")
    md: float | None = column(unit="m", description="measured depth of the row, if known")
    value: float = column(unit=None, finite=False, description="checked quantity (in `unit`)")
    limit: float = column(unit=None, description="tolerance (in `unit`)")
    unit: str = column(unit=None, description="unit of value and limit")
    passed: bool = column(unit=None, description="value within tolerance")

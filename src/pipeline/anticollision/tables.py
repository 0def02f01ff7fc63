"""Contracts of the clearance tables: the offset wells of a scan and its results.

The offset wells' stations travel as one :class:`~pipeline.tables.Stations` table whose
``survey`` column names each well (its ``well_id``).
"""

from __future__ import annotations

import json
from typing import Any

import pyarrow as pa

from pipeline.contracts import TableContract, column

RULE_KEY = b"gyropipe.clearance_rule"
"""Schema metadata of a clearance table: the rule's parameters and each well's tool model
and hole diameter (JSON), for the report to state."""


def with_rule(table: pa.Table, rule: dict[str, Any]) -> pa.Table:
    """``table`` with the rule's parameters in its schema metadata."""
    meta = {**(table.schema.metadata or {}), RULE_KEY: json.dumps(rule).encode()}
    return table.replace_schema_metadata(meta)


def rule_of(table: pa.Table) -> dict[str, Any]:
    """The rule's parameters a clearance table carries ({} when none)."""
    raw = (table.schema.metadata or {}).get(RULE_KEY)
    return dict(json.loads(raw)) if raw else {}


class OffsetWells(TableContract):
    """One row per offset well: its tool model, hole size and where its first station is."""

    offset: str = column(unit=None, description="offset well id (the stations' survey id)")
    model: str = column(unit=None, description="tool model of its survey")
    hole_diameter: float = column(unit="m", gt=0, description="hole or casing diameter")
    north: float = column(
        unit="m",
        description="its slot's north from the reference wellhead, in the reference's north; "
        "its first station lies there plus the tie_north its stations file lists",
    )
    east: float = column(
        unit="m",
        description="its slot's east from the reference wellhead, in the reference's north; "
        "its first station lies there plus the tie_east its stations file lists",
    )
    tvd: float | None = column(
        unit="m",
        description="first station's TVD below the reference's depth datum (null: the TVD its "
        "stations file lists there, else its MD)",
        default=None,
    )
    tie_tvd: float | None = column(
        unit="m",
        description="TVD its stations file lists at its first station (null: it lists not "
        "TVD, north and east there)",
        default=None,
    )
    tie_north: float | None = column(
        unit="m",
        description="north its stations file lists at its first station, from its own "
        "wellhead, referred to true north with its azimuths (null: none listed)",
        default=None,
    )
    tie_east: float | None = column(
        unit="m",
        description="east its stations file lists at its first station, from its own "
        "wellhead, referred to true north with its azimuths (null: none listed)",
        default=None,
    )
    parent: str | None = column(
        unit=None,
        description="the wellbore it was kicked off from ('reference': the reference well; "
        "null: none named, a common section detected when its first station lies on the "
        "reference path)",
        default=None,
    )
    kickoff_md: float | None = column(
        unit="m", description="MD of its kick-off on the reference (null: detected)", default=None
    )
    source: str | None = column(unit=None, description="the stations file", default=None)
    sha256: str | None = column(unit=None, description="SHA-256 of the stations file", default=None)
    reference_convergence: float | None = column(
        unit="deg",
        description="the reference well's grid convergence its grid-north azimuths were "
        "referred to true north by, its own not stated: the same grid assumed (null: its own)",
        default=None,
    )


class Clearance(TableContract):
    """Per offset well (a contiguous block) and reference station: the closest point of the
    offset well, the centre-to-centre distance, the combined σ along it and the ISCWSA
    separation factor, the least one along the course below and the level. A sidetrack's
    rows start at its common point with the reference."""

    group_by = "offset"

    offset: str = column(unit=None, description="offset well id")
    md: float = column(unit="m", monotonic="strict", description="reference station MD")
    offset_md: float = column(unit="m", description="MD of the closest point on the offset well")
    distance: float = column(unit="m", ge=0, description="centre-to-centre distance")
    sigma_s: float = column(
        unit="m",
        ge=0,
        finite=False,
        description="1σ of both wells' position errors along the centre-to-centre line "
        "(where the centres coincide: the largest σ over directions; NaN where a well's σ is "
        "flagged outside its model's range)",
    )
    sf: float = column(
        unit=None,
        finite=False,
        description="ISCWSA separation factor at the station (negative: the holes and margin "
        "overlap; NaN where σ_S is NaN)",
    )
    sf_between: float = column(
        unit=None,
        finite=False,
        description="least separation factor along the reference course from this station to "
        "the next, both ends included (the last station: its own)",
    )
    md_between: float = column(unit="m", description="reference MD of that least SF")
    level: str = column(
        unit=None,
        description="pass, warn or fail by the separation rule, decided on sf_between "
        "(level_on: course, the default) or on sf (level_on: station)",
    )
    toolface: float = column(
        unit="deg",
        ge=0,
        lt=360,
        finite=False,
        description="direction of the offset in the plane normal to the reference, clockwise "
        "from its high side (travelling cylinder; NaN where the centres coincide)",
    )
    outside_validity: bool = column(
        unit=None,
        default=False,
        description="the reference station or the offset's closest point is beyond a station "
        "outside its tool model's range: σ_S and SF NaN, level fail (outside_validity: flag)",
    )

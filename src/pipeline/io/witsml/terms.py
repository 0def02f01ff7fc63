"""WITSML 1.4.1.1 vocabulary shared by the trajectory writer and reader: namespace, units of
measure, north references, calculation methods and survey tool types.

Values of the extensible enumerations (``typeSurveyTool``, ``calcAlgorithm``) are the ones
the WITSML data schema documents; ``typeTrajStation`` and ``aziRef`` are closed enumerations.
"""

from __future__ import annotations

import re
from typing import Final

from pipeline.errors import UnitError
from pipeline.survey.methods import Method
from pipeline.tables import DLS_COURSE_M
from pipeline.units import conversion_factor
from pipeline.well import NorthReference

NS: Final = "http://www.witsml.org/schemas/1series"
VERSION: Final = "1.4.1.1"
EXTENSION_PREFIX: Final = "gyropipe.well."
"""``commonData/extensionNameValue`` names holding the well metadata WITSML has no element for."""
COVARIANCE: tuple[tuple[str, str, str], ...] = (
    ("cov_nn", "varianceNN", "m2"),
    ("cov_ne", "varianceNE", "m2"),
    ("cov_nv", "varianceNVert", "m2"),
    ("cov_ee", "varianceEE", "m2"),
    ("cov_ev", "varianceEVert", "m2"),
    ("cov_vv", "varianceVertVert", "m2"),
)
"""Position covariance columns (NEV, vertical down) and their ``matrixCov`` elements."""
ERROR_MODEL_EXTENSION = "gyropipe.error_model"
"""Name of the extension value stating the error model of the matrixCov covariances."""
TIE_ON_EXTENSION = "gyropipe.uncertainty_tie_on"
"""Name of the extension value stating where a trajectory's matrixCov starts: its tie-on and
whether the tie-on's own uncertainty is in it (:class:`~pipeline.uncertainty.tieon.TieOn`,
JSON)."""

NAME_MAX = 64
"""Longest name and uid (WITSML ``nameString``, ``uidString``)."""
TYPE_MAX = 40
"""Longest value of an extensible enumeration (WITSML ``abstractTypeEnum``)."""

AZI_REF: dict[NorthReference, str] = {
    "true": "true north",
    "grid": "grid north",
    "magnetic": "magnetic north",
}
"""North reference → ``aziRef``."""

CALC_ALGORITHM: dict[Method, str] = {
    "minimum_curvature": "minimum curvature",
    "tangential": "tangential",
    "balanced_tangential": "balanced tangential",
    "average_angle": "average angle",
    "radius_of_curvature": "radius of curvature",
}
"""Survey calculation method → ``calcAlgorithm``."""

SURVEY_TOOLS: dict[str, str] = {
    "gyroscopic north seeking": "gyro north seeking",
    "gyroscopic inertial": "gyro inertial",
    "gyroscopic MWD": "gyro MWD",
    "magnetic MWD": "magnetic MWD",
    "magnetic single-shot": "magnetic single shot",
    "magnetic multiple-shot": "magnetic multi-shot",
    "unknown": "unknown",
}
"""``typeSurveyTool`` → the ``typeTrajStation`` of the stations it measures."""
TIE_IN = "tie in point"
SURVEY_STATION_TYPES = frozenset({*SURVEY_TOOLS.values(), TIE_IN})
"""``typeTrajStation`` values of a survey's stations: a tool's measurement, the tie-in point
(a known position the survey starts from), ``unknown``."""
MARKER_TYPES = frozenset(
    {"casing MD", "casing TVD", "formation MD", "formation TVD", "marker MD", "marker TVD"}
)
"""``typeTrajStation`` values of a point at a named depth, inserted among a survey's
stations (interpolated between them, not measured)."""
TARGET_TYPES = frozenset({"target center", "target offset"})
"""``typeTrajStation`` values of a target's position."""
PLAN_SECTION_TYPES = frozenset(
    {
        "azimuth on plane",
        "buildrate to delta-MD",
        "buildrate to INCL",
        "buildrate to MD",
        "buildrate and turnrate to AZI",
        "buildrate and turnrate to delta-MD",
        "buildrate and turnrate to INCL",
        "buildrate and turnrate to INCL and AZI",
        "buildrate and turnrate to MD",
        "buildrate and turnrate to TVD",
        "buildrate TVD",
        "DLS",
        "DLS to AZI and MD",
        "DLS to AZI-TVD",
        "DLS to INCL",
        "DLS to INCL and AZI",
        "DLS to INCL and MD",
        "DLS to INCL and TVD",
        "DLS to NS, EW and TVD",
        "DLS and toolface to AZI",
        "DLS and toolface to delta-MD",
        "DLS and toolface to INCL",
        "DLS and toolface to INCL-AZI",
        "DLS and toolface to MD",
        "DLS and toolface to TVD",
        "hold to delta-MD",
        "hold to MD",
        "hold to TVD",
        "INCL, AZI and TVD",
        "NS, EW and TVD",
        "turnrate to AZI",
        "turnrate to delta-MD",
        "turnrate to MD",
        "turnrate to TVD",
    }
)
"""``typeTrajStation`` values of the end of a plan's section (a build, a hold, a turn… to a
depth or an angle): the rest of the closed enumeration."""
NOT_MEASURED_2 = {
    "MD and INCL": "an inclination-only survey (a drift indicator's): no azimuth",
    "interpolated": "interpolated between stations",
    "INCL AZI and TVD": "a point of a computed trajectory",
    "N E and TVD": "a point of a computed trajectory",
    "NS EW and TVD": "a point of a computed trajectory",
}
"""``TypeTrajStation`` values WITSML 2.0 added, of no measured direction, and what they
name (its ``MD INCL and AZI``, a normal survey station, is read as its tool's station type:
:mod:`pipeline.io.witsml.v2`)."""
STATION_TYPES = SURVEY_STATION_TYPES | MARKER_TYPES | TARGET_TYPES
"""``typeTrajStation`` values a station read from a file keeps when written (the measured
and marker kinds of the closed enumeration)."""
STATION_STATUS = frozenset({"open", "rejected", "position", "unknown"})
"""``statusTrajStation`` (closed): ``open`` not yet validated, ``rejected`` of a quality not
ok — by the schema neither enters the positions of the stations below it —, ``position``
validated and used."""
ITEM_STATES = frozenset({"actual", "model", "plan", "unknown"})
"""``commonData/itemState`` (closed): ``actual`` measured or entered at the well site, ``plan``
to be executed in the future, ``model`` for what-if calculations."""

UNIT_UOM = {"m": "m", "deg": "dega", "deg/30m": "dega/30m", "m2": "m2"}
"""Canonical column unit → WITSML uom (what the writer writes)."""
_UOM_SPELLING = {
    "m": "m",
    "ft": "ft",
    "ftUS": "usft",
    "dega": "deg",
    "rad": "rad",
    "m2": "m2",
    "ft2": "ft2",
}
"""WITSML uom → the spelling :mod:`pipeline.units` reads (what the reader accepts)."""
_RATE_UOM = re.compile(r"(dega|rad)/([0-9]*)(m|ft|ftUS)")
_TOOL_WORDS = (
    (("gyro", "north seeking"), "gyroscopic north seeking"),
    (("gyro", "northseeking"), "gyroscopic north seeking"),
    (("gyrocompass",), "gyroscopic north seeking"),
    (("gyro", "inertial"), "gyroscopic inertial"),
    (("gyro", "mwd"), "gyroscopic MWD"),
    (("mwd",), "magnetic MWD"),
    (("single shot",), "magnetic single-shot"),
    (("multi shot",), "magnetic multiple-shot"),
    (("multishot",), "magnetic multiple-shot"),
    (("multiple shot",), "magnetic multiple-shot"),
)
"""Words of a free-text tool type (all present) → ``typeSurveyTool``, first match wins."""


def survey_tool(tool_type: str | None) -> str:
    """The ``typeSurveyTool`` a free-text tool type names ('unknown' when it names none:
    a bare 'gyro' may be north-seeking, inertial or MWD)."""
    if tool_type is None:
        return "unknown"
    text = " ".join(tool_type.casefold().replace("-", " ").replace("_", " ").split())
    for value in SURVEY_TOOLS:
        if text == value.casefold().replace("-", " "):
            return value
    for words, value in _TOOL_WORDS:
        if all(word in text for word in words):
            return value
    return "unknown"


def uom_factor(uom: str, quantity: str) -> float:
    """Multiplier taking values in the WITSML ``uom`` to the canonical unit of ``quantity``
    (``length``, ``angle``, ``dogleg_severity`` or ``area``). Raises :class:`UnitError`."""
    if quantity == "dogleg_severity":
        match = _RATE_UOM.fullmatch(uom)
        if match is None:
            raise UnitError(f"uom {uom!r} is not an angle per length WITSML writes for a DLS")
        angle = conversion_factor(_UOM_SPELLING[match[1]], "angle")
        length = conversion_factor(_UOM_SPELLING[match[3]], "length") * float(match[2] or 1)
        return angle / length * DLS_COURSE_M
    spelling = _UOM_SPELLING.get(uom)
    if spelling is None:
        raise UnitError(
            f"uom {uom!r} is not supported for {quantity} (supported: "
            f"{', '.join(k for k in _UOM_SPELLING if _is(k, quantity))})"
        )
    return conversion_factor(spelling, quantity)


def _is(uom: str, quantity: str) -> bool:
    try:
        conversion_factor(_UOM_SPELLING[uom], quantity)
    except UnitError:
        return False
    return True

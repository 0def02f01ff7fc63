"""WITSML 1.4.1.1 ``trajectory`` writer: one ``<trajectory>`` per survey of a stations or
trajectory table (layout in :mod:`pipeline.io.witsml`)."""

from __future__ import annotations

import itertools
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pyarrow as pa

from pipeline.contracts import NORTH_KEY, UNIT_KEY, VERTICAL_TOLERANCE
from pipeline.errors import EmptyTableError
from pipeline.io.witsml.terms import (
    AZI_REF,
    CALC_ALGORITHM,
    EXTENSION_PREFIX,
    NAME_MAX,
    NS,
    STATION_TYPES,
    SURVEY_TOOLS,
    TIE_IN,
    UNIT_UOM,
    VERSION,
    survey_tool,
)
from pipeline.survey.calculation import calculation_of
from pipeline.survey.stations import survey_offsets
from pipeline.tables import STATION_TEXT_COLUMNS
from pipeline.version import __version__
from pipeline.well import NorthReference, WellMetadata

STATION_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("md", "md", "m"),
    ("tvd", "tvd", "m"),
    ("inc", "incl", "deg"),
    ("azi", "azi", "deg"),
    ("north", "dispNs", "m"),
    ("east", "dispEw", "m"),
    ("vertical_section", "vertSect", "m"),
    ("dls", "dls", "deg/30m"),
    ("turn", "rateTurn", "deg/30m"),
    ("build", "rateBuild", "deg/30m"),
)
"""Column, ``trajectoryStation`` element and the column's required unit, in schema order."""
COVARIANCE: tuple[tuple[str, str, str], ...] = (
    ("cov_nn", "varianceNN", "m2"),
    ("cov_ne", "varianceNE", "m2"),
    ("cov_nv", "varianceNVert", "m2"),
    ("cov_ee", "varianceEE", "m2"),
    ("cov_ev", "varianceEVert", "m2"),
    ("cov_vv", "varianceVertVert", "m2"),
)
"""Position covariance columns (NEV, vertical down) and their ``matrixCov`` elements."""
REQUIRED = ("md", "inc", "azi")
UNNAMED = "unnamed"
"""``nameWell`` (and uid) when the header names no well: WITSML requires one."""
WELL_UOM = {
    "latitude": "dega",
    "longitude": "dega",
    "elevation": "m",
    "declination": "dega",
    "grid_convergence": "dega",
    "declination_applied": "dega",
    "grid_convergence_applied": "dega",
}
"""Units of the numeric well metadata fields written as extension values."""
_XML_CHARS = re.compile("[^\t\n\r\x20-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")


def write_witsml(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write ``table`` (md, inc, azi and any of the trajectory columns) as a WITSML 1.4.1.1
    ``trajectorys`` document; raises ``ValueError`` for what WITSML cannot hold (a
    trajectory without stations among it)."""
    if table.num_rows == 0:
        raise EmptyTableError("trajectory", "a WITSML trajectory needs at least one station")
    values = _station_values(table)
    north = _north(table)
    well_name = _name(well.well or UNNAMED, "well name")
    wellbore_name = _name(well.wellbore or well_name, "wellbore name")
    tool = survey_tool(well.tool_type)
    tools, kinds = (_texts(table, name) for name in STATION_TEXT_COLUMNS)
    calculation = calculation_of(table)
    root = ET.Element("trajectorys", {"xmlns": NS, "version": VERSION})
    labels = table.column("survey").to_pylist() if "survey" in table.column_names else None
    for lo, hi in itertools.pairwise(survey_offsets(table).tolist()):
        label = str(labels[lo] or "") if labels else ""
        name = _name(label or _default_name(well), "survey id")
        traj = _sub(
            root,
            "trajectory",
            uidWell=_uid(well.uwi or well_name),
            uidWellbore=_uid(wellbore_name),
            uid=_uid(name),
        )
        _sub(traj, "nameWell", well_name)
        _sub(traj, "nameWellbore", wellbore_name)
        _sub(traj, "name", name)
        if well.survey_date is not None:
            _sub(traj, "dTimTrajStart", f"{well.survey_date.isoformat()}T00:00:00Z")
        _measure(traj, "mdMn", values["md"][lo], "m")
        _measure(traj, "mdMx", values["md"][hi - 1], "m")
        if well.service_company:
            _sub(traj, "serviceCompany", _name(well.service_company, "service company"))
        if well.declination_applied is not None:
            _measure(traj, "magDeclUsed", well.declination_applied, "dega")
        if well.grid_convergence_applied is not None:
            _measure(traj, "gridCorUsed", well.grid_convergence_applied, "dega")
        if calculation is not None and "vertical_section" in values:
            _measure(traj, "aziVertSect", calculation.vs_azimuth, "dega")
            _measure(traj, "dispNsVertSectOrig", 0.0, "m")
            _measure(traj, "dispEwVertSectOrig", 0.0, "m")
        _sub(traj, "aziRef", AZI_REF[north])
        algorithm = CALC_ALGORITHM[calculation.method] if calculation is not None else None
        for row in range(lo, hi):
            station = _sub(traj, "trajectoryStation", uid=f"stn-{row - lo + 1}")
            own = survey_tool(tools[row]) if tools[row] is not None else tool
            kind = TIE_IN if row == lo else SURVEY_TOOLS[own]
            _sub(station, "typeTrajStation", kinds[row] if kinds[row] in STATION_TYPES else kind)
            _sub(station, "typeSurveyTool", own)
            if algorithm is not None:
                _sub(station, "calcAlgorithm", algorithm)
            for column, element, unit in STATION_COLUMNS:
                if column in values and np.isfinite(values[column][row]):
                    _measure(station, element, values[column][row], UNIT_UOM[unit])
            if all(c in values and np.isfinite(values[c][row]) for c, _, _ in COVARIANCE):
                matrix = _sub(station, "matrixCov")
                for column, element, unit in COVARIANCE:
                    _measure(matrix, element, values[column][row], UNIT_UOM[unit])
        _common_data(traj, well)
    ET.indent(root)
    with path.open("wb") as fh:
        ET.ElementTree(root).write(fh, encoding="UTF-8", xml_declaration=True)
        fh.write(b"\n")


def _station_values(table: pa.Table) -> dict[str, np.ndarray]:
    """The written columns as float arrays (NaN where null), units checked."""
    missing = [c for c in REQUIRED if c not in table.column_names]
    if missing:
        raise ValueError(f"WITSML trajectory stations need columns {missing}")
    values: dict[str, np.ndarray] = {}
    for column, element, unit in (*STATION_COLUMNS, *COVARIANCE):
        if column not in table.column_names:
            continue
        found = (table.schema.field(column).metadata or {}).get(UNIT_KEY, b"").decode()
        if found != unit:
            raise ValueError(
                f"column {column!r} is in {found or 'no unit'!r}: WITSML {element} is "
                f"written from {unit!r}"
            )
        array = table.column(column).to_numpy(zero_copy_only=False)
        values[column] = np.asarray(array, dtype=np.float64)
    for column in REQUIRED:
        bad = ~np.isfinite(values[column])
        if column == "azi":  # undefined at vertical: the station is written without <azi>
            inc = values["inc"]
            bad &= ~(
                np.isnan(values[column]) & (np.minimum(inc, 180.0 - inc) <= VERTICAL_TOLERANCE)
            )
        bad = np.flatnonzero(bad)
        if bad.size:
            raise ValueError(f"column {column!r} row {int(bad[0])}: missing or not finite")
    return values


def _texts(table: pa.Table, name: str) -> list[str | None]:
    """A per-station text column's values (None where absent)."""
    if name not in table.column_names:
        return [None] * table.num_rows
    return [str(v) if v is not None else None for v in table.column(name).to_pylist()]


def _north(table: pa.Table) -> NorthReference:
    raw = (table.schema.field("azi").metadata or {}).get(NORTH_KEY, b"").decode()
    for ref in AZI_REF:
        if raw == ref:
            return ref
    raise ValueError("column 'azi' states no north reference: WITSML aziRef needs one")


def _default_name(well: WellMetadata) -> str:
    return "survey" + (f" {well.survey_date.isoformat()}" if well.survey_date else "")


def _name(text: str | None, what: str) -> str:
    """``text`` as a WITSML name: whitespace collapsed, 1 to 64 XML characters."""
    collapsed = " ".join((text or "").split())
    if not collapsed:
        raise ValueError(f"WITSML needs a {what}, got {text!r}")
    return _checked(collapsed, what, NAME_MAX)


def _uid(name: str) -> str:
    """A uid (no spaces, at most 64 characters) from a name."""
    return _checked(name.replace(" ", "_"), "uid", NAME_MAX)


def _checked(text: str, what: str, longest: int | None) -> str:
    if longest is not None and len(text) > longest:
        raise ValueError(f"{what} {text!r} is longer than the {longest} characters WITSML allows")
    bad = _XML_CHARS.search(text)
    if bad:
        raise ValueError(f"{what} {text!r} holds {bad[0]!r}, which XML cannot")
    return text


def _sub(parent: ET.Element, tag: str, text: str | None = None, **attrs: str) -> ET.Element:
    element = ET.SubElement(parent, tag, attrs)
    element.text = text
    return element


def _measure(parent: ET.Element, tag: str, value: float, uom: str) -> None:
    _sub(parent, tag, repr(float(value)), uom=uom)


def _common_data(traj: ET.Element, well: WellMetadata) -> None:
    """Provenance comment and every set well metadata field as an extension value."""
    common = _sub(traj, "commonData")
    comment = (
        f"Written by gyropipe {__version__}. dispNs/dispEw from the wellhead; tvd "
        f"below the depth reference ({well.depth_reference or 'not stated'}); matrixCov: "
        "position covariance north-east-vertical (vertical down), 1 sigma squared."
    )
    _sub(common, "comments", _checked(comment, "depth reference", None))
    for field, value in well.model_dump(exclude_none=True).items():
        if not str(value).strip():
            continue  # WITSML values are never empty
        entry = _sub(common, "extensionNameValue", uid=f"well.{field}")
        _sub(entry, "name", EXTENSION_PREFIX + field)
        if field in WELL_UOM:
            _measure(entry, "value", value, WELL_UOM[field])
            kind = "double"
        else:
            _sub(entry, "value", _checked(str(value), f"well {field}", None))
            kind = "date" if field == "survey_date" else "string"
        _sub(entry, "dataType", kind)

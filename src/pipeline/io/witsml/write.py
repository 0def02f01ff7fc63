"""WITSML 1.4.1.1 ``trajectory`` writer: one ``<trajectory>`` per survey of a stations or
trajectory table (layout in :mod:`pipeline.io.witsml`)."""

from __future__ import annotations

import itertools
import re
from pathlib import Path

import numpy as np
import pyarrow as pa

from pipeline.contracts import NORTH_KEY, UNIT_KEY, VERTICAL_TOLERANCE
from pipeline.errors import EmptyTableError
from pipeline.io.limits import TEXT_MAX
from pipeline.io.nulls import refuse_null_markers
from pipeline.io.witsml.terms import (
    AZI_REF,
    CALC_ALGORITHM,
    COVARIANCE,
    ERROR_MODEL_EXTENSION,
    EXTENSION_PREFIX,
    NAME_MAX,
    NS,
    STATION_TYPES,
    SURVEY_TOOLS,
    TIE_IN,
    TIE_ON_EXTENSION,
    UNIT_UOM,
    VERSION,
    survey_tool,
)
from pipeline.survey.calculation import calculation_of
from pipeline.survey.stations import survey_offsets
from pipeline.tables import STATION_TEXT_COLUMNS
from pipeline.uncertainty.stated import file_statements
from pipeline.uncertainty.tieon import TieOn, tie_on_of
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
    trajectory without stations among it) or a reader would not read back (a value that is
    a null marker, :func:`~pipeline.io.nulls.refuse_null_markers`)."""
    if table.num_rows == 0:
        raise EmptyTableError("trajectory", "a WITSML trajectory needs at least one station")
    values = _station_values(table)
    refuse_null_markers({column: pa.array(array) for column, array in values.items()})
    texts = {column: _numbers(array) for column, array in values.items()}
    north = _north(table)
    well_name = _name(well.well or UNNAMED, "well name")
    wellbore_name = _name(well.wellbore or well_name, "wellbore name")
    tool = survey_tool(well.tool_type)
    tools, kinds = (_texts(table, name) for name in STATION_TEXT_COLUMNS)
    calculation = calculation_of(table)
    doc = _Document()
    doc.open("trajectorys", xmlns=NS, version=VERSION)
    labels = table.column("survey").to_pylist() if "survey" in table.column_names else None
    depth = 3  # trajectorys > trajectory > trajectoryStation > the station's numbers
    numbers = _rows(
        [
            _number_lines(texts[c], e, UNIT_UOM[u], depth)
            for c, e, u in STATION_COLUMNS
            if c in texts
        ]
    )
    full_covariance = [False] * table.num_rows
    model = None
    offsets = survey_offsets(table).tolist()
    ties: list[TieOn | None] = [None] * (len(offsets) - 1)
    if all(c in texts for c, _, _ in COVARIANCE):
        record = tie_on_of(table)
        if record is not None and len(record.surveys) == len(ties):
            ties = list(record.surveys)
        stated = file_statements(pa.schema([table.schema.field(c) for c, _, _ in COVARIANCE]))
        model = stated.get("error_model")
        covariance = _rows(
            [_number_lines(texts[c], e, UNIT_UOM[u], depth + 1) for c, e, u in COVARIANCE]
        )
        full_covariance = np.logical_and.reduce(
            [np.isfinite(values[c]) for c, _, _ in COVARIANCE]
        ).tolist()
    for (lo, hi), tie in zip(itertools.pairwise(offsets), ties, strict=True):
        label = str(labels[lo] or "") if labels else ""
        name = _name(label or _default_name(well), "survey id")
        doc.open(
            "trajectory",
            uidWell=_uid(well.uwi or well_name),
            uidWellbore=_uid(wellbore_name),
            uid=_uid(name),
        )
        doc.leaf("nameWell", well_name)
        doc.leaf("nameWellbore", wellbore_name)
        doc.leaf("name", name)
        if well.survey_date is not None and well.survey_date_last is None:
            doc.leaf("dTimTrajStart", f"{well.survey_date.isoformat()}T00:00:00Z")
        doc.leaf("mdMn", texts["md"][lo], uom="m")
        doc.leaf("mdMx", texts["md"][hi - 1], uom="m")
        if well.service_company:
            doc.leaf("serviceCompany", _name(well.service_company, "service company"))
        if well.declination_applied is not None:
            doc.leaf("magDeclUsed", _number(well.declination_applied), uom="dega")
        if well.grid_convergence_applied is not None:
            doc.leaf("gridCorUsed", _number(well.grid_convergence_applied), uom="dega")
        if calculation is not None and "vertical_section" in values:
            doc.leaf("aziVertSect", _number(calculation.vs_azimuth), uom="dega")
            doc.leaf("dispNsVertSectOrig", _number(0.0), uom="m")
            doc.leaf("dispEwVertSectOrig", _number(0.0), uom="m")
        doc.leaf("aziRef", AZI_REF[north])
        algorithm = CALC_ALGORITHM[calculation.method] if calculation is not None else None
        for row in range(lo, hi):
            doc.open("trajectoryStation", uid=f"stn-{row - lo + 1}")
            own = survey_tool(tools[row]) if tools[row] is not None else tool
            kind = TIE_IN if row == lo else SURVEY_TOOLS[own]
            doc.leaf("typeTrajStation", kinds[row] if kinds[row] in STATION_TYPES else kind)
            doc.leaf("typeSurveyTool", own)
            if algorithm is not None:
                doc.leaf("calcAlgorithm", algorithm)
            doc.written(numbers[row])
            if full_covariance[row]:
                doc.open("matrixCov")
                doc.written(covariance[row])
                doc.close()
            doc.close()
        _common_data(doc, well, model, tie)
        doc.close()
    doc.close()
    with path.open("wb") as fh:
        fh.write(doc.text().encode())


def _station_values(table: pa.Table) -> dict[str, np.ndarray]:
    """The written columns as float arrays (NaN where null), units checked."""
    names = set(table.column_names)  # (built afresh on each access: once here)
    missing = [c for c in REQUIRED if c not in names]
    if missing:
        raise ValueError(f"WITSML trajectory stations need columns {missing}")
    schema = table.schema
    values: dict[str, np.ndarray] = {}
    for column, element, unit in (*STATION_COLUMNS, *COVARIANCE):
        if column not in names:
            continue
        found = (schema.field(column).metadata or {}).get(UNIT_KEY, b"").decode()
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


def _checked(text: str, what: str, longest: int = TEXT_MAX) -> str:
    """``text`` if XML holds it in at most ``longest`` characters (a name's, else any text's
    gyropipe reads back), else a ValueError."""
    if len(text) > longest:
        whose = "WITSML allows" if longest == NAME_MAX else "gyropipe reads back from WITSML"
        raise ValueError(f"{what} {text!r} is longer than the {longest:,} characters {whose}")
    bad = _XML_CHARS.search(text)
    if bad:
        raise ValueError(f"{what} {text!r} holds {bad[0]!r}, which XML cannot")
    return text


def _number(value: float) -> str:
    """A number in shortest round-trip form."""
    return repr(float(value))


def _numbers(array: np.ndarray) -> list[str | None]:
    """Each value of a float column in shortest round-trip form (None where not finite)."""
    finite = np.isfinite(array).tolist()
    return [repr(v) if ok else None for v, ok in zip(array.tolist(), finite, strict=True)]


def _number_lines(texts: list[str | None], tag: str, uom: str, depth: int) -> list[str]:
    """Each number of a column (:func:`_numbers`) as its element's line at ``depth`` (empty
    where there is none), as :meth:`_Document.leaf` writes it: a number's shortest
    round-trip form (digits, ``.``, ``-``, ``e``, ``+``) holds nothing XML escapes."""
    start = f"{'  ' * depth}<{tag}{_attributes({'uom': uom})}>"
    end = f"</{tag}>\n"
    return ["" if text is None else start + text + end for text in texts]


def _rows(columns: list[list[str]]) -> list[str]:
    """The lines of each row, joined (columns of :func:`_number_lines`)."""
    return ["".join(lines) for lines in zip(*columns, strict=True)]


class _Document:
    """An XML document written as text, as ElementTree serialises it after ``ET.indent``
    (two spaces per level, ``<tag />`` when empty, text and attribute values escaped)."""

    def __init__(self) -> None:
        self._parts = ["<?xml version='1.0' encoding='UTF-8'?>\n"]
        self._open: list[tuple[str, int]] = []
        """the open elements: tag, index of the start tag in ``_parts``"""

    def open(self, tag: str, **attrs: str) -> None:
        """Start an element that holds elements."""
        self._open.append((tag, len(self._parts)))
        self._parts.append(f"{'  ' * (len(self._open) - 1)}<{tag}{_attributes(attrs)}>\n")

    def close(self) -> None:
        """End the innermost open element."""
        tag, at = self._open.pop()
        if at == len(self._parts) - 1:  # it holds nothing
            self._parts[at] = self._parts[at][:-2] + " />\n"
        else:
            self._parts.append(f"{'  ' * len(self._open)}</{tag}>\n")

    def leaf(self, tag: str, text: str | None, **attrs: str) -> None:
        """An element holding ``text`` alone."""
        start = f"{'  ' * len(self._open)}<{tag}{_attributes(attrs)}"
        if not text:
            self._parts.append(f"{start} />\n")
        else:
            self._parts.append(f"{start}>{_escape(text)}</{tag}>\n")

    def written(self, text: str) -> None:
        """Elements already written as text (whole lines at the current depth), if any."""
        if text:
            self._parts.append(text)

    def text(self) -> str:
        """The document, every element closed."""
        if self._open:
            raise RuntimeError(f"element {self._open[-1][0]!r} is not closed")
        return "".join(self._parts)


_TEXT_ESCAPES = {ord("&"): "&amp;", ord("<"): "&lt;", ord(">"): "&gt;"}
_ATTRIBUTE_ESCAPES = _TEXT_ESCAPES | {
    ord('"'): "&quot;",
    ord("\r"): "&#13;",
    ord("\n"): "&#10;",
    ord("\t"): "&#09;",
}


def _escape(text: str) -> str:
    return text.translate(_TEXT_ESCAPES)


def _attributes(attrs: dict[str, str]) -> str:
    if not attrs:  # most elements (not a generator and a join each)
        return ""
    return "".join(f' {k}="{v.translate(_ATTRIBUTE_ESCAPES)}"' for k, v in attrs.items())


def _common_data(doc: _Document, well: WellMetadata, model: str | None, tie: TieOn | None) -> None:
    """Provenance comment, the error model of the covariances (``model``: None when not
    stated), where they start (``tie``, the trajectory's tie-on: None when not recorded) and
    every set well metadata field as an extension value."""
    doc.open("commonData")
    comment = (
        f"Written by gyropipe {__version__}. dispNs/dispEw from the wellhead; tvd "
        f"below the depth reference ({well.depth_reference or 'not stated'}); matrixCov: "
        "position covariance north-east-vertical (vertical down), 1 sigma squared"
        + (f", error model {model}." if model else ".")
    )
    doc.leaf("comments", _checked(comment, "depth reference or error model"))
    if model:
        doc.open("extensionNameValue", uid="error_model")
        doc.leaf("name", ERROR_MODEL_EXTENSION)
        doc.leaf("value", _checked(model, "error model"))
        doc.leaf("dataType", "string")
        doc.close()
    if tie is not None:
        doc.open("extensionNameValue", uid="uncertainty_tie_on")
        doc.leaf("name", TIE_ON_EXTENSION)
        doc.leaf("value", _checked(tie.model_dump_json(), "tie-on survey name"))
        doc.leaf("dataType", "string")
        doc.close()
    for field, value in well.model_dump(exclude_none=True).items():
        if not str(value).strip():
            continue  # WITSML values are never empty
        doc.open("extensionNameValue", uid=f"well.{field}")
        doc.leaf("name", EXTENSION_PREFIX + field)
        if field in WELL_UOM:
            doc.leaf("value", _number(value), uom=WELL_UOM[field])
            kind = "double"
        else:
            doc.leaf("value", _checked(str(value), f"well {field}"))
            kind = "date" if field in ("survey_date", "survey_date_last") else "string"
        doc.leaf("dataType", kind)
        doc.close()
    doc.close()

"""WITSML 1.4.1.x ``trajectory`` reader (kind ``stations``; layout in :mod:`pipeline.io.witsml`;
the document parsed by :mod:`pipeline.io.witsml.tree`; a WITSML 2.0 ``Trajectory`` read as
its 1.4.1.1 tree, :mod:`pipeline.io.witsml.v2`)."""

from __future__ import annotations

import datetime as dt
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from pipeline.contracts import SOURCE_LINE, VERTICAL_TOLERANCE
from pipeline.errors import InputFileError, UnitError, warn_input, warn_rows
from pipeline.io.csv import LAYOUTS
from pipeline.io.nulls import is_null_marker
from pipeline.io.numbers import file_number
from pipeline.io.sniffing import file_head
from pipeline.io.uncertainty_columns import Stated, stating, tie_on_record
from pipeline.io.witsml.kinds import check_tie_in, check_trajectory, left_out
from pipeline.io.witsml.terms import (
    AZI_REF,
    COVARIANCE,
    ERROR_MODEL_EXTENSION,
    EXTENSION_PREFIX,
    NS,
    TIE_ON_EXTENSION,
    survey_tool,
    uom_factor,
)
from pipeline.io.witsml.tree import Node, RepeatedElement, parse
from pipeline.io.witsml.v2 import NS_2, as_1series
from pipeline.plausibility import AngleUnitConfirmed, NullStations, SurveyStations
from pipeline.uncertainty.tieon import TieOn, TieOnRecord
from pipeline.well import (
    DATUM_WORDS,
    DefaultNorthReference,
    NorthReference,
    WellMetadata,
    contradicts_north,
)

SNIFF_BYTES = 4096
STATION_MEASURES = (
    ("md", "md", "length", True),
    ("inc", "incl", "angle", True),
    ("azi", "azi", "angle", True),
    ("tvd", "tvd", "length", False),
    ("north", "dispNs", "length", False),
    ("east", "dispEw", "length", False),
    ("dls", "dls", "dogleg_severity", False),
)
"""Column, ``trajectoryStation`` element, quantity, required."""
WELL_ELEMENTS = (
    ("service_company", "serviceCompany", None),
    ("declination_applied", "magDeclUsed", "angle"),
    ("grid_convergence_applied", "gridCorUsed", "angle"),
    ("grid_convergence_applied", "gridConUsed", "angle"),
)
"""Well metadata field, ``trajectory`` element holding it, quantity of a measure. The
corrections ``…Used`` are what was applied to the azimuths, not the site's declination or
convergence (a gridCorUsed of 0 on true-north azimuths: no grid correction applied)."""
STATION_CORRECTIONS = {
    "stnMagDeclUsed": "declination_applied",
    "stnGridCorUsed": "grid_convergence_applied",
    "stnGridConUsed": "grid_convergence_applied",
}
"""``trajectoryStation/corUsed`` elements → the well metadata field they state per station."""
STATION_TEXT = (("tool_type", "typeSurveyTool"), ("station_type", "typeTrajStation"))
"""Text columns kept per station: column, ``trajectoryStation`` element."""
EXTENSION_QUANTITY = {
    "latitude": "angle",
    "longitude": "angle",
    "elevation": "length",
    "declination": "angle",
    "grid_convergence": "angle",
    "declination_applied": "angle",
    "grid_convergence_applied": "angle",
}
_NORTH = {text: ref for ref, text in AZI_REF.items()}
_ROOT = re.compile(rb"<(?:[A-Za-z_][\w.-]*:)?trajectorys[\s>/]")
_ROOT_2 = re.compile(rb"<(?:[A-Za-z_][\w.-]*:)?Trajectory[\s>/]")


class WitsmlOptions(BaseModel):
    """Options of the WITSML reader; files need none."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    trajectory: str | None = Field(
        None, description="uid or name of the one trajectory to read (default: all)"
    )
    north_reference: NorthReference | None = Field(
        None,
        description="north reference of the azimuths when aziRef is absent or 'unknown' "
        "(must agree with it otherwise)",
    )
    default_north_reference: DefaultNorthReference = None
    null_stations: NullStations = "error"
    stations: SurveyStations = "survey"
    angle_unit_confirmed: AngleUnitConfirmed = False


def sniff(path: Path) -> bool:
    """By content: the first 4 KiB open a ``trajectorys`` element of WITSML 1.x or a
    ``Trajectory`` of WITSML 2."""
    head = file_head(path, SNIFF_BYTES)
    if head is None:
        return False
    if _ROOT.search(head) and b"witsml.org/schemas/1series" in head:
        return True
    return bool(_ROOT_2.search(head)) and NS_2.encode() in head


def read_witsml(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
    """Stations (md, inc, azi; tvd, north, east, dls and the matrixCov covariances, stating
    their ``gyropipe.error_model``, when the file has them) of every
    trajectory of a WITSML 1.4.1.x ``trajectorys`` document, in canonical units, with a
    ``survey`` column when there are several, and the well metadata it holds."""
    if kind != "stations":
        raise ValueError(f"the witsml reader reads kind 'stations', not {kind!r}")
    opts: WitsmlOptions = options or WitsmlOptions()
    try:
        return _read(path, opts)
    except RepeatedElement as exc:
        raise InputFileError(path, str(exc), line=exc.line) from None


def _read(path: Path, opts: WitsmlOptions) -> tuple[pa.Table, WellMetadata]:
    """:func:`read_witsml`'s table and well metadata."""
    root = parse(path)
    if root.namespace == NS_2:
        root = as_1series(path, root)
    if root.name != "trajectorys" or root.namespace != NS:
        raise InputFileError(
            path,
            f"root element is <{root.name}> in namespace {root.namespace or 'none'!r}; "
            f"expected <trajectorys> in {NS!r} (WITSML 1.4.1.x) or <Trajectory> in {NS_2!r} "
            "(WITSML 2.0)",
            line=root.line,
        )
    version = root.attrs.get("version", "")
    if not version.startswith("1.4.1"):
        raise InputFileError(
            path, f"version {version!r}: this reader reads WITSML 1.4.1.x", line=root.line
        )
    trajectories = _chosen(path, root, opts.trajectory)
    north = _north(path, trajectories, opts)
    labels = _labels(trajectories) if len(trajectories) > 1 else None
    data: dict[str, list[Any]] = {name: [] for name, *_ in STATION_MEASURES}
    data.update({name: [] for name, *_ in COVARIANCE})
    data.update({name: [] for name, _ in STATION_TEXT})
    data[SOURCE_LINE] = []
    survey: list[str] = []
    datum: tuple[str, int] | None = None
    for index, traj in enumerate(trajectories):
        nodes = traj.all("trajectoryStation")
        if not nodes:
            raise InputFileError(path, "trajectory has no trajectoryStation", line=traj.line)
        others = [t.attrs.get("uid") or t.text_of("name") for t in trajectories if t is not traj]
        check_trajectory(path, traj, opts.stations, [o for o in others if o])
        reasons = [left_out(node) if opts.stations == "survey" else None for node in nodes]
        nodes, rows, dropped = _survey_stations(path, traj, nodes, reasons, opts)
        _tvd_of_md_datum(path, nodes, rows)
        datum = _md_datum(path, nodes, datum)
        rows.sort(key=lambda row: row["md"])
        check_tie_in(path, traj, rows[0])
        _md_range(path, traj, sorted(rows + dropped, key=lambda row: row["md"]), datum)
        for row in rows:
            for name in data:
                data[name].append(row.get(name))
        if labels is not None:
            survey += [labels[index]] * len(rows)
    columns: dict[str, Any] = {"survey": survey} if labels is not None else {}
    for name, _, _, required in STATION_MEASURES:
        if required:
            columns[name] = np.asarray(data[name], dtype=np.float64)
        elif any(v is not None for v in data[name]):
            columns[name] = data[name]
    if all(any(v is not None for v in data[name]) for name, *_ in COVARIANCE):
        columns.update({name: data[name] for name, *_ in COVARIANCE})
    for name, _ in STATION_TEXT:
        if any(v is not None for v in data[name]):
            columns[name] = pa.array(data[name], pa.string())
    columns[SOURCE_LINE] = pa.array(data[SOURCE_LINE], pa.int64())
    stated = _stated(path, trajectories, labels)
    table = stating(LAYOUTS["stations"].table(columns, north), stated)
    return table, _well(path, trajectories, north, datum)


def _stated(path: Path, trajectories: list[Node], labels: list[str] | None) -> Stated:
    """The error model of the trajectories' matrixCov (their ``gyropipe.error_model``
    extension values, in order; several: all, as one statement) and where each starts
    (``gyropipe.uncertainty_tie_on``, each trajectory's named by its survey id of
    ``labels``: recorded when every trajectory states it). A trajectory stating either
    twice with different values is an :class:`InputFileError` at the second."""
    models: list[str] = []
    ties: list[TieOn] = []
    for index, traj in enumerate(trajectories):
        common = traj.get("commonData")
        own: dict[str, tuple[str, int]] = {}
        for entry in common.all("extensionNameValue") if common is not None else []:
            name, value = entry.text_of("name"), entry.get("value") or entry
            if name not in (ERROR_MODEL_EXTENSION, TIE_ON_EXTENSION):
                continue
            text = value.text.strip()
            first = own.setdefault(name, (text, value.line))
            if first[0] != text:
                raise InputFileError(
                    path,
                    f"extension {name} is given twice in a trajectory with different values "
                    f"(also on line {first[1]}: {first[0]!r}); expected one",
                    line=value.line,
                )
        if (model := own.get(ERROR_MODEL_EXTENSION)) is not None:
            models.append(model[0])
        if (stated := own.get(TIE_ON_EXTENSION)) is not None:
            tie = tie_on_record(path, *stated, TieOn)
            survey = None if labels is None else labels[index]
            ties.append(tie.model_copy(update={"survey": survey}))
    return Stated(
        error_model=", ".join(dict.fromkeys(m for m in models if m)) or None,
        tie_on=TieOnRecord(surveys=tuple(ties)) if len(ties) == len(trajectories) else None,
    )


def _chosen(path: Path, root: Node, wanted: str | None) -> list[Node]:
    trajectories = root.all("trajectory")
    if not trajectories:
        raise InputFileError(path, "no <trajectory> element", line=root.line)
    if wanted is None:
        return trajectories
    found = [t for t in trajectories if wanted in (t.attrs.get("uid"), t.text_of("name"))]
    if not found:
        known = [t.attrs.get("uid") or t.text_of("name") for t in trajectories]
        raise InputFileError(path, f"no trajectory with uid or name {wanted!r} (found {known})")
    return found[:1]


def _labels(trajectories: list[Node]) -> list[str]:
    """Survey ids: the trajectories' names, or their uids when names repeat."""
    names = [t.text_of("name") for t in trajectories]
    for labels in (names, [t.attrs.get("uid") for t in trajectories]):
        if all(labels) and len(set(labels)) == len(labels):
            return [str(label) for label in labels]
    return [f"trajectory {i + 1}" for i in range(len(trajectories))]


def _north(path: Path, trajectories: list[Node], opts: WitsmlOptions) -> NorthReference:
    """The one north reference of the azimuths (aziRef, else the options'; a trajectory
    without one never takes another's)."""
    found: set[NorthReference] = set()
    unstated: Node | None = None
    for traj in trajectories:
        node = traj.get("aziRef")
        text = " ".join(node.text.split()) if node is not None else "unknown"
        if text == "unknown":
            unstated = unstated or traj
            continue
        if text not in _NORTH:
            raise InputFileError(
                path,
                f"aziRef {text!r}: expected {', '.join(_NORTH)} or unknown",
                line=node.line if node else traj.line,
            )
        if opts.north_reference is not None and _NORTH[text] != opts.north_reference:
            raise InputFileError(
                path,
                f"aziRef {text!r} contradicts the option north_reference {opts.north_reference!r}",
                line=node.line if node else traj.line,
            )
        found.add(_NORTH[text])
    if len(found) > 1:
        raise InputFileError(
            path, f"trajectories have different aziRef {sorted(found)}: read one (trajectory:)"
        )
    stated = found.pop() if found else None
    if stated is not None and unstated is not None and opts.north_reference is None:
        raise InputFileError(
            path,
            f"aziRef is absent or 'unknown' here but {AZI_REF[stated]!r} in another "
            "trajectory: set the reader option north_reference, or read one (trajectory:)",
            line=unstated.line,
        )
    north = stated or opts.north_reference or opts.default_north_reference
    if north is None:
        raise InputFileError(
            path,
            "aziRef is absent or 'unknown': set the reader option north_reference (or the "
            "well's north_reference)",
            line=trajectories[0].line,
        )
    return north


def _survey_stations(
    path: Path, traj: Node, nodes: list[Node], reasons: list[str | None], opts: WitsmlOptions
) -> tuple[list[Node], list[dict[str, Any]], list[dict[str, Any]]]:
    """The stations of ``nodes`` whose ``reasons`` are None and their rows; each other one
    is left out with a warning at its line naming its md (m) and the reason, its md and line
    kept for the check of the trajectory's range. None left: refused at the trajectory."""
    kept = [node for node, reason in zip(nodes, reasons, strict=True) if reason is None]
    if not kept:
        raise InputFileError(
            path,
            f"trajectory has no survey station: {len(nodes)} left out, the first for its "
            f"{reasons[0]} (line {nodes[0].line}); the reader option stations: all reads them",
            line=traj.line,
        )
    dropped = []
    warned = []
    for node, reason in zip(nodes, reasons, strict=True):
        md_node = node.get("md")
        md = _measure(path, md_node, "length") if md_node is not None and reason else None
        if reason is not None:
            where = f"at md {md!r} m " if md is not None else ""
            warned.append(
                (
                    f"station {where}left out: {reason}; the reader option stations: all reads it",
                    node.line,
                )
            )
        if md is not None:
            dropped.append({"md": md, SOURCE_LINE: node.line})
    warn_rows(path, warned, "stations left out")
    return kept, [_station(path, node, opts) for node in kept], dropped


def _station(path: Path, node: Node, opts: WitsmlOptions) -> dict[str, Any]:
    """One station's values; a null marker is no value (a missing incl or azi is NaN under
    the option ``null_stations: drop``: the engine leaves the station out)."""
    row: dict[str, Any] = {SOURCE_LINE: node.line}
    for column, element, quantity, required in STATION_MEASURES:
        child = node.get(element)
        value = _measure(path, child, quantity) if child is not None else None
        if value is None:
            if column == "azi" and _vertical(row.get("inc")):
                row[column] = float("nan")  # undefined at vertical, as the writer leaves it
            elif required:
                what = (
                    f"<{element}> {child.text.strip()} is a null marker"
                    if child is not None
                    else f"trajectoryStation has no <{element}>"
                )
                where = " (it may be left out only at vertical)" if column == "azi" else ""
                if opts.null_stations == "drop" and column != "md":
                    row[column] = float("nan")
                    continue
                article = "an" if quantity[0] in "aeiou" else "a"
                raise InputFileError(
                    path,
                    f"{what}{where}: expected {article} {quantity} (or the reader option "
                    "null_stations: drop to leave such stations out)",
                    line=child.line if child is not None else node.line,
                    column=element,
                )
            continue
        row[column] = value
    for column, element in STATION_TEXT:
        text = node.text_of(element)
        row[column] = text if text != "unknown" else None
    cov = node.get("matrixCov")
    if cov is not None:
        for column, element, _ in COVARIANCE:
            child = cov.get(element)
            row[column] = _measure(path, child, "area") if child is not None else None
    return row


def _tvd_of_md_datum(path: Path, nodes: list[Node], rows: list[dict[str, Any]]) -> None:
    """Leave out, with one warning, the tvd of the stations whose ``tvd`` names another
    ``datum`` than their ``md`` (a TVDSS, below sea level, beside depths from the KB): a
    trajectory does not say how far apart the datums are, and stations' TVD is below the
    depths' reference."""
    other: list[tuple[int, str, str]] = []
    for node, row in zip(nodes, rows, strict=True):
        elements = (node.get("md"), node.get("tvd"))
        md, tvd = (e.attrs.get("datum", "") if e is not None else "" for e in elements)
        if row.get("tvd") is not None and md and tvd and md != tvd:
            other.append((node.line, md, tvd))
            row.pop("tvd")
    if other:
        line, md_datum, tvd_datum = other[0]
        warn_input(
            path,
            f"<tvd> of {len(other)} station(s) left out, the first: its datum {tvd_datum!r} is "
            f"not that of <md>, {md_datum!r} (the trajectory gives no offset between them)",
            line,
        )


def _md_datum(
    path: Path, nodes: list[Node], seen: tuple[str, int] | None
) -> tuple[str, int] | None:
    """The ``datum`` the stations' ``md`` name (a WITSML wellDatum uid; none named: the
    well's default one) and its line, given ``seen``, the one named before: depths from two
    datums (a DF and a KB lie metres apart) are refused at the line."""
    for node in nodes:
        md = node.get("md")
        datum = md.attrs.get("datum") if md is not None else None
        if md is None or not datum:
            continue
        if seen is None:
            seen = (datum, md.line)
        elif datum != seen[0]:
            raise InputFileError(
                path,
                f"<md> datum {datum!r} differs from the {seen[0]!r} at line {seen[1]}: depths "
                "from two datums are not one survey's (the file gives no offset between them); "
                "read one trajectory at a time (reader option trajectory)",
                line=md.line,
                column="md",
            )
    return seen


MD_RANGE_TOLERANCE = 0.05
"""How far, m, a station may lie outside its trajectory's mdMn/mdMx (a range rounded)."""


def _md_range(
    path: Path, traj: Node, rows: list[dict[str, Any]], datum: tuple[str, int] | None
) -> None:
    """Warn where the stations (sorted by md, m) and the trajectory's ``mdMn``/``mdMx`` (in
    their own uom; not compared when on another datum than the stations') disagree: a station
    outside the range, or a range reaching past the stations — stations missing from the
    file (a truncated export, or a store's answer to a query for part of the trajectory) —
    and a bound that cannot be read (no uom, not a number)."""
    named = datum[0] if datum else None
    for element, row, sign in (("mdMn", rows[0], 1.0), ("mdMx", rows[-1], -1.0)):
        node = traj.get(element)
        if node is None or node.attrs.get("datum", named) != named:
            continue
        try:
            bound = _measure(path, node, "length")
        except InputFileError as exc:  # an element only checked: the stations still read
            warn_input(path, f"{exc.reason}; the stations are not checked against it", node.line)
            continue
        if bound is None:
            continue
        past = sign * (bound - row["md"])
        if past > MD_RANGE_TOLERANCE:
            warn_input(
                path,
                f"station md {row['md']!r} m lies outside the trajectory's {element} "
                f"{bound!r} m (line {node.line}): the range or the depths are wrong",
                row[SOURCE_LINE],
            )
        elif past < -MD_RANGE_TOLERANCE:
            end = "first" if element == "mdMn" else "last"
            warn_input(
                path,
                f"{element} {bound!r} m reaches past the {end} station, at {row['md']!r} m "
                f"(line {row[SOURCE_LINE]}): stations may be missing from the file (a "
                "truncated export, or a store's answer to a query for part of the trajectory)",
                node.line,
            )


def _vertical(inc: float | None) -> bool:
    """Whether an inclination (deg) is vertical enough to leave the azimuth undefined."""
    return inc is not None and min(abs(inc), abs(180.0 - inc)) <= VERTICAL_TOLERANCE


def _measure(path: Path, node: Node, quantity: str) -> float | None:
    """A measure element's value in the canonical unit of ``quantity`` (None: a null marker
    of :mod:`pipeline.io.nulls`, in the element's own unit)."""
    uom = node.attrs.get("uom")
    if not uom:
        raise InputFileError(path, f"<{node.name}> has no uom", line=node.line, column=node.name)
    try:
        value = file_number(node.text.strip())
    except ValueError:
        raise InputFileError(
            path,
            f"<{node.name}> {node.text.strip()!r} is not a number",
            line=node.line,
            column=node.name,
        ) from None
    if not math.isfinite(value):
        raise InputFileError(
            path,
            f"<{node.name}> {node.text.strip()!r} is not a finite number",
            line=node.line,
            column=node.name,
        )
    if is_null_marker(value, angle=quantity in ("angle", "dogleg_severity")):
        return None
    try:
        return value * uom_factor(uom, quantity)
    except UnitError as exc:
        raise InputFileError(path, f"<{node.name}>: {exc}", line=node.line) from None


def _well(
    path: Path, trajectories: list[Node], north: NorthReference, datum: tuple[str, int] | None
) -> WellMetadata:
    """Well metadata: gyropipe's extension values, then the WITSML elements (which win);
    ``datum``: the one the stations' md name, which must be the depth reference's."""
    first = trajectories[0]
    found: dict[str, tuple[Any, int]] = {}
    common = first.get("commonData")
    for entry in common.all("extensionNameValue") if common is not None else []:
        name = entry.text_of("name") or ""
        holder = entry.get("value")
        field_name = name[len(EXTENSION_PREFIX) :]
        if not name.startswith(EXTENSION_PREFIX) or holder is None:
            continue
        if field_name not in WellMetadata.model_fields or field_name == "north_reference":
            continue
        quantity = EXTENSION_QUANTITY.get(field_name)
        value = _measure(path, holder, quantity) if quantity else holder.text.strip()
        if value is not None:
            found[field_name] = (value, holder.line)
    _depth_reference_agrees(path, datum, found.get("depth_reference"))
    names = {t.text_of("nameWell") for t in trajectories}
    if len(names) > 1:
        raise InputFileError(path, f"trajectories of several wells {sorted(map(str, names))}")
    if (well := first.text_of("nameWell")) is not None:
        found["well"] = (well, first.line)
    wellbore = first.text_of("nameWellbore")
    if wellbore is not None and wellbore != well:
        found["wellbore"] = (wellbore, first.line)
    for name, element, quantity in WELL_ELEMENTS:
        node = first.get(element)
        if node is not None:
            value = _measure(path, node, quantity) if quantity else " ".join(node.text.split())
            if value is not None:
                found[name] = (value, node.line)
    for traj in trajectories:
        _corrections(path, traj, found)
    _applied_agrees(path, north, found)
    _survey_date(path, trajectories, north, found)
    tools = (  # the tie-in point names no tool: the first station that names one
        (tool, station.line)
        for traj in trajectories
        for station in traj.all("trajectoryStation")
        if (tool := station.text_of("typeSurveyTool")) and survey_tool(tool) != "unknown"
    )
    if "tool_type" not in found and (tool_found := next(tools, None)) is not None:
        found["tool_type"] = tool_found
    for name, (value, line) in found.items():
        try:
            WellMetadata.model_validate({name: value})
        except ValidationError as exc:
            raise InputFileError(
                path, f"{name} {value!r}: {exc.errors()[0]['msg']}", line=line
            ) from None
    return WellMetadata(north_reference=north, **{n: v for n, (v, _) in found.items()})


def _depth_reference_agrees(
    path: Path, datum: tuple[str, int] | None, reference: tuple[Any, int] | None
) -> None:
    """A datum the stations' md name (KB, RKB, DF, GL… by :data:`~pipeline.well.DATUM_WORDS`)
    must be the depth reference the file states, whose elevation it may state too."""
    if datum is None or reference is None:
        return
    named, stated = (
        DATUM_WORDS.get("".join(str(t).casefold().split())) for t in (datum[0], reference[0])
    )
    if named is not None and stated is not None and named != stated:
        raise InputFileError(
            path,
            f"<md> datum {datum[0]!r} is not the depth reference {reference[0]!r} stated at "
            f"line {reference[1]}: the depths and the well's elevation would be of two datums",
            line=datum[1],
            column="md",
        )


def _corrections(path: Path, traj: Node, found: dict[str, tuple[Any, int]]) -> None:
    """The corrections a trajectory and each of its stations say were applied (``…Used``,
    ``corUsed``; null markers are no value) must be one value for the whole file, as
    the first trajectory states it: the well metadata hold one, applied to every azimuth."""
    used = [(traj, element, name) for name, element, q in WELL_ELEMENTS if q == "angle"]
    for station in traj.all("trajectoryStation"):
        holder = station.get("corUsed")
        if holder is not None:
            used += [(holder, element, name) for element, name in STATION_CORRECTIONS.items()]
    for holder, element, name in used:
        node = holder.get(element)
        value = _measure(path, node, "angle") if node is not None else None
        if value is None or node is None:
            continue
        if name not in found:
            found[name] = (value, node.line)
        elif not math.isclose(value, found[name][0], rel_tol=0.0, abs_tol=1e-9):
            raise InputFileError(
                path,
                f"<{element}> {value!r}° differs from the {found[name][0]!r}° stated at "
                f"line {found[name][1]}: a correction varying along a trajectory or between "
                "trajectories is not supported (it would be applied as one value)",
                line=node.line,
                column=element,
            )


def _applied_agrees(path: Path, north: NorthReference, found: dict[str, tuple[Any, int]]) -> None:
    """A correction applied to the azimuths must fit their north reference
    (:data:`~pipeline.well.APPLIED_REFUSED`)."""
    for name, (value, line) in found.items():
        if contradicts_north(north, name, value):
            raise InputFileError(
                path,
                f"{name.replace('_', ' ')} {value!r}° contradicts aziRef {AZI_REF[north]!r}: "
                f"azimuths referred to {north} north carry no such correction",
                line=line,
            )


def _survey_date(
    path: Path, trajectories: list[Node], north: NorthReference, found: dict[str, tuple[Any, int]]
) -> None:
    """The survey date: the earliest ``dTimTrajStart``, the day the survey began, and of
    trajectories begun on several days the latest as ``survey_date_last`` (no one date's
    declination is then applied to every station downstream). Magnetic-north azimuths
    without a stated declination take theirs from the date downstream (a declination drifts
    by up to tenths of a degree a year): trajectories started on different days, or one
    undated beside a dated one, are refused here, at the line, not given one day's; of other
    azimuths, an undated one beside a dated one is warned of at its line."""
    starts = [(traj, traj.get("dTimTrajStart")) for traj in trajectories]
    dated = [(node, _date(path, node)) for _, node in starts if node is not None]
    if not dated:
        return
    earliest, day = min(dated, key=lambda entry: entry[1])
    latest, last = max(dated, key=lambda entry: entry[1])
    found["survey_date"] = (day, earliest.line)
    found.pop("survey_date_last", None)  # the trajectories' own dates, not an extension's
    if last != day:
        found["survey_date_last"] = (last, latest.line)
    later = next(((node, other) for node, other in dated if other != day), None)
    undated = next((traj for traj, node in starts if node is None), None)
    if north == "magnetic" and "declination" not in found and (later or undated):
        if later is not None:
            line = later[0].line
            what = (
                f"<dTimTrajStart> {later[1].isoformat()} differs from the {day.isoformat()} "
                f"at line {earliest.line}"
            )
        else:
            line = undated.line if undated is not None else 0
            what = (
                f"trajectory without <dTimTrajStart> beside one started {day.isoformat()} "
                f"(line {earliest.line})"
            )
        raise InputFileError(
            path,
            f"{what}: the declination of these magnetic-north azimuths (none stated, none "
            "applied) depends on each survey's date; read one trajectory at a time (reader "
            "option trajectory: its uid or name)",
            line=line,
            column="dTimTrajStart",
        )
    if undated is not None:
        warn_input(
            path,
            f"trajectory without <dTimTrajStart> beside one started {day.isoformat()} (line "
            f"{earliest.line}): when it began is not known; the survey date is the dated "
            "ones' (a geomagnetic field or declination from it applies to its stations too)",
            undated.line,
        )


def _date(path: Path, node: Node) -> dt.date:
    text = node.text.strip()
    try:
        return dt.datetime.fromisoformat(text.replace("Z", "+00:00")).date()
    except ValueError:
        raise InputFileError(
            path, f"<{node.name}> {text!r} is not an ISO 8601 date and time", line=node.line
        ) from None

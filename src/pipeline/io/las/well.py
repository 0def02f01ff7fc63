"""Well metadata of a LAS file, from its ~Well, then ~Parameter items (an item in both with
another value is refused: a ~Parameter item does not override the ~Well's).

WELL, UWI (else API), FLD, COMP, SRVC, TOOL, TOOLSN, TOOLPRESET (the tool catalogue's
entry, as gyropipe writes it), TOOLNAME, WELLBORE, RUN, JOB, HZCS (else CRS, PROJ); the
wellhead's map coordinates X/EASTING/XCOORD and Y/NORTHING/YCOORD in the item's unit, a
unitless one only beside depths in metres (feet do not tell US survey from international
ones: refused at its line); MAGFIELD (in its unit) and MAGDIP; LAT/LATI/LATITUDE and
LON/LONG/LONGITUDE in decimal degrees (in the item's unit) or degrees, minutes and seconds
(``61 15 00.5 N``, ``73°24'30"E``); DATE as ISO or another unambiguous form
(``13-DEC-1986``, ``13/12/1986``; ``05/06/2024`` is refused as ambiguous:
:mod:`pipeline.io.dates`, as a CSV title's date); elevation
from EREF, else the item of the depth reference (DREF, LMF or DMF: KB→EKB, DF→EDF, GL→EGL,
else ELEV), else the only one of EKB/EDF/EGL/ELEV (several and no reference item: an
error), in its unit, else in the file's depth unit, as a CSV title's: md's in the reader
option ``units`` (which says what the depths are in), else that of STRT, STOP, STEP and the
index curve where they agree on one (else an error); DECL (MAGDEC, DECLINATION) and GRIDCONV
(CONV, CONVERGENCE), the site's, and DECLUSED and GRIDUSED, the corrections already applied
to the azimuths, in degrees or the item's angle unit (non-zero ones the file's north cannot
carry are refused, as in WITSML: a GRIDUSED on true- or magnetic-north azimuths, a DECLUSED
on magnetic ones). A GRIDCORR is left out with a warning: a vendor's grid correction is what
was applied to azimuths, added by some (−γ) and subtracted by others (γ), never the site's
convergence as such.
A number item holding the file's NULL or a null marker (``-999.25``…, in its unit) is no
value, as in the data. ``north_reference`` is the one the file names (an option's is not the
file's).
"""

from __future__ import annotations

import datetime as dt
import re
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from pipeline.errors import InputFileError, UnitError, warn_input
from pipeline.io.dates import header_date
from pipeline.io.las.header import NUMBER, Header, Item, header_number
from pipeline.io.nulls import is_null_marker
from pipeline.units import conversion_factor
from pipeline.well import DATUM_WORDS, NorthReference, WellMetadata, contradicts_north

TEXT_ITEMS: dict[str, tuple[str, ...]] = {
    "well": ("WELL",),
    "uwi": ("UWI", "API"),
    "field": ("FLD", "FIELD"),
    "company": ("COMP",),
    "service_company": ("SRVC",),
    "tool_type": ("TOOL",),
    "tool_serial": ("TOOLSN",),
    "tool_preset": ("TOOLPRESET",),
    "tool_name": ("TOOLNAME",),
    "wellbore": ("WELLBORE",),
    "run_number": ("RUN",),
    "job_number": ("JOB",),
    "crs": ("HZCS", "CRS", "PROJ"),
}
"""Well metadata text fields and the mnemonics holding them, preferred first."""
MAP_ITEMS = {
    "easting": ("EASTING", "XCOORD", "X"),
    "northing": ("NORTHING", "YCOORD", "Y"),
}
"""The wellhead's map coordinates (LAS 3.0 X and Y; vendors' EASTING/NORTHING, XCOORD/YCOORD):
in the item's unit, else only where the depths are in metres (feet do not tell US survey
from international ones, 2 ppm apart)."""
ANGLE_ITEMS = {
    "declination": ("DECL", "MAGDEC", "DECLINATION"),
    "grid_convergence": ("GRIDCONV", "CONV", "CONVERGENCE"),
    "declination_applied": ("DECLUSED",),
    "grid_convergence_applied": ("GRIDUSED",),
    "magnetic_dip": ("MAGDIP",),
}
"""Well metadata angles (deg, in the item's unit) and the mnemonics holding them."""
FIELD_ITEM = "MAGFIELD"
"""The geomagnetic total field (in the item's unit, which it must state; nT)."""
UNREAD_CORRECTION = "GRIDCORR"
"""A vendor's grid correction, of no agreed sign: not read as either grid convergence."""
COORDINATE_ITEMS = {
    "latitude": (("LAT", "LATI", "LATITUDE"), "NS"),
    "longitude": (("LON", "LONG", "LONGITUDE"), "EW"),
}
"""Coordinate fields: their mnemonics and hemisphere letters (positive, negative)."""
REFERENCE_ITEMS = ("DREF", "LMF", "DMF")
ELEVATION_ITEMS: dict[str, str | None] = {
    "EREF": None,
    "EKB": "KB",
    "EDF": "DF",
    "EGL": "GL",
    "ELEV": None,
}
"""Elevation items and the depth reference each implies."""

_DMS_NUMBER = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)"
_DMS_MARKS = re.compile(r"[°º'′\"″:\s]|DEG")


def well_metadata(
    path: Path,
    header: Header,
    north: NorthReference | None,
    *,
    strict: bool = True,
    depth_unit: str | None = None,
) -> WellMetadata:
    """Well metadata from ~Well, then ~Parameter items; ``north`` is the file's (a
    correction applied that its azimuths cannot carry is refused); ``depth_unit``: the
    depths' unit an option states (else the file's). Not ``strict`` (a log), an item that
    cannot be read is left out with a warning."""
    found: dict[str, tuple[Any, Item]] = {}

    def take(name: str, read: Callable[[], tuple[Any, Item] | None]) -> None:
        try:
            value = read()
            if value is not None:
                try:
                    WellMetadata.model_validate({name: value[0]})
                except ValidationError as exc:
                    item = value[1]
                    raise InputFileError(
                        path,
                        f"{item.mnemonic} {item.value!r}: {exc.errors()[0]['msg']}",
                        line=item.line,
                    ) from None
                found[name] = value
        except InputFileError as exc:
            if strict:
                raise
            warn_input(path, f"{exc.reason}; well metadata {name} left out", exc.line)

    def text(mnemonics: tuple[str, ...]) -> tuple[Any, Item] | None:
        item = header.find(path, *mnemonics)
        return None if item is None else (item.value, item)

    def coordinate(mnemonics: tuple[str, ...], hemispheres: str) -> tuple[Any, Item] | None:
        item = header.find(path, *mnemonics)
        if item is None or _null(header, item, angle=True):
            return None
        return _coordinate(path, item, hemispheres), item

    def map_coordinate(mnemonics: tuple[str, ...]) -> tuple[Any, Item] | None:
        item = header.find(path, *mnemonics)
        if item is None or _null(header, item, angle=False):
            return None
        return header_number(path, item) * _map_factor(path, header, item, depth_unit), item

    def angle(mnemonics: tuple[str, ...]) -> tuple[Any, Item] | None:
        item = header.find(path, *mnemonics)
        if item is None or _null(header, item, angle=True):
            return None
        return header_number(path, item) * _angle_factor(path, item), item

    def field_strength() -> tuple[Any, Item] | None:
        item = header.find(path, FIELD_ITEM)
        if item is None or _null(header, item, angle=False):
            return None
        try:
            factor = conversion_factor(item.unit, "magnetic_field")
        except UnitError as exc:
            raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None
        return header_number(path, item) * factor, item

    def date() -> tuple[Any, Item] | None:
        item = header.find(path, "DATE")
        return None if item is None else (_date(path, item), item)

    for name, mnemonics in TEXT_ITEMS.items():
        take(name, partial(text, mnemonics))
    for name, (mnemonics, hemispheres) in COORDINATE_ITEMS.items():
        take(name, partial(coordinate, mnemonics, hemispheres))
    for name, mnemonics in ANGLE_ITEMS.items():
        take(name, partial(angle, mnemonics))
    take("magnetic_field", field_strength)
    for name, mnemonics in MAP_ITEMS.items():
        take(name, partial(map_coordinate, mnemonics))
    take("survey_date", date)
    if (unread := header.find(path, UNREAD_CORRECTION)) is not None:
        warn_input(
            path,
            f"{UNREAD_CORRECTION} {unread.value!r} left out: a grid correction's sign is the "
            "vendor's (added to the azimuths or subtracted); state it as GRIDCONV (the site's "
            "convergence, grid north east of true north +) or GRIDUSED (the one applied)",
            unread.line,
        )
    try:
        elevation, reference = _elevation(path, header, depth_unit)
    except InputFileError as exc:
        if strict:
            raise
        warn_input(path, f"{exc.reason}; well metadata elevation left out", exc.line)
        elevation, reference = None, None
    take("elevation", lambda: elevation)
    take("depth_reference", lambda: reference)
    for name, (value, item) in found.items():
        if contradicts_north(north, name, value):
            raise InputFileError(
                path,
                f"{item.mnemonic} {value!r}°: a {name.replace('_', ' ')} contradicts the "
                f"azimuths' {north} north (azimuths referred to it carry no such correction)",
                line=item.line,
            )
    return WellMetadata(north_reference=north, **{n: v for n, (v, _) in found.items()})


def _null(header: Header, item: Item, *, angle: bool) -> bool:
    """Whether a number item holds a null: the file's NULL or a null marker
    (:mod:`pipeline.io.nulls`), in its own unit: no value, as in the data."""
    if not re.fullmatch(NUMBER, item.value):
        return False
    value = float(item.value)
    nulls = (i.value for i in header.well + header.parameters if i.mnemonic == "NULL")
    return is_null_marker(value, angle=angle) or any(
        re.fullmatch(NUMBER, null) and float(null) == value for null in nulls
    )


def _angle_factor(path: Path, item: Item) -> float:
    """Degrees per unit of an angle item (no unit: degrees)."""
    try:
        return conversion_factor(item.unit, "angle") if item.unit else 1.0
    except UnitError as exc:
        raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None


def _coordinate(path: Path, item: Item, hemispheres: str) -> float:
    """Degrees of a latitude/longitude: a decimal number (in the item's unit, default deg)
    or degrees, minutes and seconds, with an optional hemisphere letter (S and W: −)."""

    def fail(reason: str) -> InputFileError:
        return InputFileError(
            path,
            f"{item.mnemonic} {item.value!r}: {reason}; write decimal degrees (61.25, -73.4) "
            "or degrees, minutes and seconds (61 15 00.0 N)",
            line=item.line,
        )

    text = item.value.strip().upper()
    sign = 1.0
    if found := re.fullmatch(rf"([{hemispheres}])\s*(.*)|(.*?)\s*([{hemispheres}])", text):
        text = found[2] if found[1] else found[3]
        sign = -1.0 if (found[1] or found[4]) == hemispheres[1] else 1.0
        if text.startswith(("-", "+")):
            raise fail("both a sign and a hemisphere")
    try:
        if not re.fullmatch(NUMBER, text):
            return sign * _dms(text)
        return sign * float(text) * (conversion_factor(item.unit, "angle") if item.unit else 1.0)
    except (ValueError, UnitError) as exc:
        raise fail(str(exc)) from None


def _dms(text: str) -> float:
    """Degrees of degrees-minutes(-seconds) text (marks ° ' " or spaces; sign on degrees)."""
    numbers = re.findall(_DMS_NUMBER, text)
    if _DMS_MARKS.sub("", re.sub(_DMS_NUMBER, "", text)) or not 2 <= len(numbers) <= 3:
        raise ValueError("not a coordinate")
    degrees, *rest = (float(n) for n in numbers)
    if not degrees.is_integer() or any(
        r >= 60 or n[0] in "+-" for r, n in zip(rest, numbers[1:], strict=True)
    ):
        raise ValueError("minutes and seconds must be in [0, 60) after whole degrees")
    magnitude = abs(degrees) + sum(r / 60.0**k for k, r in enumerate(rest, start=1))
    return -magnitude if numbers[0].startswith("-") else magnitude


def _date(path: Path, item: Item) -> dt.date:
    """The date of a DATE item (:func:`pipeline.io.dates.header_date`)."""
    try:
        return header_date(item.value)
    except ValueError as exc:
        raise InputFileError(
            path, f"DATE {item.value!r}: {exc}; write it as YYYY-MM-DD", line=item.line
        ) from None


def _elevation(
    path: Path, header: Header, depth_unit: str | None
) -> tuple[tuple[float, Item] | None, tuple[str, Item] | None]:
    """(elevation m, its item) and (depth reference, its item), each when known; an item
    without a unit is in ``depth_unit`` if given, else the file's depth unit."""
    reference = header.find(path, *REFERENCE_ITEMS)
    present = {m: i for m in ELEVATION_ITEMS if (i := header.find(path, m)) is not None}
    item = present.get("EREF")
    if item is None and reference is not None:
        datum = DATUM_WORDS.get("".join(reference.value.casefold().split()))
        of_datum = (i for m, i in present.items() if datum and ELEVATION_ITEMS[m] == datum)
        item = next(of_datum, present.get("ELEV"))
    elif item is None and len(present) > 1:
        raise InputFileError(
            path,
            f"elevations {', '.join(present)} are given but no DREF, LMF or DMF item says "
            "which one depths are measured from",
            line=max(i.line for i in present.values()),
        )
    elif item is None and present:
        item = next(iter(present.values()))
    depth: tuple[str, Item] | None = None
    if reference is not None:
        depth = (reference.value, reference)
    elif item is not None and (implied := ELEVATION_ITEMS[item.mnemonic]) is not None:
        depth = (implied, item)
    if item is None or _null(header, item, angle=False):
        return None, depth
    try:
        unit = item.unit or depth_unit or _depth_unit(header)
        if not unit:
            raise UnitError(
                "no unit, and the depths (STRT, STOP, STEP, the index curve) give none or "
                f"several: write e.g. '{item.mnemonic}.M  {item.value}'"
            )
        factor = conversion_factor(unit, "length")
    except UnitError as exc:
        raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None
    return (header_number(path, item) * factor, item), depth


def _map_factor(path: Path, header: Header, item: Item, depth_unit: str | None) -> float:
    """Factor to metres of a map coordinate item (:data:`MAP_ITEMS`): its unit's, else 1
    where the depths are in metres; else an :class:`InputFileError` at its line."""
    try:
        if item.unit:
            return conversion_factor(item.unit, "length")
        unit = depth_unit or _depth_unit(header)
        if unit and conversion_factor(unit, "length") == 1.0:
            return 1.0
    except UnitError as exc:
        raise InputFileError(path, f"{item.mnemonic}: {exc}", line=item.line) from None
    raise InputFileError(
        path,
        f"{item.mnemonic}: no unit, and a map coordinate is in its CRS's unit, which depths in "
        f"{unit or 'no one unit'} do not tell (US survey or international feet): write e.g. "
        f"'{item.mnemonic}.USFT  {item.value}'",
        line=item.line,
    )


def _depth_unit(header: Header) -> str | None:
    """The file's one depth unit: that of STRT, STOP, STEP and the index curve, where those
    that state one agree (None: none states one, or they differ or are no length)."""
    items = [i for i in header.well if i.mnemonic in ("STRT", "STOP", "STEP")] + header.curves[:1]
    units = [i.unit for i in items if i.unit]
    try:
        factors = {conversion_factor(unit, "length") for unit in units}
    except UnitError:
        return None
    return units[0] if len(factors) == 1 else None

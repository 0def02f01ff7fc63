"""The manifest of offset wells for a clearance scan: a CSV file, one well per line.

Columns (header row first; lines starting with ``#`` are comments; a length column names its
unit in the header, ``hole_diameter (in)``, ``north [m]``):

- ``well_id`` — the offset well's name in the results (unique);
- ``file`` — its stations file (MD, inclination, azimuth), relative to the manifest's folder;
- ``model`` — its tool model (e.g. ``ISCWSA-MWD-REV5``, ``GYRO-NS``);
- ``hole_diameter`` — hole or casing diameter (a length);
- ``north``, ``east`` — its slot: its position relative to the reference well's wellhead,
  in the north of the reference's azimuths; its first station lies there, plus the north and
  east its stations file lists there where it lists TVD, north and east (its tie-on, from
  its own wellhead) (lengths; required on every
  row: an empty cell or a null marker (``-999.25``…, :mod:`pipeline.io.nulls`) is an
  error, never the reference's wellhead or a slot 999.25 away; a well on the
  reference's own slot, a sidetrack or re-entry, says so with ``0,0``);
- ``tvd`` — its first station's TVD below the reference's depth datum (a length; default:
  the TVD its stations file lists there, else the first station's MD);
- ``parent`` — optional: ``reference`` (or the reference well's name) for a sidetrack of the
  reference well; ``kickoff_md`` — optional: its kick-off MD on the reference (a length;
  naming it names the parent). Without them a well whose first station lies on the reference
  path is found to share its hole there;
- ``declination``, ``convergence`` — optional: the well's magnetic declination and grid
  convergence (deg, east of true north positive; an angle unit in the header optional),
  where its stations file cannot state them (a WITSML trajectory has no element for the
  site's declination): a magnetic-north well's azimuths are referred to true north by its
  own declination, a grid-north well's by its own convergence, never by another file's.

A null marker in any length column is no value, as an empty cell. Every problem is an
:class:`~pipeline.errors.InputFileError` naming the file and line.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from pipeline.errors import InputFileError, UnitError
from pipeline.io.nulls import is_null_marker
from pipeline.io.numbers import file_number
from pipeline.units import conversion_factor

__all__ = ["ANGLES", "LENGTHS", "OffsetEntry", "read_offset_manifest"]

LENGTHS = ("hole_diameter", "north", "east", "tvd", "kickoff_md")
"""The length columns, each with its unit in the header."""
ANGLES = ("declination", "convergence")
"""The angle columns (deg unless the header names another angle unit), within ±180°."""
_TEXT = ("well_id", "file", "model")
_OPTIONAL_TEXT = ("parent",)
_REQUIRED = ("hole_diameter", "north", "east")
_HEADER = re.compile(r"^\s*([A-Za-z_]+)\s*(?:[\(\[]\s*([^\)\]]*?)\s*[\)\]])?\s*$")


@dataclass(frozen=True)
class OffsetEntry:
    """One offset well of a manifest; lengths in metres (``tvd`` None: the first MD), angles
    in degrees (None: not given)."""

    well_id: str
    file: Path
    model: str
    hole_diameter: float
    north: float
    east: float
    tvd: float | None
    line: int
    parent: str | None = None
    kickoff_md: float | None = None
    declination: float | None = None
    convergence: float | None = None


def _columns(path: Path, line: int, cells: list[str]) -> dict[str, tuple[int, float]]:
    """Column name → (index, factor to m or deg) of a header row."""
    found: dict[str, tuple[int, float]] = {}
    for index, cell in enumerate(cells):
        match = _HEADER.match(cell)
        name = match.group(1).lower() if match else cell.strip()
        if name not in (*_TEXT, *_OPTIONAL_TEXT, *LENGTHS, *ANGLES):
            known = ", ".join((*_TEXT, *_OPTIONAL_TEXT, *LENGTHS, *ANGLES))
            raise InputFileError(
                path,
                f"unknown column {cell.strip()!r}; expected {known}",
                line,
            )
        if name in found:
            raise InputFileError(path, f"column {name!r} appears twice", line)
        unit = match.group(2) if match else None
        if name in LENGTHS and not unit:
            raise InputFileError(
                path, f"column {name!r} needs its unit in the header, e.g. '{name} (m)'", line
            )
        factor = 1.0
        if unit and name in (*LENGTHS, *ANGLES):
            try:
                factor = conversion_factor(unit, "length" if name in LENGTHS else "angle")
            except UnitError as exc:
                raise InputFileError(path, f"column {name!r}: {exc}", line) from None
        found[name] = (index, factor)
    missing = [c for c in (*_TEXT, *_REQUIRED) if c not in found]
    if missing:
        raise InputFileError(path, f"missing column(s) {', '.join(missing)}", line)
    return found


def _records(path: Path, text: str) -> Iterator[tuple[int, list[str]]]:
    """The CSV records, each with the line it starts on; a quoted cell spanning lines is
    refused at its line (split into lines first, its parts were joined into one name)."""
    reader = csv.reader(io.StringIO(text, newline=""))
    start = 1
    for cells in reader:
        broken = next((cell for cell in cells if "\n" in cell or "\r" in cell), None)
        if broken is not None:
            raise InputFileError(
                path,
                f"a line break in {broken!r} (a quoted cell spans lines): a cell is one line",
                start,
            )
        yield start, cells
        start = reader.line_num + 1


def read_offset_manifest(path: Path, resolve: Callable[[str], str]) -> list[OffsetEntry]:
    """The offset wells a manifest lists (module docstring); ``resolve`` gives the canonical
    name of a tool model (ValueError: unknown)."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"cannot read the manifest: {exc}") from None
    rows = [
        (number, cells)
        for number, cells in _records(path, text)
        if cells and any(c.strip() for c in cells) and not cells[0].lstrip().startswith("#")
    ]
    if not rows:
        raise InputFileError(path, "empty manifest (expected a header row)")
    header_line, header = rows[0]
    columns = _columns(path, header_line, header)
    entries: list[OffsetEntry] = []
    seen: dict[str, int] = {}
    for line, cells in rows[1:]:
        if len(cells) != len(header):
            raise InputFileError(path, f"{len(cells)} cells, the header has {len(header)}", line)
        cell = {name: cells[i].strip() for name, (i, _) in columns.items()}
        well_id, model = cell["well_id"], cell["model"]
        if not well_id or not cell["file"]:
            raise InputFileError(path, "well_id and file must not be empty", line)
        if well_id in seen:
            raise InputFileError(
                path, f"well {well_id!r} already listed on line {seen[well_id]}", line
            )
        seen[well_id] = line
        try:
            model = resolve(model)
        except ValueError as exc:
            raise InputFileError(path, str(exc), line, "model") from None
        numbers: dict[str, float | None] = {}
        for name in (*LENGTHS, *ANGLES):
            raw = cell.get(name, "")
            if not raw:
                numbers[name] = None
                continue
            try:
                number = file_number(raw)
            except ValueError:
                raise InputFileError(path, f"{name}: not a number: {raw!r}", line, name) from None
            if is_null_marker(number, angle=name in ANGLES):  # in the file's unit: no value
                numbers[name] = None
                continue
            value = number * columns[name][1]
            if value != value or abs(value) == float("inf"):
                raise InputFileError(path, f"{name}: not a finite number: {raw!r}", line, name)
            if name in ANGLES and abs(value) > 180.0:
                shown = raw if columns[name][1] == 1.0 else f"{raw} ({value:.6g}°)"
                raise InputFileError(path, f"{name}: {shown} is not within ±180°", line, name)
            numbers[name] = value
        diameter = numbers["hole_diameter"]
        if diameter is None or diameter <= 0:
            raise InputFileError(
                path, "hole_diameter must be given and positive", line, "hole_diameter"
            )
        north, east = numbers["north"], numbers["east"]
        if north is None or east is None:
            name = "north" if north is None else "east"
            raise InputFileError(
                path,
                f"{name} is empty or a null marker: expected the slot's {name} from the "
                "reference wellhead "
                "(a length; 0,0 for a well on the reference's own slot)",
                line,
                name,
            )
        entries.append(
            OffsetEntry(
                well_id=well_id,
                file=(path.parent / cell["file"]).resolve(),
                model=model,
                hole_diameter=diameter,
                north=north,
                east=east,
                tvd=numbers["tvd"],
                line=line,
                parent=cell.get("parent")
                or ("reference" if numbers["kickoff_md"] is not None else None),
                kickoff_md=numbers["kickoff_md"],
                declination=numbers["declination"],
                convergence=numbers["convergence"],
            )
        )
    if not entries:
        raise InputFileError(path, "no offset wells listed below the header")
    return entries

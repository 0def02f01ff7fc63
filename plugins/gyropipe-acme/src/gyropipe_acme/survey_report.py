"""Acme survey report (``.txt``), a fictional vendor export of survey stations.

Layout (UTF-8 text, LF or CRLF line ends)::

    ACME SURVEY REPORT                  line 1: the format's title
    WELL=Demo-1                         optional KEY=VALUE lines: WELL, LAT, LON
    NORTH=GRID                          north reference of the azimuths: TRUE, GRID, MAGNETIC
    MD(ft) INC(deg) AZI(deg)            the column header, always these three
    100.0 1.25 47.5                     one station per line, blank-separated

Depths are in feet, angles in degrees. The column header names MD, INC and AZI, so
gyropipe's own CSV reader recognises the file as well; this reader claims it by its title
line and, at the same strength, a third-party reader wins the choice.
"""

from __future__ import annotations

from pathlib import Path

import pyarrow as pa
from pydantic import BaseModel, ConfigDict

from pipeline.plugin import (
    SOURCE_LINE,
    Claim,
    DefaultNorthReference,
    InputFileError,
    NorthReference,
    Stations,
    WellMetadata,
    conversion_factor,
)

TITLE = "ACME SURVEY REPORT"
COLUMNS = ("MD(ft)", "INC(deg)", "AZI(deg)")
NORTH: dict[str, NorthReference] = {"TRUE": "true", "GRID": "grid", "MAGNETIC": "magnetic"}
WELL_KEYS = {"WELL": "well", "LAT": "latitude", "LON": "longitude"}


class SurveyReportOptions(BaseModel):
    """Options of the ``acme_survey`` reader."""

    model_config = ConfigDict(extra="forbid")
    default_north_reference: DefaultNorthReference = None


def sniff(path: Path) -> Claim:
    """By content: the first line is the title ``ACME SURVEY REPORT``."""
    try:
        with path.open("rb") as fh:
            first = fh.readline(len(TITLE) + 8)
    except OSError:
        return Claim.NO
    return Claim.CONTENT if first.strip() == TITLE.encode() else Claim.NO


def read_stations(path: Path, options: SurveyReportOptions) -> tuple[pa.Table, WellMetadata]:
    """Stations (md m, inc deg, azi deg from the north the file declares, else the option's)
    with the ``source_line`` of each, and the header's well metadata; a malformed line is an
    :class:`InputFileError` naming it."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputFileError(path, f"cannot read the file as UTF-8 text: {exc}") from None
    if not lines or lines[0].strip() != TITLE:
        raise InputFileError(path, f"expected the title {TITLE!r}", line=1)
    well: dict[str, str] = {}
    north: NorthReference | None = options.default_north_reference
    for number, line in enumerate(lines[1:], 2):
        key, sep, value = line.partition("=")
        if sep and key.strip() == "NORTH":
            north = NORTH.get(value.strip().upper())
            if north is None:
                raise InputFileError(path, f"NORTH must be one of {', '.join(NORTH)}", line=number)
        elif sep and key.strip() in WELL_KEYS:
            well[WELL_KEYS[key.strip()]] = value.strip()
        elif tuple(line.split()) == COLUMNS:
            return _stations(path, lines, number, north), WellMetadata.model_validate(well)
        else:
            raise InputFileError(
                path, f"expected KEY=VALUE or the header {' '.join(COLUMNS)}", number
            )
    raise InputFileError(path, f"no header line {' '.join(COLUMNS)}", line=len(lines))


def _stations(path: Path, lines: list[str], header: int, north: str | None) -> pa.Table:
    if north is None:
        raise InputFileError(path, "no NORTH line (TRUE, GRID or MAGNETIC) and no default", 2)
    rows: list[list[float]] = []
    numbers: list[int] = []
    for number, line in enumerate(lines[header:], header + 1):
        if not line.strip():
            continue
        cells = line.split()
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            values = []
        if len(values) != len(COLUMNS):
            raise InputFileError(path, f"expected three numbers, got {line.strip()!r}", number)
        rows.append(values)
        numbers.append(number)
    feet = conversion_factor("ft", "length")
    data = {
        "md": [row[0] * feet for row in rows],
        "inc": [row[1] for row in rows],
        "azi": [row[2] for row in rows],
        SOURCE_LINE: pa.array(numbers, pa.int64()),
    }
    return Stations.compiled().make_table(data, north_reference=north)

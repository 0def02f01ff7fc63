"""Acme GyroLog v2 (``.agl``), a fictional vendor format of raw gyro-tool samples.

Layout (UTF-8 text, LF or CRLF line ends)::

    ACME GYROLOG v2                     line 1: magic and format version
    WELL=Demo-1                         header, KEY=VALUE lines in any order:
    SERIAL=AG-1093                        WELL, SERIAL, LAT and LON (deg, WGS84),
    LAT=61.25                             DATE (ISO 8601); other keys are ignored
    LON=73.4
    DATE=2026-11-21
    CHANNELS=T DEPTH FANG WX WY WZ AX AY AZ MX MY MZ STN POS
    DATA                                end of the header
    0 0 0 0 0.00200960673332025 ...     one sample per line, one value per channel,
                                        separated by blanks; '-' = none (STN, POS)

Channels are in Acme's units (:data:`CHANNELS`) and Acme's axes (:data:`CONVENTIONS`). Both
are only declared here; the conversions are gyropipe's own (:func:`conversion_factor`,
:func:`to_canonical`). T and the WX/WY/WZ and AX/AY/AZ triads are required, MX/MY/MZ come as
a triad or not at all (Acme's x and y are canonical y and x, so converting needs whole
triads), DEPTH, FANG, STN and POS are optional.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import pyarrow as pa
import pyarrow.compute as pc
from pydantic import ValidationError

from pipeline.plugin import (
    CURVES,
    SOURCE_LINE,
    Claim,
    Conventions,
    InputFileError,
    RawSamples,
    WellMetadata,
    conversion_factor,
    to_canonical,
)

MAGIC = "ACME GYROLOG v"
VERSION = "2"
END_OF_HEADER = "DATA"
NO_VALUE = "-"
DIGITS = 15
"""Significant digits the writer keeps: the format's precision (relative 5e-15)."""
Number = TypeVar("Number", int, float)


@dataclass(frozen=True)
class Channel:
    """An Acme channel: the canonical column it becomes and its unit in the file (``None``
    for counters)."""

    column: str
    unit: str | None


CHANNELS: dict[str, Channel] = {
    "T": Channel("time", "s"),
    "DEPTH": Channel("md", "ft"),
    "FANG": Channel("frame_angle", "rad"),
    **{f"W{a.upper()}": Channel(f"gyro_{a}", "deg/s") for a in "xyz"},
    **{f"A{a.upper()}": Channel(f"acc_{a}", "g") for a in "xyz"},
    **{f"M{a.upper()}": Channel(f"mag_{a}", "uT") for a in "xyz"},
    "STN": Channel("station", None),
    "POS": Channel("position", None),
}
"""Acme channel name → canonical column and the unit Acme records it in (Acme's own axes)."""

CONVENTIONS = Conventions(
    axes=("y", "x", "-z"),  # canonical x = Acme y, canonical y = Acme x, Acme z up-hole
    accelerometer="specific_force",  # a tool at rest reads −g
    frame_angle_direction="counterclockwise",
)
"""Acme's axes and signs. Every part is its own inverse (a symmetric signed permutation,
sign flips, a reversed angle), so :func:`to_canonical` also converts canonical → Acme."""

REQUIRED = ("T", "WX", "WY", "WZ", "AX", "AY", "AZ")
TRIADS = (("WX", "WY", "WZ"), ("AX", "AY", "AZ"), ("MX", "MY", "MZ"))
WELL_KEYS = {
    "WELL": "well",
    "SERIAL": "tool_serial",
    "LAT": "latitude",
    "LON": "longitude",
    "DATE": "survey_date",
}
"""Header key → :class:`WellMetadata` field."""


@dataclass(frozen=True)
class Header:
    """What the header declares: well metadata, channels and the first data line (0-based)."""

    well: WellMetadata
    channels: list[str]
    data_start: int


def sniff(path: Path) -> Claim:
    """By content: the file starts with the magic ``ACME GYROLOG v`` (any version)."""
    try:
        with path.open("rb") as fh:
            magic = fh.read(len(MAGIC))
    except OSError:
        return Claim.NO
    return Claim.CONTENT if magic == MAGIC.encode() else Claim.NO


def read_samples(path: Path) -> tuple[pa.Table, WellMetadata]:
    """RawSamples in canonical units and frame (s, m, deg, deg/h, m/s², nT), plus
    ``source_line`` (1-based file line of each sample), and the header's well metadata.

    Raises :class:`InputFileError` naming the file and line of any malformed part.
    """
    lines = _lines(path)
    header = _header(path, lines)
    rows: list[list[str]] = []
    line_numbers: list[int] = []
    for index in range(header.data_start, len(lines)):
        cells = lines[index].split()
        if not cells:
            continue
        if len(cells) != len(header.channels):
            raise InputFileError(
                path,
                f"{len(cells)} values, expected {len(header.channels)} "
                f"(one per channel: {' '.join(header.channels)})",
                line=index + 1,
            )
        rows.append(cells)
        line_numbers.append(index + 1)
    if not rows:
        raise InputFileError(path, "no samples after DATA", line=header.data_start)

    columns: dict[str, pa.Array] = {}
    for j, name in enumerate(header.channels):
        channel = CHANNELS[name]
        texts = [row[j] for row in rows]
        quantity = CURVES[channel.column].quantity
        if channel.unit is None or quantity is None:
            columns[channel.column] = pa.array(
                _parse(path, texts, line_numbers, name, int, nullable=True), pa.int64()
            )
        else:
            values = pa.array(_parse(path, texts, line_numbers, name, float), pa.float64())
            columns[channel.column] = pc.multiply(values, conversion_factor(channel.unit, quantity))
    contract = RawSamples.compiled()
    data: dict[str, Any] = {c.name: columns[c.name] for c in contract.columns if c.name in columns}
    data[SOURCE_LINE] = pa.array(line_numbers, pa.int64())
    return to_canonical(contract.make_table(data), CONVENTIONS), header.well


def write_samples(table: pa.Table, path: Path, well: WellMetadata) -> None:
    """Write a canonical RawSamples table in Acme's units and axes, with the well's name,
    tool serial, latitude, longitude and survey date in the header."""
    RawSamples.validate_table(table)
    vendor = to_canonical(table, CONVENTIONS)  # canonical → Acme (see CONVENTIONS)
    channels = [name for name, ch in CHANNELS.items() if ch.column in vendor.column_names]
    missing = [name for name in REQUIRED if name not in channels]
    if missing:
        raise ValueError(f"Acme GyroLog needs channel(s) {', '.join(missing)}")
    header = [MAGIC + VERSION]
    for key, field in WELL_KEYS.items():
        value = getattr(well, field)
        if value is not None:
            text = str(value)  # floats: shortest exact repr; dates: ISO 8601
            if "\n" in text or "\r" in text:
                raise ValueError(f"well {field} {text!r}: a header value is one line")
            header.append(f"{key}={text}")
    header += ["CHANNELS=" + " ".join(channels), END_OF_HEADER]

    cells: list[list[str]] = []
    for name in channels:
        channel = CHANNELS[name]
        column = vendor.column(channel.column)
        quantity = CURVES[channel.column].quantity
        if channel.unit is None or quantity is None:
            cells.append([NO_VALUE if v is None else str(v) for v in column.to_pylist()])
            continue
        if column.null_count:
            raise ValueError(f"column {channel.column!r} has missing values; Acme has no NaN")
        values = pc.divide(column, conversion_factor(channel.unit, quantity))
        cells.append([f"{v:.{DIGITS}g}" for v in values.to_pylist()])
    rows = (" ".join(row) for row in zip(*cells, strict=True))
    path.write_text("\n".join([*header, *rows]) + "\n", encoding="utf-8")


def _lines(path: Path) -> list[str]:
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise InputFileError(path, f"not UTF-8 text: {exc.reason}", line=line) from None
    return [line.removesuffix("\r") for line in text.split("\n")]


def _header(path: Path, lines: list[str]) -> Header:
    first = lines[0].strip()
    if not first.startswith(MAGIC):
        raise InputFileError(
            path, f"not an Acme GyroLog file: expected {MAGIC + VERSION!r}, got {first!r}", line=1
        )
    if first[len(MAGIC) :] != VERSION:
        raise InputFileError(
            path, f"Acme GyroLog version {first[len(MAGIC) :]!r}: this reader reads v2", line=1
        )
    well = WellMetadata()
    channels: list[str] | None = None
    seen: dict[str, int] = {}
    for number, text in enumerate(lines[1:], start=2):
        line = text.strip()
        if line == END_OF_HEADER:
            if channels is None:
                raise InputFileError(path, "no CHANNELS line before DATA", line=number)
            return Header(well, channels, number)
        key, sep, value = (part.strip() for part in line.partition("="))
        if not sep or not key:
            raise InputFileError(
                path,
                f"expected KEY=VALUE or {END_OF_HEADER} in the header, got {line!r}",
                line=number,
            )
        if key in seen:
            raise InputFileError(
                path, f"{key} given twice (first on line {seen[key]})", line=number
            )
        seen[key] = number
        if key == "CHANNELS":
            channels = _channels(path, value.split(), line=number)
        elif key in WELL_KEYS:
            try:
                well = well.merged({WELL_KEYS[key]: value})
            except ValidationError as exc:
                message = exc.errors()[0]["msg"]
                raise InputFileError(path, f"{key}={value}: {message}", line=number) from None
    raise InputFileError(path, f"the header has no {END_OF_HEADER} line", line=len(lines))


def _channels(path: Path, names: list[str], line: int) -> list[str]:
    for i, name in enumerate(names):
        if name not in CHANNELS:
            raise InputFileError(
                path, f"unknown channel {name!r} (Acme channels: {' '.join(CHANNELS)})", line=line
            )
        if name in names[:i]:
            raise InputFileError(path, f"channel {name} listed twice", line=line)
    missing = [name for name in REQUIRED if name not in names]
    if missing:
        raise InputFileError(path, f"missing channel(s) {' '.join(missing)}", line=line)
    for triad in TRIADS:
        present = [name for name in triad if name in names]
        if present and len(present) < len(triad):
            raise InputFileError(
                path,
                f"channels {' '.join(triad)} come together, got only {' '.join(present)}",
                line=line,
            )
    return names


def _parse(
    path: Path,
    texts: list[str],
    line_numbers: list[int],
    channel: str,
    kind: Callable[[str], Number],
    *,
    nullable: bool = False,
) -> list[Number | None]:
    """Each text as ``kind`` (``-`` → None where ``nullable``); errors name line and channel."""
    values: list[Number | None] = []
    for text, line in zip(texts, line_numbers, strict=True):
        if nullable and text == NO_VALUE:
            values.append(None)
            continue
        try:
            values.append(kind(text))
        except ValueError:
            expected = f"an integer or {NO_VALUE!r}" if nullable else "a number"
            raise InputFileError(
                path, f"{text!r} is not {expected}", line=line, column=channel
            ) from None
    return values

"""Text and header of a LAS file: the file split at its data title, decoded, and the header
sections read as items.

* **Header** — the lines before the ``~A`` (LAS 3: ``~Log_Data``) title are split into
  sections at their ``~`` titles; each item line of ``~V``, ``~W``, ``~C`` and ``~P`` (LAS 3:
  ``~Log_Definition``, ``~Log_Parameter``) is parsed with lasio's header grammar
  (:func:`lasio.reader.read_header_line`: ``MNEM.UNIT  VALUE : DESCRIPTION``), keeping the
  raw text and line of every item (``lasio.read`` turns a UWI ``0012`` into ``12``, and
  even with ``ignore_data`` scans the whole file: 4 s for 100 MB). LAS 1.x ``~W`` items
  other than STRT/STOP/STEP/NULL hold their value after the colon, as the 1.2 standard
  (and lasio) says. Other sections (``~O``, unknown ones) are skipped. An item line longer
  than :data:`~pipeline.io.limits.HEADER_LINE_MAX` characters, or its mnemonic, unit, value
  or description than :data:`~pipeline.io.limits.TEXT_MAX`, is refused at its line.
* **Text** — UTF-16 with a byte-order mark, or without one when every other byte of the
  head is a NUL (as Windows tools write it), is transcoded to UTF-8 first (lasio cannot read
  it); then UTF-8 (BOM or not) when the bytes are valid UTF-8, else Windows-1252 (Latin-1
  plus ``°``, ``µ``…); a byte neither accepts, or a NUL byte, is an error naming its line.
"""

from __future__ import annotations

import math
import mmap
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from pipeline.errors import InputFileError, WrongKindError
from pipeline.io.limits import HEADER_LINE_MAX, MAX_COLUMNS, too_long

SNIFF_BYTES = 64 * 1024
BOM = b"\xef\xbb\xbf"
UTF16_BOMS = {b"\xff\xfe": "utf-16-le", b"\xfe\xff": "utf-16-be"}
SHOWN = 8

Role = Literal["version", "well", "curves", "parameter", "data"]
SECTION_NAMES: dict[Role, str] = {
    "version": "Version",
    "well": "Well",
    "curves": "Curves",
    "parameter": "Parameter",
    "data": "Data",
}
"""lasio's name of each section role (its header grammar depends on it)."""

_DATA_TITLE = re.compile(rb"^[ \t]*~(?:A|LOG_DATA)", re.IGNORECASE | re.MULTILINE)
_INCLINOMETRY_TITLE = re.compile(rb"^[ \t]*~INCLINOMETRY_DATA", re.IGNORECASE | re.MULTILINE)
_NEXT_TITLE = re.compile(rb"^[ \t]*~", re.MULTILINE)
LOG = "LOG"
INCLINOMETRY = "INCLINOMETRY"
"""LAS 3 data sets read: the log (``~Log_Definition``, ``~Log_Data``; LAS 2 ``~C``, ``~A``)
and, in a file without one, the directional survey (``~Inclinometry_Definition``,
``~Inclinometry_Data``)."""
NUMBER = r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$"


@dataclass(frozen=True)
class Item:
    """One header line: upper-case mnemonic, unit, value and description as written."""

    mnemonic: str
    unit: str
    value: str
    descr: str
    line: int


@dataclass(frozen=True)
class Header:
    """The header sections read."""

    version: float
    wrapped: bool
    delimiter: str
    """SPACE, COMMA or TAB (LAS 3 ``DLM``)"""
    well: list[Item]
    parameters: list[Item]
    curves: list[Item]

    def find(self, path: Path, *mnemonics: str) -> Item | None:
        """The first item with a value among ``mnemonics`` (preferred first), in ~Well then
        ~Parameter. One mnemonic given twice with different values (:func:`_same`), in one
        section or one in each (a ~Parameter item does not override the ~Well's), is an
        error."""
        for mnemonic in mnemonics:
            items = [i for i in self.well + self.parameters if i.mnemonic == mnemonic and i.value]
            other = next((i for i in items if not _same(i, items[0])), None)
            if other is not None:
                raise InputFileError(
                    path,
                    f"{mnemonic} is given twice with different values "
                    f"({items[0].value!r} on line {items[0].line}, {other.value!r})",
                    line=other.line,
                )
        for section in (self.well, self.parameters):
            for mnemonic in mnemonics:
                found = next((i for i in section if i.mnemonic == mnemonic and i.value), None)
                if found is not None:
                    return found
        return None


def _same(a: Item, b: Item) -> bool:
    """Whether two items of one mnemonic say the same: the same text, or the same number in
    the same unit (``0`` and ``0.00 DEG``)."""
    if a.value == b.value:
        return True
    try:
        return float(a.value) == float(b.value) and a.unit.upper() == b.unit.upper()
    except ValueError:
        return False


@dataclass(frozen=True)
class Source:
    """A LAS file split at its data title: the header lines, and the file's bytes with the
    offset of the data (the line after the title), not copied."""

    header: list[str]
    title_line: int
    """1-based line of the data section title (0: there is none)"""
    raw: bytes | mmap.mmap
    """the file's bytes, mapped into memory when they need no transcoding (:func:`load`);
    an ~Inclinometry_Data section's file up to its end"""
    start: int
    data_set: str = LOG
    """the LAS 3 data set read (:data:`LOG` or :data:`INCLINOMETRY`)"""


# ------------------------------------------------------------------------- file text


def load(path: Path) -> Source:
    """The file's header lines (decoded) and data bytes (UTF-16 transcoded to UTF-8). A
    large file that needs no transcoding is mapped into memory, not copied."""
    try:
        mapped = _mapped(path)
        if mapped is not None:
            return _split(path, mapped)
        raw = path.read_bytes()
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc.strerror or exc}") from None
    codec = utf16_codec(raw)
    if codec is not None:
        raw = _from_utf16(path, raw, codec)
    raw = raw.removeprefix(BOM)
    if not raw or raw.isspace():
        raise InputFileError(path, "the file is empty")
    head = raw[:SNIFF_BYTES]
    if head.count(b"\r") != head.count(b"\r\n"):  # old Mac line ends: lone CRs
        raw = raw.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return _split(path, raw)


def _mapped(path: Path) -> mmap.mmap | None:
    """The file mapped into memory when it is larger than :data:`SNIFF_BYTES` and its head
    has text but neither a byte-order mark, UTF-16 nor lone CR line ends; else None."""
    with path.open("rb") as fh:
        head = fh.read(SNIFF_BYTES)
        if len(head) < SNIFF_BYTES or head.startswith(BOM) or utf16_codec(head) is not None:
            return None
        if head.isspace() or head.count(b"\r") != head.count(b"\r\n"):
            return None
        return mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)


def _split(path: Path, raw: bytes | mmap.mmap) -> Source:
    """``raw`` split at its data section title: the log's, else a LAS 3 file's
    ~Inclinometry_Data (``raw`` then ends where that section does)."""
    title = _DATA_TITLE.search(raw)
    data_set = LOG
    if title is None and (title := _INCLINOMETRY_TITLE.search(raw)) is not None:
        data_set = INCLINOMETRY
        after = _NEXT_TITLE.search(raw, title.end())
        raw = raw[: after.start()] if after is not None else raw
    if title is None:
        lines = split_lines(decode(path, raw[:], 1))
        if not any(line.lstrip().startswith("~") for line in lines):
            raise InputFileError(
                path, "not a LAS file: no section title (~Version, ~Well, ~Curve, ~A)"
            )
        return Source(lines, 0, b"", 0)
    end = raw.find(b"\n", title.start())
    lines = split_lines(decode(path, raw[: title.start()], 1))
    return Source(lines[:-1], len(lines), raw, len(raw) if end < 0 else end + 1, data_set)


def utf16_codec(head: bytes) -> str | None:
    """``utf-16-le``/``-be`` when ``head`` starts with a UTF-16 byte-order mark or, without
    one, when NULs fill every other byte (ASCII text in UTF-16); else None."""
    for bom, codec in UTF16_BOMS.items():
        if head.startswith(bom):
            return codec
    sample = head[:4096]
    pairs = len(sample) // 2
    if pairs < 8 or b"\0" not in sample:
        return None
    even, odd = sample[0 : 2 * pairs : 2].count(0), sample[1 : 2 * pairs : 2].count(0)
    if odd > 0.3 * pairs and even < 0.02 * pairs:
        return "utf-16-le"
    if even > 0.3 * pairs and odd < 0.02 * pairs:
        return "utf-16-be"
    return None


def _from_utf16(path: Path, raw: bytes, codec: str) -> bytes:
    """UTF-16 bytes as UTF-8 (the byte-order mark dropped)."""
    try:
        text = raw.decode(codec)
    except UnicodeDecodeError as exc:
        line = 1 + raw[: exc.start].decode(codec, errors="replace").count("\n")
        raise InputFileError(
            path, f"the file looks like {codec.upper()} but is not", line
        ) from None
    return text.removeprefix("\ufeff").encode()


def text_head(head: bytes) -> bytes:
    """The head of a file as UTF-8 bytes (a UTF-16 head transcoded; a cut character
    dropped), for sniffing."""
    codec = utf16_codec(head)
    if codec is None:
        return head
    return head.decode(codec, errors="ignore").removeprefix("\ufeff").encode()


def decode(path: Path, data: bytes, first_line: int) -> str:
    """UTF-8 text if ``data`` is valid UTF-8, else Windows-1252; ``data`` starts on file
    line ``first_line``."""
    if b"\0" in data:
        line = first_line + data[: data.index(b"\0")].count(b"\n")
        raise InputFileError(path, "NUL byte: this is not a LAS text file", line=line)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        pass
    try:
        return data.decode("cp1252")
    except UnicodeDecodeError as exc:
        line = first_line + data[: exc.start].count(b"\n")
        raise InputFileError(
            path,
            f"byte 0x{data[exc.start]:02x} is neither UTF-8 nor Windows-1252 (Latin-1) text",
            line=line,
        ) from None


def split_lines(text: str) -> list[str]:
    """Lines of ``text`` split at LF, CRLF or a lone CR."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


# ---------------------------------------------------------------------------- header


def parse_header(path: Path, lines: list[str], data_set: str = LOG) -> Header:
    """The ~Version, ~Well and ``data_set``'s definition and parameter sections."""
    sections: dict[Role, list[Item]] = {role: [] for role in SECTION_NAMES}
    role: Role | None = None
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if text.startswith("~"):
            role = section_role(text, data_set)
        elif role is not None:
            if role == "curves" and len(sections[role]) == MAX_COLUMNS:
                raise InputFileError(path, f"more than {MAX_COLUMNS:,} curves: refused", number)
            sections[role].append(_bounded(path, text, number, role))
    version, wrapped, delimiter = _version(path, sections["version"])
    well = sections["well"]
    if version < 2:
        well = [_las1_well_item(item) for item in well]
    return Header(version, wrapped, delimiter, well, sections["parameter"], sections["curves"])


def require_curves(path: Path, header: Header) -> None:
    """A survey kind needs the ~Curve section (a log without one has unnamed columns): else
    a :class:`WrongKindError` (the file may still be read as a log)."""
    if not header.curves:
        raise WrongKindError(path, "no curves: the ~Curve section is missing or empty", found="log")


def section_role(title: str, data_set: str = LOG) -> Role | None:
    """The role of a section from its ``~`` title when ``data_set`` is read (None: a
    section not read)."""
    name = title[1:].strip().upper()
    if data_set != LOG:
        suffixes: tuple[tuple[str, Role], ...] = (
            ("DEFINITION", "curves"),
            ("PARAMETER", "parameter"),
            ("DATA", "data"),
        )
        for suffix, role in suffixes:
            if name.startswith(f"{data_set}_{suffix}"):
                return role
        return "version" if name.startswith("V") else "well" if name.startswith("W") else None
    if name.startswith("LOG_DEFINITION") or (name.startswith("C") and "_" not in name):
        return "curves"
    if name.startswith("LOG_PARAMETER") or (name.startswith("P") and "_" not in name):
        return "parameter"
    if name.startswith(("A", "LOG_DATA")):
        return "data"
    if name.startswith("V"):
        return "version"
    if name.startswith("W"):
        return "well"
    return None


def _bounded(path: Path, text: str, number: int, role: Role) -> Item:
    """The item of a header line, refused at its line for its length (:func:`item_problem`)."""
    item = _item(path, text, number, role)
    if (reason := item_problem(item, text)) is not None:
        raise InputFileError(path, reason, line=number)
    return item


def item_problem(item: Item, line: str) -> str | None:
    """Why a header item (on ``line``) is refused for its length, else None: its mnemonic,
    unit, value or description over :data:`~pipeline.io.limits.TEXT_MAX` characters, or
    the line over :data:`~pipeline.io.limits.HEADER_LINE_MAX` (a megabyte well name was read
    and copied into every table, header and file written from it)."""
    parts = {"mnemonic": item.mnemonic, "unit": item.unit, "value": item.value}
    reasons = [too_long(part, f"the {what} of {item.mnemonic!r}") for what, part in parts.items()]
    reasons += [
        too_long(item.descr, f"the description of {item.mnemonic!r}"),
        too_long(line, f"the header line of {item.mnemonic!r}", HEADER_LINE_MAX),
    ]
    return next((reason for reason in reasons if reason is not None), None)


def _item(path: Path, text: str, number: int, role: Role) -> Item:
    from lasio.reader import read_header_line  # imported on use: lasio is slow to import

    try:
        parsed = read_header_line(text, section_name=SECTION_NAMES[role])
    except AttributeError:  # lasio's grammar does not match the line
        raise InputFileError(
            path,
            f"cannot read header line {text!r}: expected 'MNEMONIC.UNIT  VALUE : DESCRIPTION'",
            line=number,
        ) from None
    unit = parsed["unit"]
    if len(unit) >= 2 and unit[0] + unit[-1] in ("[]", "()"):  # as lasio strips them
        unit = unit[1:-1].strip()
    return Item(parsed["name"].upper(), unit, parsed["value"], parsed["descr"], number)


def _las1_well_item(item: Item) -> Item:
    """A LAS 1.x ~Well item holds its value after the colon (except STRT/STOP/STEP/NULL);
    a value written on one side only is taken where it is."""
    if item.mnemonic in ("STRT", "STOP", "STEP", "NULL") or not item.descr:
        return item
    return Item(item.mnemonic, item.unit, item.descr, item.value, item.line)


def _version(path: Path, items: list[Item]) -> tuple[float, bool, str]:
    """LAS version (2.0 if not given), whether the data are wrapped, the data delimiter."""

    def value(mnemonic: str, default: str) -> tuple[str, int]:
        found = [i for i in items if i.mnemonic == mnemonic and i.value]
        return (found[0].value.upper(), found[0].line) if found else (default, 0)

    vers, line = value("VERS", "2.0")
    version = float(vers) if re.fullmatch(r"[0-9]+(\.[0-9]*)?", vers) else 0.0
    if int(version) not in (1, 2, 3):
        raise InputFileError(path, f"VERS {vers!r}: not a LAS version (1.2, 2.0, 3.0)", line=line)
    wrap, line = value("WRAP", "NO")
    if wrap not in ("YES", "NO"):
        raise InputFileError(path, f"WRAP {wrap!r}: expected YES or NO", line=line)
    delimiter, line = value("DLM", "SPACE")
    if delimiter not in ("SPACE", "COMMA", "TAB"):
        raise InputFileError(path, f"DLM {delimiter!r}: expected SPACE, COMMA or TAB", line=line)
    return version, wrap == "YES", delimiter


def header_number(path: Path, item: Item) -> float:
    """The item's value as a number; a value past the float range (``1e309``, read as ±inf)
    is refused like a word."""
    if re.fullmatch(NUMBER, item.value):
        value = float(item.value)
        if math.isfinite(value):
            return value
        raise InputFileError(
            path, f"{item.mnemonic} {item.value!r} is too large for a number", line=item.line
        )
    raise InputFileError(path, f"{item.mnemonic} {item.value!r} is not a number", line=item.line)


def mnemonics(curves: list[Item]) -> str:
    names = [c.mnemonic for c in curves]
    more = f" and {len(names) - SHOWN} more" if len(names) > SHOWN else ""
    return ", ".join(names[:SHOWN]) + more

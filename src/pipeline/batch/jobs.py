"""The wells of a batch: from a manifest CSV or from a glob of input files.

A manifest is a CSV file with a header row. Column ``well_id`` names each well (it becomes
the well's output directory ``OUT/<well_id>/``, so no two ids may be equal up to case); one
column per pipeline input holds that input's file (relative paths are relative to the
manifest's directory); any other column must be a :class:`~pipeline.well.WellMetadata`
field (``latitude``, ``longitude``, ``elevation``, ``tool_serial``…) and overrides that
header field for the well. Empty cells leave a header field unset. Lines starting with
``#`` are comments.
"""

from __future__ import annotations

import csv
import glob
import io
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from pipeline.errors import GyropipeError
from pipeline.well import WellMetadata

WELL_ID_COLUMN = "well_id"
WELL_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}\Z")
LEDGER = "ledger.sqlite"
LEDGER_SIDECARS = ("-wal", "-shm", "-journal")
"""SQLite's files beside a ledger ``L``: ``L-wal``, ``L-shm``, ``L-journal``"""
SUMMARY_FILES = ("summary.json", "summary.csv", "fleet.html")
"""what each batch writes in the output directory: its summary table and the fleet page"""
RESERVED_NAMES = frozenset({LEDGER, *(LEDGER + s for s in LEDGER_SIDECARS), *SUMMARY_FILES})
"""Names the batch itself keeps in the output directory (lower case); no well may be called
so, up to case. (Its staging directory ``.gyropipe-batch`` starts with a dot, which no well
id does.)"""


_UP_TO_CASE = (
    " up to case: their output directories would collide on a case-insensitive file system"
)


class BatchConfigError(GyropipeError):
    """The batch cannot start: bad manifest, glob matching nothing, unusable ledger…"""


@dataclass(frozen=True)
class WellJob:
    """One well to process: its id, its input files by pipeline input name, and the header
    fields that override the pipeline's and the files' well metadata."""

    well_id: str
    inputs: Mapping[str, Path]
    well: WellMetadata


def jobs_from_manifest(
    manifest: Path, input_names: Sequence[str], defaults: WellMetadata
) -> list[WellJob]:
    """Read a manifest (module docstring). ``defaults`` (``--well``) apply to every well;
    a manifest cell overrides them. Raises :class:`BatchConfigError` naming file and line."""
    try:
        text = manifest.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise BatchConfigError(f"{manifest}: cannot read the manifest: {exc}") from None
    rows = [
        (number, cells)
        for number, cells in _records(text)
        if cells and any(c.strip() for c in cells) and not cells[0].lstrip().startswith("#")
    ]
    if not rows:
        raise BatchConfigError(f"{manifest}: empty manifest (expected a header row)")
    header_line, header = rows[0]
    columns = [c.strip() for c in header]
    _check_header(manifest, header_line, columns, input_names)
    base = manifest.parent
    jobs: list[WellJob] = []
    seen: dict[str, tuple[str, int]] = {}  # casefolded id → (id, line)
    for line, cells in rows[1:]:
        if len(cells) != len(columns):
            raise BatchConfigError(
                f"{manifest}:{line}: {len(cells)} cells, the header has {len(columns)}"
            )
        values = dict(zip(columns, (c.strip() for c in cells), strict=True))
        _check_text(values, f"{manifest}:{line}")
        well_id = _well_id(values.pop(WELL_ID_COLUMN), f"{manifest}:{line}")
        if (same := seen.get(well_id.casefold())) is not None:
            first, first_line = same
            raise BatchConfigError(
                f"{manifest}:{line}: well {well_id!r} already listed on line {first_line}"
                if first == well_id
                else f"{manifest}:{line}: well {well_id!r} equals well {first!r} of "
                f"{manifest}:{first_line}{_UP_TO_CASE}"
            )
        seen[well_id.casefold()] = (well_id, line)
        inputs: dict[str, Path] = {}
        for name in input_names:
            cell = values.pop(name)
            if not cell:
                raise BatchConfigError(f"{manifest}:{line}: well {well_id!r}: no file for {name!r}")
            try:
                inputs[name] = (base / cell).resolve()
            except (OSError, RuntimeError) as exc:  # a symlink loop (RuntimeError before 3.13)
                raise BatchConfigError(
                    f"{manifest}:{line}: well {well_id!r}: {name} {cell!r}: {exc}"
                ) from None
        overrides = {k: v for k, v in values.items() if v}
        try:
            well = defaults.merged(WellMetadata.model_validate(overrides))
        except ValidationError as exc:
            problems = "; ".join(
                f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors()
            )
            raise BatchConfigError(f"{manifest}:{line}: well {well_id!r}: {problems}") from None
        jobs.append(WellJob(well_id, inputs, well))
    if not jobs:
        raise BatchConfigError(f"{manifest}:{header_line}: no wells listed below the header")
    return jobs


def jobs_from_glob(
    pattern: str, input_names: Sequence[str], defaults: WellMetadata
) -> list[WellJob]:
    """One well per file matching ``pattern`` (recursive ``**`` allowed), its id the file
    name without extension. Only for pipelines with exactly one input."""
    if len(input_names) != 1:
        raise BatchConfigError(
            f"--inputs works for pipelines with one input; this one has "
            f"{', '.join(input_names) or 'none'}: give a --manifest"
        )
    files = sorted(Path(p) for p in glob.glob(pattern, recursive=True) if Path(p).is_file())
    if not files:
        raise BatchConfigError(f"--inputs {pattern!r} matches no file")
    jobs: list[WellJob] = []
    seen: dict[str, tuple[str, Path]] = {}  # casefolded id → (id, file)
    for path in files:
        shown = str(path) if str(path).isprintable() else repr(str(path))  # one line
        well_id = _well_id(path.stem, shown)
        if (same := seen.get(well_id.casefold())) is not None:
            first, first_path = same
            what = (
                f"would both be well {well_id!r}"
                if first == well_id
                else f"would be wells {first!r} and {well_id!r}, equal{_UP_TO_CASE}"
            )
            raise BatchConfigError(
                f"--inputs {pattern!r}: {first_path} and {path} {what}: use a --manifest"
            )
        seen[well_id.casefold()] = (well_id, path)
        jobs.append(WellJob(well_id, {input_names[0]: path.resolve()}, defaults))
    return jobs


def _check_header(
    manifest: Path, line: int, columns: list[str], input_names: Sequence[str]
) -> None:
    fields = list(WellMetadata.model_fields)
    allowed = (
        f"{WELL_ID_COLUMN}, inputs {', '.join(input_names)}, header fields {', '.join(fields)}"
    )
    duplicates = sorted({c for c in columns if columns.count(c) > 1})
    if duplicates:
        raise BatchConfigError(f"{manifest}:{line}: duplicate columns {duplicates}")
    missing = [c for c in (WELL_ID_COLUMN, *input_names) if c not in columns]
    if missing:
        raise BatchConfigError(
            f"{manifest}:{line}: missing column(s) {', '.join(missing)} (columns: {allowed})"
        )
    unknown = [
        c for c in columns if c not in fields and c not in input_names and c != WELL_ID_COLUMN
    ]
    if unknown:
        raise BatchConfigError(
            f"{manifest}:{line}: unknown column(s) {', '.join(unknown)} (columns: {allowed})"
        )


def _records(text: str) -> Iterator[tuple[int, list[str]]]:
    """The manifest's CSV records, each with the line it starts on (a quoted cell may hold
    a line break: kept in the cell, refused by :func:`_check_text`, never joined away)."""
    reader = csv.reader(io.StringIO(text, newline=""))
    start = 1
    for cells in reader:
        yield start, cells
        start = reader.line_num + 1


def _check_text(values: Mapping[str, str], where: str) -> None:
    """Refuse a cell holding a NUL byte or a line break (no file name, id or header field
    can hold one)."""
    for column, cell in values.items():
        if "\x00" in cell:
            raise BatchConfigError(f"{where}: column {column!r}: a NUL byte in {cell!r}")
        if "\n" in cell or "\r" in cell:
            raise BatchConfigError(
                f"{where}: column {column!r}: a line break in {cell!r} (a quoted cell spans "
                "lines): a manifest cell is one line"
            )


def _well_id(text: str, where: str) -> str:
    if not WELL_ID.match(text):
        raise BatchConfigError(
            f"{where}: well id {text!r} is not a plain directory name (letters, digits, '.', "
            "'_', '-'; starting with a letter or digit)"
        )
    if text.casefold() in RESERVED_NAMES:
        raise BatchConfigError(
            f"{where}: well id {text!r} names a file the batch keeps in its output directory "
            f"(reserved, up to case: {', '.join(sorted(RESERVED_NAMES))})"
        )
    return text

"""Conversion of any readable input to any writable format, normalised on the way.

The kind of table read is asked for (``stations``, ``samples``, ``readings``, ``log``) or
found (``auto``): the survey kinds first (a file that is one reads as one, in canonical
units); a file that no reader takes for a survey, because it lacks a survey's curves (a
well log), is read as a ``log`` when a reader reads logs (LAS). A file that is a survey but
is broken is reported as such, never read as a log instead. A file that is not the kind
asked for is reported in a few words, with the kind it can be read as. A file that
``auto`` cannot read is named in one line: the reader that took it and its first kind's
error, or what the file looks like (a reader's description of it) and that no reader reads
it as a log.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa

from pipeline.atomic import atomic_path
from pipeline.contracts import SOURCE_LINE, TableContract
from pipeline.errors import (
    GyropipeError,
    InputFileError,
    ReaderChoiceError,
    ReaderOptionsError,
    WrongKindError,
    bounded,
)
from pipeline.hashing import file_kind
from pipeline.registry import Registry, WriterDef
from pipeline.well import WellMetadata, attach

SURVEY_KINDS = ("stations", "samples", "readings")
KINDS = (*SURVEY_KINDS, "log")


@dataclass(frozen=True)
class Converted:
    """What :func:`convert` wrote: the table (without ``source_line``), where, and the
    kind it was read as."""

    table: pa.Table
    target: Path
    kind: str


def writer_for(registry: Registry, path: Path) -> WriterDef:
    """The registered writer whose extension matches ``path``."""
    ext = path.suffix.lstrip(".").lower()
    for writer, _ in registry.writers.values():
        if writer.extension == ext:
            return writer
    known = ", ".join(sorted(f".{w.extension}" for w, _ in registry.writers.values()))
    raise ValueError(f"no writer for {path.name!r} (extensions: {known})")


def read_any(
    registry: Registry,
    path: Path,
    *,
    kind: str,
    reader: str,
    options: dict[str, Any],
    well: WellMetadata | None = None,
) -> tuple[pa.Table, WellMetadata]:
    """Read ``path`` as ``kind`` (``auto``: see the module docstring), returning the table
    and the file's well metadata; reader options marked as well defaults come from
    ``well``."""
    table, header, _ = read_kind(
        registry, path, kind=kind, reader=reader, options=options, defaults=well
    )
    return table, header


def read_kind(
    registry: Registry,
    path: Path,
    *,
    kind: str,
    reader: str,
    options: dict[str, Any],
    defaults: WellMetadata | None = None,
) -> tuple[pa.Table, WellMetadata, str]:
    """:func:`read_any`, also returning the kind read."""
    if not path.is_file():
        try:
            mode = path.stat().st_mode
        except OSError:  # missing, a dangling link, a loop
            raise InputFileError(path, "no such file") from None
        raise InputFileError(path, f"not a regular file ({file_kind(mode)}): give a file")
    if kind != "auto":
        try:
            table, well = registry.read(path, kind, reader=reader, options=options, well=defaults)
        except WrongKindError as exc:
            other = _readable_as(registry, path, kind, reader, options)
            if other is None:
                raise
            raise WrongKindError(exc.path, f"{exc.reason} — use --kind {other}", exc.line) from None
        return table, well, kind
    failures: list[tuple[str, str, GyropipeError]] = []
    wrong: list[str] = []
    for candidate in SURVEY_KINDS:
        try:
            chosen = registry.reader_for(path, candidate, reader)
        except ReaderChoiceError:
            continue
        try:
            table, well = registry.read(
                path, candidate, reader=chosen.name, options=options, well=defaults
            )
        except ReaderOptionsError:
            raise
        except WrongKindError as exc:
            wrong.append(exc.reason)
            continue
        except GyropipeError as exc:
            failures.append((candidate, chosen.name, exc))
            continue
        missing = _missing_columns(chosen.kinds[candidate], table)
        if missing:  # a reader of tables of any kind (Parquet) read another kind's table
            wrong.append(f"{chosen.name} table without column {', '.join(missing)}")
            continue
        return table, well, candidate
    if len(failures) == 1:  # the one kind the file is, broken: its own error
        raise failures[0][2]
    if failures:  # a reader of several kinds took it and read none: the first one's error
        kinds = ", ".join(kind for kind, _, _ in failures)
        first, name, error = failures[0]
        reason = error.reason if isinstance(error, InputFileError) else str(error)
        line = error.line if isinstance(error, InputFileError) else 0
        raise InputFileError(
            path, f"a {name} file that reads as none of {kinds}; as {first}: {reason}", line
        )
    try:  # not a survey: a log, if a reader reads it as one
        chosen = registry.reader_for(path, "log", reader)
    except ReaderChoiceError:
        pass
    else:
        table, well = registry.read(path, "log", reader=chosen.name, options=options, well=defaults)
        return table, well, "log"
    if wrong:
        raise InputFileError(path, f"not a survey file and no reader reads it as a log: {wrong[0]}")
    kinds = ", ".join(KINDS[:-1]) + f" or {KINDS[-1]}"
    raise InputFileError(path, f"cannot be read: no installed reader recognises it as {kinds}")


def _missing_columns(contract: type[TableContract], table: pa.Table) -> list[str]:
    """Required columns of ``contract`` that ``table`` lacks."""
    columns = contract.compiled().columns
    return [c.name for c in columns if c.required and c.name not in table.column_names]


def _readable_as(
    registry: Registry, path: Path, kind: str, reader: str, options: dict[str, Any]
) -> str | None:
    """Another kind the file reads as, if any (the kinds in order, the log last)."""
    for other in KINDS:
        if other == kind:
            continue
        try:
            table, _ = registry.read(path, other, reader=reader, options=options)
        except GyropipeError:
            continue
        if not _missing_columns(registry.reader_for(path, other, reader).kinds[other], table):
            return other
    return None


def convert(
    registry: Registry,
    source: Path,
    target: Path,
    *,
    kind: str = "auto",
    reader: str = "auto",
    options: dict[str, Any] | None = None,
    well: WellMetadata | None = None,
) -> Converted:
    """Read ``source`` and write it to ``target`` (format from its extension, atomically)."""
    writer = writer_for(registry, target)
    table, header, read_as = read_kind(
        registry, source, kind=kind, reader=reader, options=options or {}
    )
    merged = header.merged(well) if well is not None else header
    if SOURCE_LINE in table.column_names:  # line numbers of the source mean nothing in the copy
        table = table.drop_columns([SOURCE_LINE])
    try:
        with atomic_path(target) as tmp:
            writer.write(attach(table, merged), tmp, merged)
    except ValueError as exc:  # a table the format cannot hold: say which file, and where to
        raise ValueError(
            f"{source}: the {read_as} read cannot be written to {target.name} "
            f"(writer {writer.name!r}): {bounded(str(exc))}"
        ) from exc
    return Converted(table, target, read_as)

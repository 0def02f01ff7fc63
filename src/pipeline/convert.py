"""Conversion of any readable input to any writable format, normalised on the way."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pyarrow as pa

from pipeline.atomic import atomic_path
from pipeline.contracts import SOURCE_LINE
from pipeline.errors import GyropipeError, InputFileError, ReaderChoiceError, ReaderOptionsError
from pipeline.registry import Registry, WriterDef
from pipeline.well import WellMetadata, attach

KINDS = ("stations", "samples", "readings")


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
    """Read ``path`` as ``kind`` (``auto``: each kind the reader knows, stations first),
    returning the table of the first kind that reads and the file's well metadata; reader
    options marked as well defaults come from ``well``."""
    if not path.is_file():
        raise InputFileError(path, "no such file")
    kinds = KINDS if kind == "auto" else (kind,)
    problems: list[str] = []
    for candidate in kinds:
        try:
            chosen = registry.reader_for(path, candidate, reader)
        except ReaderChoiceError as exc:
            problems.append(f"as {candidate}: {exc}")
            continue
        try:
            return registry.read(path, candidate, reader=chosen.name, options=options, well=well)
        except ReaderOptionsError:
            raise
        except GyropipeError as exc:
            if kind != "auto":
                raise
            problems.append(f"as {candidate} ({chosen.name}): {exc}")
    raise InputFileError(path, "cannot be read: " + "; ".join(problems))


def convert_file(
    registry: Registry,
    source: Path,
    target: Path,
    *,
    kind: str = "auto",
    reader: str = "auto",
    options: dict[str, Any] | None = None,
    well: WellMetadata | None = None,
) -> tuple[pa.Table, Path]:
    """Read ``source`` and write it to ``target`` (format from its extension, atomically)."""
    writer = writer_for(registry, target)
    table, header = read_any(registry, source, kind=kind, reader=reader, options=options or {})
    merged = header.merged(well) if well is not None else header
    if SOURCE_LINE in table.column_names:  # line numbers of the source mean nothing in the copy
        table = table.drop_columns([SOURCE_LINE])
    with atomic_path(target) as tmp:
        writer.write(attach(table, merged), tmp, merged)
    return table, target

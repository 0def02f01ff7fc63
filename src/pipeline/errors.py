"""Typed errors. Every failure a user can cause names where it happened and what was expected."""

from __future__ import annotations

import contextlib
import difflib
import os
import re
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any


def did_you_mean(name: str, known: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` naming the known names closest to ``name`` ("" if none)."""
    close = difflib.get_close_matches(name, list(known), n=3)
    return f"; did you mean {', '.join(map(repr, close))}?" if close else ""


LONG_QUOTE = 300
"""Characters of quoted text (a cell, a header value, a unit: what the file wrote) past
which a message shows only its ends (:func:`bounded`)."""
_LONG_QUOTE = re.compile(f"'[^'\\n]{{{LONG_QUOTE},}}'|\"[^\"\\n]{{{LONG_QUOTE},}}\"")


def bounded(message: str) -> str:
    """``message`` with each quoted text longer than :data:`LONG_QUOTE` characters shown by
    its ends and length (``'xxxx…xxxx' (1,000,000 characters)``): a megabyte cell or header
    value a file holds makes a one-line error, not a megabyte one."""

    def ends(match: re.Match[str]) -> str:
        text = match.group()
        quote, inner = text[0], text[1:-1]
        return f"{quote}{inner[:60]}…{inner[-20:]}{quote} ({len(inner):,} characters)"

    return _LONG_QUOTE.sub(ends, message) if len(message) > LONG_QUOTE else message


class GyropipeError(Exception):
    """Base of every error gyropipe raises on purpose (its text :func:`bounded`)."""

    def __init__(self, *args: object) -> None:
        super().__init__(*(bounded(a) if isinstance(a, str) else a for a in args))


@dataclass(frozen=True)
class Location:
    """A place in a text file: 1-based line and column (0 means unknown)."""

    file: str
    line: int = 0
    column: int = 0

    def __str__(self) -> str:
        if self.line and self.column:
            return f"{self.file}:{self.line}:{self.column}"
        if self.line:
            return f"{self.file}:{self.line}"
        return self.file


@dataclass(frozen=True)
class Problem:
    """One validation problem of a pipeline spec."""

    location: Location
    message: str

    def __post_init__(self) -> None:
        object.__setattr__(self, "message", bounded(self.message))

    def __str__(self) -> str:
        return f"{self.location}: {self.message}"


class SpecError(GyropipeError):
    """A pipeline spec is invalid; carries every problem found, each with its YAML location."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        lines = "\n".join(f"  {p}" for p in problems)
        super().__init__(f"invalid pipeline ({len(problems)} problem(s)):\n{lines}")


class InputFileError(GyropipeError):
    """An input file is malformed: names the file, the line (1-based; 0 if unknown) and
    what was expected."""

    def __init__(self, path: str | Path, message: str, line: int = 0, column: str = "") -> None:
        self.path = str(path)
        self.line = line
        self.column = column
        self.reason = message = bounded(message)
        where = f"{self.path}:{line}" if line else self.path
        col = f" (column {column!r})" if column else ""
        super().__init__(f"{where}{col}: {message}")


class WrongKindError(InputFileError):
    """A readable file that holds another kind of table than the one asked for (a well log
    read as survey stations): the message says what the file looks like and what the kind
    needs, so a caller may try another kind; ``found`` names the kind it holds if known."""

    def __init__(
        self, path: str | Path, message: str, line: int = 0, *, found: str | None = None
    ) -> None:
        super().__init__(path, message, line)
        self.found = found


class InputFileWarning(UserWarning):
    """An input file was read despite a problem, named with its file and line and what the
    reader did about it (e.g. a header value contradicting the data it kept)."""


class SurveyCheckWarning(UserWarning):
    """A run's numbers disagree with what its input states (e.g. a stations file's own
    positions with the recomputed ones), named with the stage and the first station."""


def warn_input(path: str | Path, message: str, line: int = 0) -> None:
    """Issue an :class:`InputFileWarning` located at ``path:line``."""
    where = f"{path}:{line}" if line else str(path)
    warnings.warn(f"{where}: {bounded(message)}", InputFileWarning, stacklevel=2)


WARNED_EACH = 10
"""Rows of one kind warned of one by one (:func:`warn_rows`); the rest in one warning."""


def warn_rows(path: str | Path, rows: list[tuple[str, int]], what: str) -> None:
    """Warn of each of the first :data:`WARNED_EACH` ``(message, line)`` at its line, and
    of the rest (``what`` they are: "stations left out") in one warning counting them from
    the first's line to the last's: a file of 20,000 such rows is not 20,000 lines."""
    for message, line in rows[:WARNED_EACH]:
        warn_input(path, message, line)
    rest = rows[WARNED_EACH:]
    if rest:
        span = f"lines {rest[0][1]} to {rest[-1][1]}" if len(rest) > 1 else f"line {rest[0][1]}"
        warn_input(path, f"{len(rest)} more {what} likewise ({span})", rest[0][1])


class EmptyTableError(GyropipeError, ValueError):
    """A stage (or writer) can compute nothing from a table with no rows. An empty table is a
    legal stage output, so this names the table and says that what produced it gave none."""

    def __init__(self, table: str, needs: str) -> None:
        self.table = table
        super().__init__(
            f"the {table} table has no rows (the stage that produced it gave none): {needs}"
        )


class FileSystemError(GyropipeError, OSError):
    """A file operation failed (disk full, read-only, permission denied, a file gone): names
    the operation and the file, "cannot write OUT/x.parquet: No space left on device
    (errno 28)". An ``OSError`` too, with the cause's ``errno``, ``strerror`` and
    ``filename``, so a handler of ``OSError`` still catches it."""

    def __init__(self, operation: str, path: str | Path, code: int | None, reason: str) -> None:
        super().__init__(code, reason, str(path))
        self.operation = operation

    @classmethod
    def of(cls, exc: OSError, operation: str, path: str | Path | None = None) -> FileSystemError:
        """``exc`` as a located error; ``path`` if given, else the file ``exc`` names."""
        if isinstance(exc, FileSystemError):
            return exc
        where = path if path is not None else (exc.filename or "?")
        reason = exc.strerror or str(exc)
        if exc.errno and f"[errno {exc.errno}]" in reason.lower():  # Arrow's: names a temp file
            reason = os.strerror(exc.errno)
        return cls(operation, where, exc.errno, reason)

    def __str__(self) -> str:
        code = f" (errno {self.errno})" if self.errno else ""
        return f"cannot {self.operation} {self.filename}: {self.strerror}{code}"

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.operation, self.filename, self.errno, self.strerror))


@contextlib.contextmanager
def file_errors(operation: str, path: str | Path | None = None) -> Iterator[None]:
    """Raise an ``OSError`` inside as a :class:`FileSystemError` (``operation``, ``path``)."""
    try:
        yield
    except OSError as exc:
        raise FileSystemError.of(exc, operation, path) from exc


class UnitError(GyropipeError):
    """A unit string is unknown or not convertible to the unit required."""


class MissingSiteError(GyropipeError):
    """A stage needs the site (its latitude; longitude and survey date for a geomagnetic
    model) and neither the stage's parameters nor the well metadata give it. Names the stage
    and every place the values may be given."""

    def __init__(
        self, stage: str, missing: list[str], param: str | None = None, *, python: bool = False
    ) -> None:
        self.stage = stage
        self.missing = missing
        self.param = param
        model = [name for name in missing if name != "latitude"]
        why = (
            ""
            if not model
            else " (for the geomagnetic model)"
            if model == missing
            else f" (the geomagnetic model needs the {_listed(model)})"
        )
        head = f"the {stage} stage needs the site {_listed(missing)}{why}"
        if python:  # a gp.* function: its argument or its well= mapping
            argument = f"the function's `{param}=` argument or " if param else ""
            mapping = ", ".join(f'"{name}": …' for name in missing)
            super().__init__(
                f"{head}: give {argument}`well={{{mapping}}}` (or the input's well metadata)"
            )
            return
        given = f"the {stage} stage's `{param}`, or " if param else ""
        fields = _listed([f"`{name}`" for name in missing])
        flags = " ".join(f"--well {name}=…" for name in missing)
        super().__init__(
            f"{head}: set {given}the well's {fields} in the pipeline's `well:` block, on the "
            f"command line ({flags}) or in the input file's header"
        )

    def in_python(self) -> MissingSiteError:
        """The same error worded for the Python API (``latitude=``, ``well={…}``)."""
        return MissingSiteError(self.stage, self.missing, self.param, python=True)


def _listed(names: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return " and ".join([", ".join(names[:-1]), names[-1]] if len(names) > 1 else names)


@dataclass(frozen=True)
class RuleFailure:
    """One failed contract rule on one column."""

    column: str
    rule: str
    expected: str
    bad_rows: int = 0
    examples: tuple[tuple[int, object], ...] = ()
    lines: tuple[int, ...] = ()
    """source file line of each example row, when the table records it"""

    def __str__(self) -> str:
        text = f"column {self.column!r}: {self.rule}: expected {self.expected}"
        if self.bad_rows:
            where = [f"row {i}" for i, _ in self.examples]
            if self.lines:
                where = [f"{w} (line {n})" for w, n in zip(where, self.lines, strict=True)]
            shown = ", ".join(f"{w}: {v!r}" for w, (_, v) in zip(where, self.examples, strict=True))
            text += f"; {self.bad_rows} bad row(s), first: {shown}"
        return text


class ContractViolation(GyropipeError):
    """A table broke its port contract. Names pipeline, stage, port and every failed rule."""

    def __init__(
        self,
        contract: str,
        failures: list[RuleFailure],
        *,
        source: str = "",
        pipeline: str = "",
        stage: str = "",
        port: str = "",
        direction: str = "",
    ) -> None:
        self.contract = contract
        self.failures = failures
        self.source = source
        self.pipeline = pipeline
        self.stage = stage
        self.port = port
        self.direction = direction
        where = " ".join(
            part
            for part in (
                f"pipeline {pipeline!r}" if pipeline else "",
                f"stage {stage!r}" if stage else "",
                f"{direction} port {port!r}" if port else "",
            )
            if part
        )
        head = f"{where}: " if where else ""
        read_from = f" (data read from {source})" if source else ""
        body = "\n".join(f"  {f}" for f in failures)
        super().__init__(f"{head}table violates contract {contract}{read_from}:\n{body}")

    def located(self, *, pipeline: str, stage: str, port: str, direction: str) -> ContractViolation:
        """The same violation, annotated with where in the pipeline it happened."""
        return ContractViolation(
            self.contract,
            self.failures,
            source=self.source,
            pipeline=pipeline,
            stage=stage,
            port=port,
            direction=direction,
        )


class StageError(GyropipeError):
    """A stage raised: names the stage id, its registered name and the plugin that provides it."""

    def __init__(self, stage_id: str, uses: str, plugin: str, cause: BaseException) -> None:
        self.stage_id = stage_id
        self.uses = uses
        self.plugin = plugin
        why = cause if isinstance(cause, FileSystemError) else f"{type(cause).__name__}: {cause}"
        super().__init__(f"stage {stage_id!r} ({uses} from plugin {plugin}) failed: {why}")


class ParameterError(GyropipeError):
    """Parameters given to a function or stage are not valid for it; names each one."""


class ReaderChoiceError(GyropipeError):
    """No installed reader, or more than one equally sure, can read a file as the kind of
    table asked for."""


class ReaderOptionsError(GyropipeError):
    """Options given to a reader are not valid for it."""


class ReaderError(GyropipeError):
    """A reader failed on a file: names the reader and the plugin that provides it."""

    def __init__(self, reader: str, plugin: str, cause: BaseException) -> None:
        self.reader = reader
        self.plugin = plugin
        self.cause = cause
        super().__init__(
            f"reader {reader!r} (plugin {plugin}) failed: {type(cause).__name__}: {cause}"
        )


class PluginError(GyropipeError):
    """A plugin failed to load or registered something invalid."""

    def __init__(self, plugin: str, version: str, message: str) -> None:
        self.plugin = plugin
        self.version = version
        super().__init__(f"plugin {plugin} {version}: {message}")


class ToolModelError(GyropipeError, ValueError):
    """A tool-model (error model) file is invalid, or a term of it cannot be evaluated;
    carries every problem found, each located at its file, line and column."""

    def __init__(self, problems: list[Problem]) -> None:
        self.problems = problems
        lines = "\n".join(f"  {p}" for p in problems)
        super().__init__(f"invalid tool model ({len(problems)} problem(s)):\n{lines}")

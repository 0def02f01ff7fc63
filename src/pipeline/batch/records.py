"""Rows of the run ledger as Python objects. Times are POSIX seconds (UTC).

A row is read defensively (:func:`run_row`, :func:`batch_row`): a column that is not valid
UTF-8, not JSON where JSON is stored, of the wrong type, or a status outside the known ones
is a :class:`BadRow` naming the column, never a traceback.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pydantic import TypeAdapter, ValidationError
from typing_extensions import TypedDict

from pipeline.manifest import REJECTED

from .fingerprint import Fingerprint

RUN_STATUSES = ("running", "done", "failed", "interrupted")
BATCH_STATUSES = ("running", "finished", "interrupted")


class InputEntry(TypedDict):
    """An input file as a run read it."""

    path: str
    sha256: str
    bytes: int


class OutputEntry(TypedDict):
    """A published output file."""

    file: str
    path: str
    sha256: str
    bytes: int


@dataclass(frozen=True)
class RunRow:
    """One run of one well."""

    id: int
    well: str
    batch: int
    status: str
    reasons: list[str]
    """why it ran"""
    fingerprint: Fingerprint
    versions: dict[str, Any]
    """gyropipe version and every loaded plugin's version"""
    out_dir: str
    started: float
    finished: float | None = None
    inputs: dict[str, InputEntry] = field(default_factory=dict)
    """input name → {path, sha256, bytes} as the run read them"""
    outputs: list[OutputEntry] = field(default_factory=list)
    """{file, path, sha256, bytes} of every published output"""
    calibration: list[dict[str, Any]] = field(default_factory=list)
    """per drift calibration result the run read: its stage, input file and SHA-256, the
    instruments it calibrates and its selected estimates"""
    drift: list[dict[str, Any]] | None = None
    """per drift-corrected output, the correction applied: ``stage`` and ``port`` of the
    corrected readings, then the :class:`~pipeline.drift.correction.DriftRate` they record
    — ``instrument`` (the calibrated one), ``source`` (calibration, given, tie_in),
    ``method`` (the estimate) and ``label`` (the series it compares), ``rate_deg_h`` and
    ``sigma_deg_h``, ``calibration_date`` (ISO 8601), ``verdict`` (linearity) and
    ``caveats`` — each null where the readings record none; [] none was applied, None not
    recorded (a failed run, a run of an earlier version, or one recovered after
    its batch died)"""
    error: str | None = None
    note: str | None = None
    wall_time_s: float | None = None
    """the whole run in its worker, s"""
    run_time_s: float | None = None
    """the runner's part of it (stages, contract checks, persisted outputs, run.json), s"""
    process_time_s: float | None = None
    """the stages alone, s"""
    peak_rss_bytes: int | None = None
    worker: str | None = None

    @property
    def verdict(self) -> str:
        """``rejected`` for a done run whose survey failed acceptance, else its status."""
        rejected = self.status == "done" and (self.note or "").startswith(f"{REJECTED}:")
        return REJECTED if rejected else self.status


def rejection(manifest: dict[str, Any]) -> str | None:
    """The note of a run whose ``run.json`` says ``rejected``: which gates failed."""
    from pipeline.qc.gates import failed_gates

    if manifest.get("status") != REJECTED:
        return None
    return f"{REJECTED}: acceptance FAILED ({', '.join(failed_gates(manifest))})"


@dataclass(frozen=True)
class BatchRow:
    """One invocation of ``gyropipe batch``."""

    id: int
    key: str
    status: str
    pipeline_file: str
    pipeline_sha256: str
    out_dir: str
    options: dict[str, Any]
    host: str
    pid: int
    started: float
    heartbeat: float
    finished: float | None = None
    counts: dict[str, int] = field(default_factory=dict)


def iso(seconds: float | None) -> str:
    """POSIX seconds as an ISO 8601 UTC time to the second ('' for None)."""
    if seconds is None:
        return ""
    return dt.datetime.fromtimestamp(seconds, dt.UTC).isoformat(timespec="seconds")


JSON_RUN_COLUMNS = ("reasons", "fingerprint", "versions", "inputs", "outputs", "calibration")
NULLABLE_RUN_COLUMNS = ("drift",)
"""JSON columns a row may hold null in (not recorded)"""
JSON_BATCH_COLUMNS = ("options", "counts")
FINGERPRINT_KEYS = frozenset(f.name for f in dataclasses.fields(Fingerprint))


class BadRow(Exception):
    """A ledger row that does not parse: the column and what is wrong with it."""

    def __init__(self, column: str, problem: str) -> None:
        super().__init__(f"{column} {problem}")
        self.column = column


class Undecodable(bytes):
    """A TEXT value that is not valid UTF-8 (the ledger's ``text_factory`` keeps its bytes)."""


def decode_text(data: bytes) -> str | Undecodable:
    """The ledger connection's ``text_factory``: UTF-8 text, else :class:`Undecodable`."""
    try:
        return data.decode()
    except UnicodeDecodeError:
        return Undecodable(data)


def run_row(values: Mapping[str, Any]) -> RunRow:
    """A ``runs`` row as a :class:`RunRow`; :class:`BadRow` if a column does not parse."""
    parsed = _columns(values, JSON_RUN_COLUMNS, NULLABLE_RUN_COLUMNS)
    fingerprint = parsed["fingerprint"]
    if not isinstance(fingerprint, dict) or set(fingerprint) != FINGERPRINT_KEYS:
        keys = ", ".join(sorted(FINGERPRINT_KEYS))
        raise BadRow("fingerprint", f"is not an object with exactly the keys {keys}")
    if parsed["status"] not in RUN_STATUSES:
        raise BadRow("status", f"is {parsed['status']!r}, not one of {', '.join(RUN_STATUSES)}")
    row: RunRow = _validated(_RUN, parsed)
    return row


def batch_row(values: Mapping[str, Any]) -> BatchRow:
    """A ``batches`` row as a :class:`BatchRow`; :class:`BadRow` if a column does not parse."""
    parsed = _columns(values, JSON_BATCH_COLUMNS)
    if parsed["status"] not in BATCH_STATUSES:
        raise BadRow("status", f"is {parsed['status']!r}, not one of {', '.join(BATCH_STATUSES)}")
    row: BatchRow = _validated(_BATCH, parsed)
    return row


def _columns(
    values: Mapping[str, Any], json_columns: tuple[str, ...], nullable: tuple[str, ...] = ()
) -> dict[str, Any]:
    parsed = dict(values)
    for column, value in parsed.items():
        if isinstance(value, Undecodable):
            raise BadRow(column, "is not valid UTF-8 text")
    for column in (*json_columns, *(c for c in nullable if parsed.get(c) is not None)):
        try:
            parsed[column] = json.loads(parsed[column])
        except (TypeError, ValueError):
            raise BadRow(column, "is not JSON") from None
    return parsed


def _validated(adapter: TypeAdapter[Any], values: dict[str, Any]) -> Any:
    try:
        return adapter.validate_python(values)
    except ValidationError as exc:
        first = exc.errors()[0]
        column = str(first["loc"][0]) if first["loc"] else "?"
        raise BadRow(column, f"is not valid: {first['msg']}") from None


_RUN = TypeAdapter(RunRow)
_BATCH = TypeAdapter(BatchRow)

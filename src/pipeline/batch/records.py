"""Rows of the run ledger as Python objects. Times are POSIX seconds (UTC)."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from typing import Any

from .fingerprint import Fingerprint

RUN_STATUSES = ("running", "done", "failed", "interrupted")
REJECTED = "rejected"
"""a done run (outputs published) whose survey failed an acceptance gate: the ledger keeps
status ``done`` and says so in the run's note (``rejected: acceptance FAILED (…)``)"""
BATCH_STATUSES = ("running", "finished", "interrupted")


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
    inputs: dict[str, Any] = field(default_factory=dict)
    """input name → {path, sha256, bytes} as the run read them"""
    outputs: list[dict[str, Any]] = field(default_factory=list)
    """{file, path, sha256, bytes} of every published output"""
    calibration: list[dict[str, Any]] = field(default_factory=list)
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

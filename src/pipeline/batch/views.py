"""What ``gyropipe status DIR`` (its text, JSON and fleet page) and ``gyropipe history WELL``
show from a ledger."""

from __future__ import annotations

import json
import shutil
from dataclasses import asdict
from pathlib import Path
from typing import Any

from .causes import cause
from .fleet_page import Fleet, FleetWell
from .ledger import Ledger, alive
from .records import BatchRow, RunRow, iso
from .summary import wrapped


def status_document(ledger: Ledger) -> dict[str, Any]:
    """Batches and the latest run of every well, as JSON values."""
    batches = ledger.batches()
    return {
        "ledger": str(ledger.path),
        "batches": [{**asdict(b), "alive": _live(b)} for b in batches],
        "wells": [_run_document(r) for r in ledger.latest_runs()],
    }


def status_text(ledger: Ledger) -> str:
    """A readable status: counts, batches, then one line per well."""
    batches = {b.id: b for b in ledger.batches()}
    runs = ledger.latest_runs()
    tally: dict[str, int] = {}
    for run in runs:
        tally[run.verdict] = tally.get(run.verdict, 0) + 1
    lines = [
        f"ledger {ledger.path}: {len(runs)} wells — "
        + (", ".join(f"{n} {s}" for s, n in sorted(tally.items())) or "no runs")
    ]
    for b in batches.values():
        state = b.status
        if b.status == "running":
            state += f" (pid {b.pid} on {b.host})" if _live(b) else " (its process is gone)"
        done = ", ".join(f"{n} {s}" for s, n in b.counts.items() if n)
        lines.append(
            f"  batch {b.id:<4} {state:<12} started {iso(b.started)}"
            + (f", ended {iso(b.finished)}" if b.finished else "")
            + (f": {done}" if done else "")
        )
    if runs:
        width = max(4, *(len(r.well) for r in runs))
        lines.append(f"{'well':<{width}}  {'status':<11} {'finished':<25} {'time s':>8}  detail")
        columns = shutil.get_terminal_size((120, 24)).columns
        for r in runs:
            time_s = f"{r.wall_time_s:8.2f}" if r.wall_time_s is not None else f"{'-':>8}"
            prefix = f"{r.well:<{width}}  {_state(r, batches):<11} {iso(r.finished):<25} {time_s}  "
            lines += wrapped(prefix, _detail(r), columns)
            for entry in r.drift if r.status == "done" and r.drift else ():
                lines += wrapped(" " * len(prefix), _drift_text(entry), columns)
    return "\n".join(lines)


def status_fleet(ledger: Ledger, title: str) -> Fleet:
    """The fleet page of every well the ledger knows: its latest run (a running well whose
    batch is gone is ``stale``), the figures from the outputs that run published."""
    batches = {b.id: b for b in ledger.batches()}
    wells = tuple(
        FleetWell(
            r.well,
            _state(r, batches),
            r.error or r.note or "; ".join(r.reasons),
            r.wall_time_s,
            r.id,
            Path(r.out_dir),
        )
        for r in ledger.latest_runs()
    )
    return Fleet(title, tuple(batches.values()), wells, ledger_id=ledger.ledger_id)


def history_text(well: str, runs: list[RunRow]) -> str:
    """Every run of ``well``: when, status, why it ran, what it read, versions, outputs."""
    lines = [f"well {well}: {len(runs)} run(s)"]
    for r in runs:
        time_s = f"{r.wall_time_s:.2f} s" if r.wall_time_s is not None else "-"
        lines.append(
            f"run {r.id} (batch {r.batch}) {r.status} started {iso(r.started)} "
            f"finished {iso(r.finished) or '-'} ({time_s})"
        )
        lines.append(f"  why: {'; '.join(r.reasons)}")
        if r.error:
            lines.append(f"  error: {r.error}")
        if r.note:
            lines.append(f"  note: {r.note}")
        for name, entry in (r.inputs or {}).items():
            lines.append(f"  input {name}: {entry['path']} sha256 {entry['sha256'][:16]}…")
        if not r.inputs:
            for name, digest in r.fingerprint.inputs.items():
                lines.append(f"  input {name}: sha256 {digest[:16]}")
        lines.append(f"  gyropipe {r.versions.get('gyropipe')}; plugins: {_plugins(r.versions)}")
        lines.append(f"  pipeline sha256 {r.fingerprint.pipeline[:16]}…")
        if r.fingerprint.well:
            lines.append(f"  well header: {dict(r.fingerprint.well)}")
        lines += [_calibration_line(cal) for cal in r.calibration]
        if r.status == "done":
            lines += _drift_lines(r.drift)
        if r.outputs:
            lines.append(f"  outputs: {r.out_dir} ({len(r.outputs)} files)")
    return "\n".join(lines)


def _calibration_line(cal: dict[str, Any]) -> str:
    """A drift calibration's entry in words; another contract's (or a damaged one) as JSON."""
    try:
        chosen = ", ".join(
            f"{s['instrument']} {s['method']} {s['drift_deg_h']:.4f} deg/h" for s in cal["selected"]
        )
        return (
            f"  calibration ({cal['stage']}, input {cal['input']} sha256 "
            f"{(cal['sha256'] or '')[:16]}…): selected {chosen}"
        )
    except (KeyError, TypeError, ValueError):
        return f"  calibration: {json.dumps(cal, sort_keys=True, default=str)}"


def _drift_lines(found: list[dict[str, Any]] | None) -> list[str]:
    """A done run's drift corrections, one line each (none: no line; None: not recorded)."""
    if found is None:
        return ["  drift applied: not recorded (run by an earlier version, or recovered)"]
    return [f"  {_drift_text(entry)}" for entry in found]


SOURCES = {"given": "a given rate", "tie_in": "the tie-in misclosure"}
"""How a drift rate's source other than a calibration is worded"""


def _drift_text(entry: dict[str, Any]) -> str:
    """A ledger ``drift`` entry (:attr:`~pipeline.batch.records.RunRow.drift`) in words: the
    rate applied, where it came from and the calibration's caveats; a damaged one as JSON."""
    try:
        where = f"drift applied ({entry['stage']}.{entry['port']})"
        if entry["rate_deg_h"] is None:
            return f"{where}: not recorded by the corrected readings"
        rate = f"{entry['rate_deg_h']:.4f} ± {entry['sigma_deg_h']:.4f} deg/h"
        if entry["source"] == "calibration":
            day = entry["calibration_date"] or "day not stated"
            source = (
                f"calibration of {entry['instrument']} ({entry['method']}, {day}, "
                f"{entry['verdict']})"
            )
        else:
            source = SOURCES.get(entry["source"], str(entry["source"]))
        return f"{where}: {rate}, {source}" + "".join(f"; ⚠ {c}" for c in entry["caveats"])
    except (KeyError, TypeError, ValueError):
        return f"drift applied: {json.dumps(entry, sort_keys=True, default=str)}"


def history_document(well: str, runs: list[RunRow]) -> dict[str, Any]:
    return {"well": well, "runs": [_run_document(r) for r in runs]}


def _run_document(run: RunRow) -> dict[str, Any]:
    document = asdict(run)
    document["verdict"] = run.verdict
    document["started_iso"] = iso(run.started)
    document["finished_iso"] = iso(run.finished)
    return document


def _live(batch: BatchRow) -> bool:
    return batch.status == "running" and alive(batch)


def _state(run: RunRow, batches: dict[int, BatchRow]) -> str:
    if run.status != "running":
        return run.verdict
    owner = batches.get(run.batch)
    return "running" if owner is not None and _live(owner) else "stale"


def _plugins(versions: dict[str, Any]) -> str:
    plugins = versions.get("plugins")
    if not isinstance(plugins, dict):
        return "unknown"
    builtin = sum(1 for n in plugins if n.startswith("builtin."))
    others = [f"{n} {v}" for n, v in plugins.items() if not n.startswith("builtin.")]
    return ", ".join([f"{builtin} built-in", *others])


def _detail(run: RunRow) -> str:
    return cause(run.error or run.note or "; ".join(run.reasons))

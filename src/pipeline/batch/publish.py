"""A well's output directory is published whole: the run writes into a private staging
directory ``OUT/.gyropipe-batch/<well>.<run id>.staging``, which is renamed to
``OUT/<well>`` once every file in it is on disk (fsync). ``OUT/<well>`` therefore always
holds one complete run — its outputs, its ``run.json`` and the ``batch.json`` marker naming
the ledger run that produced it — or does not exist.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pipeline.atomic import TRASH_SUFFIX, atomic_write_bytes, discard
from pipeline.runner import MANIFEST, remove_stale_staging

WORK_DIR = ".gyropipe-batch"
MARKER = "batch.json"
STAGING_SUFFIX = ".staging"


@dataclass(frozen=True)
class PublishedRun:
    """What a published well directory says about itself."""

    run_id: int
    manifest: dict[str, Any]
    """the runner's ``run.json``"""


def staging_dir(out_root: Path, well_id: str, run_id: int) -> Path:
    """The private directory where run ``run_id`` of ``well_id`` writes its files."""
    return out_root / WORK_DIR / f"{well_id}.{run_id}{STAGING_SUFFIX}"


def staging_run_id(entry: Path) -> int | None:
    """The run id in a staging directory's name (None for other entries)."""
    if not entry.name.endswith(STAGING_SUFFIX):
        return None
    run_text = entry.name.removesuffix(STAGING_SUFFIX).rsplit(".", 1)[-1]
    return int(run_text) if run_text.isdigit() else None


def write_marker(staging: Path, record: dict[str, Any]) -> None:
    """Write ``batch.json`` (well, run id, batch id, fingerprint) into the staging dir."""
    atomic_write_bytes(staging / MARKER, json.dumps(record, indent=2).encode())


def read_published(well_dir: Path) -> PublishedRun | None:
    """The published run in ``well_dir``, if it is complete: marker and manifest present
    and every output listed in the manifest on disk with its recorded size."""
    try:
        marker = json.loads((well_dir / MARKER).read_text())
        manifest = json.loads((well_dir / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    for entry in manifest.get("outputs", []):
        path = well_dir / entry["file"]
        if not path.is_file() or path.stat().st_size != entry["bytes"]:
            return None
    return PublishedRun(int(marker["run_id"]), manifest)


def clean_work_dir(out_root: Path, active_runs: set[int]) -> list[Path]:
    """Remove staging directories of runs not in ``active_runs`` and leftover trash."""
    removed: list[Path] = []
    work = out_root / WORK_DIR
    if not work.is_dir():
        return removed
    removed += remove_stale_staging(work)  # the runner's own, inside a killed worker's run
    for entry in work.iterdir():
        run_id = staging_run_id(entry)
        if entry.name.endswith(TRASH_SUFFIX) or (run_id is not None and run_id not in active_runs):
            discard(entry)
            removed.append(entry)
    return removed

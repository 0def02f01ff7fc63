"""A well's output directory is published whole: the run writes into a private staging
directory ``OUT/.gyropipe-batch/<well>.<run id>.<worker pid>.staging``, which is renamed
to ``OUT/<well>`` once every file in it is on disk (fsync). ``OUT/<well>`` therefore always
holds one complete run — its outputs, its ``run.json`` and the ``batch.json`` marker naming
the ledger run that produced it — or does not exist.

A staging directory is removed once its run is no longer claimed and its worker process is
gone: a worker of a killed batch may live on for a moment (it exits as soon as it sees its
batch gone), and removing its directory under it would let it make the directory again
(renaming its finished run there) and leave it behind.
"""

from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pipeline.atomic import TRASH_SUFFIX, discard, write_synced
from pipeline.hashing import file_key, regular_bytes
from pipeline.manifest import MANIFEST
from pipeline.processes import owner_alive
from pipeline.runner import remove_stale_staging

WORK_DIR = ".gyropipe-batch"
MARKER = "batch.json"
STAGING_SUFFIX = ".staging"


@dataclass(frozen=True)
class Publication:
    """A run as published in ``OUT/<well>``, known by the SHA-256 of its ``batch.json`` and
    ``run.json`` bytes: files whose hashes are these hold this run's marker and manifest."""

    run_id: int
    marker_sha256: str
    manifest_sha256: str
    ledger_id: str | None = None
    """the identity of the ledger whose run it is (None: not known, or a ``batch.json`` of
    an earlier version, which names none)"""

    def is_run(self, ledger_id: str | None, run_id: int) -> bool:
        """Whether this is run ``run_id`` of ledger ``ledger_id``: run ids are each ledger's
        own, so another ledger publishing into the same OUT has its own run of that id; a
        ``batch.json`` naming no ledger (an earlier version's) is known by its run id alone."""
        return self.run_id == run_id and of_ledger(self.ledger_id, ledger_id)


def of_ledger(named: object, ledger_id: str | None) -> bool:
    """Whether a ``batch.json`` naming ledger ``named`` holds a run of ledger ``ledger_id``:
    one naming none (an earlier version's) is taken as the ledger's."""
    return named is None or named == ledger_id


@dataclass(frozen=True)
class PublishedRun:
    """What a published well directory says about itself."""

    run_id: int
    manifest: dict[str, Any]
    """the runner's ``run.json``"""
    marker_sha256: str
    """SHA-256 of the ``batch.json`` bytes read"""
    manifest_sha256: str
    """SHA-256 of the ``run.json`` bytes read"""
    ledger_id: str | None = None
    """the ledger whose run it is, as ``batch.json`` names it (None: it names none)"""

    @property
    def publication(self) -> Publication:
        return Publication(self.run_id, self.marker_sha256, self.manifest_sha256, self.ledger_id)


def staging_dir(out_root: Path, well_id: str, run_id: int) -> Path:
    """The private directory where run ``run_id`` of ``well_id`` writes its files (in this
    process)."""
    return out_root / WORK_DIR / f"{well_id}.{run_id}.{os.getpid()}{STAGING_SUFFIX}"


def staging_owner(entry: Path) -> tuple[int, int | None] | None:
    """The run id and worker pid in a staging directory's name (the pid None in the names of
    earlier versions, ``<well>.<run id>.staging``); None for other entries."""
    if not entry.name.endswith(STAGING_SUFFIX):
        return None
    parts = entry.name.removesuffix(STAGING_SUFFIX).split(".")
    numbers = [int(p) if p.isdigit() else None for p in parts[-2:]]
    if len(numbers) == 2 and numbers[0] is not None and numbers[1] is not None:
        return numbers[0], numbers[1]
    return (numbers[-1], None) if numbers[-1] is not None else None


def write_marker(staging: Path, record: dict[str, Any]) -> None:
    """Write ``batch.json`` (well, run id, ledger id, batch id, fingerprint, figures) into
    the staging dir, on disk (fsync) before the directory is published."""
    write_synced(staging / MARKER, json.dumps(record, indent=2).encode())


def read_published(well_dir: Path) -> PublishedRun | None:
    """The published run in ``well_dir``, if it is complete: marker and manifest present and
    well formed (``batch.json`` names an integer ``run_id``, and a text ``ledger_id`` if
    any; ``run.json`` lists its outputs with their file names and sizes) and every output
    listed on disk with its recorded size. A marker or manifest that is missing, damaged or
    edited counts as not published. The hashes of the two files' bytes as read come with
    it: the batch process knows the publication again by them
    (:mod:`pipeline.batch.filestate`) without reading a file."""
    try:
        marker_bytes = regular_bytes(well_dir / MARKER)
        manifest_bytes = regular_bytes(well_dir / MANIFEST)
        marker = json.loads(marker_bytes)
        manifest = json.loads(manifest_bytes)
        run_id = marker["run_id"]
        ledger_id = marker.get("ledger_id")
        outputs = manifest["outputs"]
        if not isinstance(run_id, int) or not isinstance(ledger_id, str | None):
            return None
        if not isinstance(outputs, list):
            return None
        if not all(output_on_disk(well_dir, entry) for entry in outputs):
            return None
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return PublishedRun(
        run_id,
        manifest,
        hashlib.sha256(marker_bytes).hexdigest(),
        hashlib.sha256(manifest_bytes).hexdigest(),
        ledger_id,
    )


def output_on_disk(well_dir: Path, entry: Any) -> bool:
    """Whether an output ``run.json`` lists (``{"file", "bytes"}``) is a regular file of
    that size directly in ``well_dir``, its status read through a descriptor
    (:func:`~pipeline.hashing.file_key`: fresh on NFS too)."""
    try:
        path = well_dir / entry["file"]
        return bool(path.parent == well_dir and file_key(path).size == entry["bytes"])
    except (OSError, KeyError, TypeError):
        return False


def clean_work_dir(out_root: Path, active_runs: set[int]) -> list[Path]:
    """Remove the staging directories (and their trash) of runs not in ``active_runs`` whose
    worker process is gone (module docstring)."""
    removed: list[Path] = []
    work = out_root / WORK_DIR
    if not work.is_dir():
        return removed
    removed += remove_stale_staging(work)  # the runner's own, inside a killed worker's run
    for entry in work.iterdir():
        owner = staging_owner(entry.with_name(entry.name.removesuffix(TRASH_SUFFIX)))
        if owner is None:
            continue
        run_id, pid = owner
        if run_id not in active_runs and (pid is None or not owner_alive(pid, entry)):
            discard(entry)
            removed.append(entry)
    return removed

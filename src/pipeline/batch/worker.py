"""The per-well task every executor runs: one DAG run into a staging directory, published
whole to ``OUT/<well>``. It never raises: any failure comes back as a failed
:class:`WellOutcome`. It never touches the ledger (only the batch process does), so it can
run on any machine that sees the input and output files.

The worker is where files are read: it hashes each input once (``run.json``, and a failed
run's outcome) — but an input whose stat key is the one the batch process saw and holds a
settled hash for (:attr:`WellTask.known`), which it takes as is, unread — and the files a
check names
(:attr:`WellTask.check`). A run whose input changed while it ran (its stat key before the
hash, given to the runner, and at the end) fails with the runner's
:class:`~pipeline.runner.InputChangedError`; the worker checks that ``OUT/<well>`` holds the
run once published.
"""

from __future__ import annotations

import gc
import json
import os
import resource
import select
import shutil
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from pipeline.atomic import replace_dir
from pipeline.contracts import TableContract
from pipeline.drift.correction import DriftRate, drift_rate_of
from pipeline.drift.tables import CorrectedFreeGyroReadings
from pipeline.errors import GyropipeError
from pipeline.executing import PipelineRef
from pipeline.graph import Plan, PlannedStage, build_plan
from pipeline.hashing import FileKey, key_after
from pipeline.io.threads import set_reader_threads
from pipeline.lazy_pandas import defer_pandas
from pipeline.plugins import shared_registry
from pipeline.processes import process_alive
from pipeline.registry import Registry
from pipeline.runner import RunResult, check_out_dir, run_plan
from pipeline.streams import use_returning_memory_pool
from pipeline.well import WellMetadata

from .fingerprint import UNREADABLE, completed_json, hashed
from .fleet import WellFigures, figures_record, run_figures, well_figures
from .publish import MARKER, Publication, read_published, staging_dir, write_marker

OWN = frozenset({MARKER})
"""what a batch's published well directory holds besides the run's own files"""
EXIT_ORPHAN = 70
ORPHAN_POLL_S = 0.5


@dataclass(frozen=True)
class WellTask:
    """One claimed run of one well."""

    well_id: str
    run_id: int
    batch_id: int
    pipeline: str
    """the digest of the batch's :class:`~pipeline.executing.PipelineRef` (the worker was
    given the reference once: :func:`worker_init`, or with the task)"""
    inputs: dict[str, str]
    """pipeline input name → absolute file path"""
    well: dict[str, Any]
    """header overrides (WellMetadata fields, JSON values)"""
    out_root: str
    fingerprint: str
    """the claim's fingerprint (JSON), recorded in ``batch.json`` with the run's hashes"""
    check: list[str] | None = None
    """a check, not a run: the files (absolute paths) to hash; nothing is run or written"""
    known: dict[str, tuple[FileKey, str]] = field(default_factory=dict)
    """input path → the stat key the batch process saw and the SHA-256 the ledger holds for
    it (settled entries only): used for ``run.json`` where the worker's own key is the same"""
    ledger_id: str | None = None
    """the identity of the ledger that claimed the run, written into ``batch.json`` with the
    run id (None: none written, the run known by its id alone)"""


@dataclass(frozen=True)
class WellOutcome:
    """What a worker reports back. Times in seconds; memory in bytes."""

    well_id: str
    run_id: int
    status: str
    """done, failed, or checked (a check's :attr:`hashes` taken)"""
    error: str | None = None
    manifest: dict[str, Any] = field(default_factory=dict)
    """the published ``run.json``"""
    calibration: list[dict[str, Any]] = field(default_factory=list)
    """the ledger's ``calibration`` entries of the run (:func:`_calibration`)"""
    drift: list[dict[str, Any]] | None = None
    """the ledger's ``drift`` entries of a done run (:func:`_drift`; None: a failed run's)"""
    wall_time_s: float = 0.0
    """the whole task in the worker"""
    run_time_s: float = 0.0
    """the runner (read, stages, contracts, writes, run.json)"""
    process_time_s: float = 0.0
    """the stages alone"""
    peak_rss_bytes: int = 0
    """the worker process's peak resident memory so far (OS accounting)"""
    worker: str = ""
    hashes: dict[str, str] = field(default_factory=dict)
    """path → SHA-256 (``unreadable`` where it cannot be read) of a check's files, or of a
    failed run's inputs (a done run's are in its manifest)"""
    held: Publication | None = None
    """the run whose outputs ``OUT/<well>`` held when the task began, by the hashes of its
    ``batch.json`` and ``run.json`` (None: none whole)"""
    publication: Publication | None = None
    """the run ``OUT/<well>`` holds as the task ends (a check: the one it held; a done run:
    itself), by the hashes of its ``batch.json`` and ``run.json``"""
    figures: WellFigures | None = None
    """the fleet page's figures of that run (:mod:`pipeline.batch.fleet`), recorded here as
    it ran (in its ``batch.json``) so that the batch process reads none"""


_PLANS: dict[tuple[str, tuple[str, ...]], tuple[Plan, Registry]] = {}
"""(pipeline digest, disabled plugins) → the plan built in this process and its registry"""
_GIVEN: dict[str, PipelineRef] = {}
"""the pipelines :func:`worker_init` gave this process, by digest"""


def worker_init(ref: PipelineRef, batch_pid: int) -> None:
    """Process-pool initialiser: keep the batch's pipeline ``ref`` and build its plan once,
    and exit as soon as the batch process
    ``batch_pid`` is gone (killed), so no orphan goes on writing outputs.

    BLAS and OpenMP run single-threaded here, as in Dask's workers: the wells are the
    parallelism, and a worker's BLAS threads spinning on the cores the other workers use
    cost 2 workers on 2 cores 18 % of their time (benchmarks/bench_batch.py). Arrow's
    allocator gives freed memory back (:func:`~pipeline.streams.use_returning_memory_pool`);
    pandas is loaded only if a stage imports it (:mod:`pipeline.lazy_pandas`).

    First of all, every object a forked worker inherits is frozen out of the garbage
    collector (``gc.freeze``): the batch process's garbage — a pool of an earlier batch in
    the same process, not yet collected — would otherwise be collected here, and
    ``concurrent.futures``' callback for a collected pool takes that pool's lock, which a
    thread of the batch process may have held as it forked: the worker hung there for
    good, and the batch with it (a resumed batch after a full ledger, in one process)."""
    gc.freeze()
    defer_pandas()
    threadpool_limits(limits=1)
    use_returning_memory_pool()
    threading.Thread(target=_exit_with, args=(batch_pid,), daemon=True).start()
    _GIVEN[ref.digest] = ref
    try:
        _plan(ref)
    except Exception:  # reported per well by run_well
        return


def _exit_with(pid: int) -> None:
    """Wait for process ``pid`` to end (a pidfd on Linux, else polling), then exit."""
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        os._exit(EXIT_ORPHAN)
    except (AttributeError, OSError):  # no pidfd: poll
        while process_alive(pid):
            time.sleep(ORPHAN_POLL_S)
        os._exit(EXIT_ORPHAN)
    select.select([fd], [], [])
    os._exit(EXIT_ORPHAN)


def run_well(task: WellTask, ref: PipelineRef | None = None) -> WellOutcome:
    """Run one well (module docstring) of the pipeline ``ref``, by default the one
    :func:`worker_init` gave this process, its readers on one thread: the workers are the
    parallelism. A check (:attr:`WellTask.check`) hashes its files and runs nothing."""
    t0 = time.perf_counter()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    final = Path(task.out_root) / task.well_id
    held = read_published(final)
    found = held.publication if held is not None else None
    if task.check is not None:
        hashes = {path: hashed(path) for path in task.check}
        return WellOutcome(
            task.well_id,
            task.run_id,
            "checked",
            wall_time_s=time.perf_counter() - t0,
            worker=worker,
            hashes=hashes,
            held=found,
            publication=found,
            figures=well_figures(final, manifest=held.manifest) if held is not None else None,
        )
    set_reader_threads(1)
    staging = staging_dir(Path(task.out_root), task.well_id, task.run_id)
    digests: dict[str, str] = {}  # input path → SHA-256, each input hashed at most once
    try:
        check_out_dir(final, OWN)  # early: a well that cannot be published is not run
        plan, registry = _plan(_given(task, ref))
        shutil.rmtree(staging, ignore_errors=True)
        staging.mkdir(parents=True)
        before = {name: key_after(path) for name, path in task.inputs.items()}
        for name, path in task.inputs.items():
            digests[path] = _digest(task, path, before[name])
        t_run = time.perf_counter()
        result = run_plan(
            plan,
            registry,
            inputs={name: Path(path) for name, path in task.inputs.items()},
            out_dir=staging,
            well=WellMetadata.model_validate(task.well),
            publish_as=final,
            known_inputs={
                name: (digests[path], before[name])
                for name, path in task.inputs.items()
                if digests[path] != UNREADABLE  # run.json names the file's error instead
            },
        )
        run_time = time.perf_counter() - t_run
        manifest = result.manifest
        figures = run_figures(plan, result.tables, manifest, staging)
        write_marker(
            staging,
            {
                "well_id": task.well_id,
                "run_id": task.run_id,
                "ledger_id": task.ledger_id,
                "batch_id": task.batch_id,
                "fingerprint": json.loads(str(completed_json(task.fingerprint, manifest))),
                "figures": figures_record(figures),
            },
        )
        check_out_dir(final, OWN)  # again: the user may have put files there meanwhile
        replace_dir(staging, final)
        published = read_published(final)
        if published is None or not published.publication.is_run(task.ledger_id, task.run_id):
            raise Inconsistent(
                f"{final} does not hold this run whole once published (replaced meanwhile?)"
            )
        return WellOutcome(
            task.well_id,
            task.run_id,
            "done",
            manifest=manifest,
            calibration=_calibration(plan, result),
            drift=_drift(plan, result),
            wall_time_s=time.perf_counter() - t0,
            run_time_s=run_time,
            process_time_s=sum(s["wall_time_s"] for s in manifest["stages"]),
            peak_rss_bytes=peak_rss_bytes(),
            worker=worker,
            held=found,
            publication=published.publication,
            figures=figures,
        )
    except Exception as exc:  # a failing well is reported, never raised into the batch
        error = str(exc) if isinstance(exc, GyropipeError) else f"{type(exc).__name__}: {exc}"
        return WellOutcome(
            task.well_id,
            task.run_id,
            "failed",
            error=error,
            wall_time_s=time.perf_counter() - t0,
            peak_rss_bytes=peak_rss_bytes(),
            worker=worker,
            hashes={
                path: digests.get(path) or _digest(task, path, key_after(path))
                for path in task.inputs.values()
            },
            held=found,
        )
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def _digest(task: WellTask, path: str, key: FileKey | None) -> str:
    """The SHA-256 of the input ``path`` whose stat key is ``key`` now: the settled hash
    the batch process sent for that key (:attr:`WellTask.known`), else read and hashed
    (:data:`~pipeline.batch.fingerprint.UNREADABLE` if it cannot be read)."""
    known = task.known.get(path)
    if known is not None and key is not None and known[0] == key:
        return known[1]
    return hashed(path)


class Inconsistent(GyropipeError):
    """A run whose outputs cannot be taken as done: ``OUT/<well>`` does not hold it once
    published."""


class NoPipeline(GyropipeError):
    """A worker was handed a task without the batch's pipeline."""


def _given(task: WellTask, ref: PipelineRef | None) -> PipelineRef:
    """The pipeline of ``task``: ``ref``, else the one :func:`worker_init` gave."""
    found = ref if ref is not None else _GIVEN.get(task.pipeline)
    if found is None or found.digest != task.pipeline:
        raise NoPipeline(
            f"this worker was not given the batch's pipeline {task.pipeline[:12]}… "
            "(an executor hands it to worker_init or to run_well)"
        )
    return found


def _plan(ref: PipelineRef) -> tuple[Plan, Registry]:
    """The plan of ``ref`` built against this process's plugins, once per process."""
    key = (ref.digest, ref.disabled)
    cached = _PLANS.get(key)
    if cached is None:
        registry = shared_registry(ref.disabled)
        cached = _PLANS[key] = (build_plan(ref.loaded(), registry), registry)
    return cached


def _calibration(plan: Plan, result: RunResult) -> list[dict[str, Any]]:
    """What the ledger's ``calibration`` column holds of a run: per output whose contract
    is one the ledger records (:attr:`~pipeline.contracts.TableContract.in_ledger`, e.g. a
    drift calibration result), the stage that brought it in, its input file and what the
    contract says of the table (which instrument's estimate was applied, if any, is the
    ``drift`` column's: :func:`_drift`)."""
    inputs = result.manifest["inputs"]
    found = []
    for st, port, contract in _outputs(plan, lambda c: c.in_ledger):
        table = result.tables.get((st.id, port))
        if table is None:
            continue
        name = getattr(st.params, "input", None)
        found.append(
            {
                "stage": st.id,
                "input": name,
                "sha256": inputs[name]["sha256"] if name in inputs else None,
                **contract.ledger_entry(table),
            }
        )
    return found


def _drift(plan: Plan, result: RunResult) -> list[dict[str, Any]]:
    """What the ledger's ``drift`` column holds of a run: per output of drift-corrected
    readings, the correction they record having applied (:attr:`~pipeline.batch.records.
    RunRow.drift`, rate and σ in deg/h) — the instrument whose calibration the survey's own
    tool serial picked, not the run's well serial; [] where the run corrected none."""
    found = []
    for st, port, _ in _outputs(plan, lambda c: issubclass(c, CorrectedFreeGyroReadings)):
        table = result.tables.get((st.id, port))
        if table is None:
            continue
        rate = drift_rate_of(table)
        record: dict[str, Any] = (
            dict.fromkeys(DriftRate.model_fields) if rate is None else rate.model_dump(mode="json")
        )
        record["rate_deg_h"], record["sigma_deg_h"] = record.pop("rate"), record.pop("sigma")
        found.append({"stage": st.id, "port": port, **record})
    return found


def _outputs(
    plan: Plan, wanted: Callable[[type[TableContract]], bool]
) -> Iterator[tuple[PlannedStage, str, type[TableContract]]]:
    """The (stage, port, contract) of every output whose contract is ``wanted`` (known by
    its contract alone: looking a port up would read a streamed output whole)."""
    for st in plan.stages:
        for port, contract in st.definition.outputs.items():
            if wanted(contract):
                yield st, port, contract


def peak_rss_bytes() -> int:
    """Peak resident set size of this process (``ru_maxrss``: KiB on Linux, bytes on macOS)."""
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(peak if sys.platform == "darwin" else peak * 1024)

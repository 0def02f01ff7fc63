"""``gyropipe batch``: one DAG run per well, on an executor, recorded in the ledger.

The batch process hashes each well's inputs, claims the well in the ledger (or skips it,
see :mod:`pipeline.batch.policy`), hands claimed wells to the executor a few at a time, and
records each outcome once the well's outputs are published. A failing well never stops the
others. Killed at any point and started again with the same command, it completes the
remaining wells and recomputes none that finished.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from pipeline.errors import file_errors
from pipeline.executing import ExecutorSetup, PipelineRef
from pipeline.graph import Plan
from pipeline.registry import Registry
from pipeline.version import __version__

from .executors import Executor, open_executor
from .fingerprint import Fingerprint, PlanIdentity
from .jobs import LEDGER, LEDGER_SIDECARS, SUMMARY_FILES, BatchConfigError, WellJob
from .ledger import LEASE_S, Busy, Claimed, Ledger, LedgerError, Skipped
from .policy import Mode, decide
from .progress import Reporter
from .publish import WORK_DIR, clean_work_dir, read_published
from .records import REJECTED, BatchRow, rejection
from .summary import WellResult, counts, write_summary
from .worker import WellOutcome, WellTask

BUSY_POLL_S = 0.5
"""how often a well held by another batch is looked at again"""
PREFETCH = 2
"""wells claimed per worker ahead of time, so no worker waits for the ledger"""


@dataclass(frozen=True)
class BatchOptions:
    """How to run a batch (``gyropipe batch`` options)."""

    out_dir: Path
    workers: int
    executor: str = "local"
    scheduler: str | None = None
    mode: Mode = field(default_factory=Mode)
    ledger: Path | None = None
    disabled: tuple[str, ...] = ()


@dataclass
class BatchReport:
    """What a batch did. ``exit_code``: 0 every well done or skipped, 1 some well failed
    (or was interrupted, or not processed), else 3 some well was rejected (its survey failed
    an acceptance gate)."""

    batch: BatchRow
    results: list[WellResult]
    summary_files: list[Path]
    not_processed: int = 0

    @property
    def exit_code(self) -> int:
        bad = any(r.status in ("failed", "interrupted") for r in self.results)
        if bad or self.not_processed:
            return 1
        return 3 if any(r.status == REJECTED for r in self.results) else 0


def run_batch(
    plan: Plan,
    registry: Registry,
    jobs: Sequence[WellJob],
    options: BatchOptions,
    reporter: Reporter,
) -> BatchReport:
    """Run ``jobs`` (module docstring). Raises
    :class:`~pipeline.batch.jobs.BatchConfigError` if the ledger cannot be used; a
    ``KeyboardInterrupt`` stops the batch and is re-raised after the ledger is closed."""
    out = options.out_dir.resolve()
    ledger_path = options.ledger or out / LEDGER
    _check_ledger_place(ledger_path, out, jobs)
    with file_errors("create the output directory", out):
        out.mkdir(parents=True, exist_ok=True)
    ref = PipelineRef(str(Path(plan.file).resolve()), plan.spec, options.disabled)
    # first: local workers fork before the ledger is open and before any thread starts
    setup = ExecutorSetup(options.workers, ref, options.scheduler)
    executor = open_executor(registry, options.executor, setup)
    try:
        ledger = Ledger(ledger_path)
    except BaseException:
        executor.close(cancel=True)
        raise
    try:
        return _Batch(plan, registry, jobs, options, reporter, out, ledger, ref).run(executor)
    finally:
        ledger.close()


class _Batch:
    def __init__(
        self,
        plan: Plan,
        registry: Registry,
        jobs: Sequence[WellJob],
        options: BatchOptions,
        reporter: Reporter,
        out: Path,
        ledger: Ledger,
        ref: PipelineRef,
    ) -> None:
        self.plan = plan
        self.jobs = list(jobs)
        self.options = options
        self.reporter = reporter
        self.out = out
        self.ledger = ledger
        self.identity = PlanIdentity.of(plan, registry)
        self.versions = {
            "gyropipe": __version__,
            "plugins": {n: p.version for n, p in sorted(registry.plugins.items()) if not p.error},
        }
        self.ref = ref
        self.results: dict[str, WellResult] = {}
        self.inflight: dict[int, tuple[WellJob, Fingerprint, list[str]]] = {}
        self.waiting: dict[str, tuple[float, WellJob]] = {}
        self.noted: set[str] = set()

    def run(self, executor: Executor) -> BatchReport:
        try:
            self._begin()
        except BaseException:
            executor.close(cancel=True)
            raise
        t0 = time.perf_counter()
        try:
            self._loop(executor)
        except BaseException:
            # the first failure is the one reported: the ledger or the disk failing again
            # while closing (disk full) would only hide it, and the next batch settles
            # whatever this one could not record
            with contextlib.suppress(LedgerError, OSError):
                self._end(executor, "interrupted", t0)
            raise
        results, files = self._end(executor, "finished", t0)
        return BatchReport(self.batch, results, files, len(self.jobs) - len(results))

    def _end(
        self, executor: Executor, status: str, t0: float
    ) -> tuple[list[WellResult], list[Path]]:
        """Stop the executor, close the batch in the ledger, write the summary files."""
        executor.close(cancel=status != "finished")
        for job, _, _ in self.inflight.values():
            self._report(WellResult(job.well_id, "interrupted", "the batch was stopped"))
        self.inflight.clear()
        results = [self.results[j.well_id] for j in self.jobs if j.well_id in self.results]
        self.ledger.end_batch(self.batch.id, status, counts(results))
        clean_work_dir(self.out, self.ledger.running_ids())  # a killed batch's late orphans
        files = write_summary(self.out, self.batch, results)
        self.reporter.end(self.batch.id, time.perf_counter() - t0)
        return results, files

    def _begin(self) -> None:
        """Settle dead batches, register this one, clean stale staging, announce it."""
        for swept in self.ledger.sweep():
            self.reporter.note(
                f"batch {swept.id} (pid {swept.pid} on {swept.host}) had stopped; "
                "its unfinished runs were settled"
            )
        self._tell_problems()
        key = self._key()
        self.batch = self.ledger.start_batch(
            key,
            self.ref.file,
            self.plan.digest,
            self.out,
            {
                "executor": self.options.executor,
                "workers": self.options.workers,
                "only_changed": self.options.mode.only_changed,
                "rerun_failed": self.options.mode.rerun_failed,
                "wells": len(self.jobs),
            },
        )
        self.resume_since = self.ledger.resume_since(key, self.batch.id)
        if self.resume_since is not None:
            self.reporter.note(f"resuming the interrupted batch {self.resume_since}")
        clean_work_dir(self.out, self.ledger.running_ids())
        self.reporter.start(
            self.batch.id,
            self.plan.file,
            len(self.jobs),
            self.options.executor,
            self.options.workers,
        )

    def _loop(self, executor: Executor) -> None:
        # largest inputs first: the long wells do not end up alone at the end of the batch
        queue = deque(sorted(self.jobs, key=_input_bytes, reverse=True))
        capacity = max(1, self.options.workers) * PREFETCH
        beat = time.monotonic()
        while queue or self.inflight or self.waiting:
            now = time.monotonic()
            for well, (due, job) in list(self.waiting.items()):
                if due <= now:
                    del self.waiting[well]
                    queue.appendleft(job)
            while queue and len(self.inflight) < capacity:
                self._consider(queue.popleft(), executor)
            if self.inflight:
                for outcome in executor.wait(BUSY_POLL_S if self.waiting else LEASE_S / 6):
                    self._record(outcome)
            elif self.waiting and not queue:
                time.sleep(BUSY_POLL_S)
            if time.monotonic() - beat > LEASE_S / 6:
                self.ledger.heartbeat(self.batch.id)
                beat = time.monotonic()

    def _consider(self, job: WellJob, executor: Executor) -> None:
        fingerprint, problems = self.identity.fingerprint(job)
        well_dir = self.out / job.well_id
        choose = functools.partial(
            decide,
            self.options.mode,
            current=fingerprint,
            batch_id=self.batch.id,
            batch_started=self.batch.started,
            resume_since=self.resume_since,
        )
        claim = self.ledger.claim(
            job.well_id, self.batch, fingerprint, self.versions, well_dir, choose
        )
        self._tell_problems()
        if isinstance(claim, Skipped):
            self._report(WellResult(job.well_id, "skipped", claim.reason))
        elif isinstance(claim, Busy):
            if job.well_id not in self.noted:
                self.noted.add(job.well_id)
                self.reporter.note(
                    f"{job.well_id}: being run by batch {claim.batch} (pid {claim.pid} on "
                    f"{claim.host}); waiting for it"
                )
            self.waiting[job.well_id] = (time.monotonic() + BUSY_POLL_S, job)
        elif isinstance(claim, Claimed):
            self.inflight[claim.run_id] = (job, fingerprint, claim.reasons)
            if problems:
                self._record(WellOutcome(job.well_id, claim.run_id, "failed", "; ".join(problems)))
                return
            executor.submit(
                WellTask(
                    job.well_id,
                    claim.run_id,
                    self.batch.id,
                    self.ref.digest,
                    {name: str(path) for name, path in job.inputs.items()},
                    dict(fingerprint.well),
                    str(self.out),
                    fingerprint.to_json(),
                )
            )

    def _record(self, outcome: WellOutcome) -> None:
        job, fingerprint, reasons = self.inflight.pop(outcome.run_id)
        error = self._inconsistency(outcome, fingerprint) if outcome.status == "done" else None
        self.ledger.finish(outcome, error, fingerprint.reading_manifest(outcome.manifest))
        if outcome.status == "done" and error is None:
            rejected = rejection(outcome.manifest)
            result = WellResult(
                job.well_id,
                REJECTED if rejected else "done",
                rejected or "; ".join(reasons),
                outcome.wall_time_s,
                outcome.run_id,
            )
        else:
            detail = error or outcome.error or "failed"
            result = WellResult(job.well_id, "failed", detail, outcome.wall_time_s, outcome.run_id)
        self._report(result)

    def _inconsistency(self, outcome: WellOutcome, fingerprint: Fingerprint) -> str | None:
        """Why a worker's done outcome cannot be recorded as done, if it cannot."""
        manifest = outcome.manifest
        read = {name: entry["sha256"] for name, entry in manifest["inputs"].items()}
        changed = sorted(n for n in read if read[n] != fingerprint.inputs.get(n))
        if changed:
            return f"input changed while the well ran: {', '.join(changed)}; run it again"
        plugins = self.versions["plugins"]
        if manifest["gyropipe"] != __version__ or manifest["plugins"] != plugins:
            return (
                f"the worker ran gyropipe {manifest['gyropipe']} with plugins "
                f"{manifest['plugins']}, the batch process has {__version__} with "
                f"{plugins}: install the same versions everywhere"
            )
        published = read_published(self.out / outcome.well_id)
        if published is None or published.run_id != outcome.run_id:
            return (
                f"the outputs are not visible at {self.out / outcome.well_id} from the batch "
                "process (workers must share the output directory)"
            )
        return None

    def _tell_problems(self) -> None:
        """The ledger rows that did not parse, as notes (once each)."""
        for problem in self.ledger.problems:
            self.reporter.note(f"warning: {problem}")
        self.ledger.problems.clear()

    def _report(self, result: WellResult) -> None:
        self.results[result.well] = result
        self.reporter.well(result)

    def _key(self) -> str:
        """Identity of the batch command, to recognise it when started again."""
        wells = [
            [j.well_id, {n: str(p) for n, p in sorted(j.inputs.items())}, j.well.model_dump_json()]
            for j in self.jobs
        ]
        text = json.dumps(
            [
                self.plan.digest,
                sorted(self.options.disabled),
                str(self.out),
                self.options.mode.only_changed,
                self.options.mode.rerun_failed,
                wells,
            ],
            sort_keys=True,
        )
        return hashlib.sha256(text.encode()).hexdigest()


def _check_ledger_place(ledger: Path, out: Path, jobs: Sequence[WellJob]) -> None:
    """Refuse a ledger whose files (``L``, ``L-wal``…) lie where the batch publishes: in a
    well's directory ``OUT/<well>``, its staging directory, or as a summary file (names
    compared up to case)."""
    taken = {j.well_id.casefold() for j in jobs} | {WORK_DIR, *SUMMARY_FILES}
    resolved = ledger.resolve()
    for path in (resolved, *(resolved.with_name(resolved.name + s) for s in LEDGER_SIDECARS)):
        if path.is_relative_to(out) and path != out:
            top = out / path.relative_to(out).parts[0]
            if top.name.casefold() in taken:
                raise BatchConfigError(
                    f"--ledger {ledger}: {path} is at or inside {top}, which the batch "
                    "replaces or writes: keep the ledger outside the wells' directories"
                )


def _input_bytes(job: WellJob) -> int:
    """Total size of a well's input files (missing files count 0)."""
    return sum(path.stat().st_size if path.is_file() else 0 for path in job.inputs.values())

"""``gyropipe batch``: one DAG run per well, on an executor, recorded in the ledger.

The batch process claims each well in the ledger (or skips it, see
:mod:`pipeline.batch.policy`), hands claimed wells to the executor a few at a time, and
records each outcome once the well's outputs are published. It reads no input, no file a
parameter names and no well's outputs: it stats them, takes their hashes from the ledger's
cache where their stat is unchanged (:mod:`pipeline.batch.filestate`) — a well's
publication too, by the hashes of its ``batch.json`` and ``run.json`` — and leaves every
read to the workers: the run's own hashes, a check's hashes and look at OUT/<well> when the
choice turns on what it cannot know so. A failing well never stops the others.

Each turn of its loop is one ledger transaction: the outcomes that came back are recorded
and the wells that take their place claimed, all committed or none; only then are the new
tasks handed out and the results told. Killed at any point and started again with the same
command, it completes the remaining wells and recomputes none that finished: a claim
committed but not run is settled ``interrupted`` and runs again, a run published but not
recorded is settled ``done`` (recovered), a check is dropped; nothing is counted twice.

Test-only: ``GYROPIPE_TEST_CRASH_AT=STEP:N`` makes the batch process SIGKILL itself the N-th
time it reaches STEP — ``commit`` (inside a turn's transaction, before it commits),
``committed`` (after, before anything is handed out), ``submitted`` (tasks handed out),
``received`` (outcomes back, not yet recorded) — so tests kill it exactly there.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import signal
import stat
import time
from collections import Counter, deque
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pipeline.errors import file_errors
from pipeline.executing import ExecutorSetup, PipelineRef
from pipeline.graph import Plan
from pipeline.hashing import FileKey, key_after
from pipeline.manifest import MANIFEST, REJECTED
from pipeline.registry import Registry
from pipeline.version import __version__

from .executors import Executor, open_executor
from .filestate import Seen, look
from .fingerprint import PENDING, UNREADABLE, Fingerprint, PlanIdentity
from .fleet import WellFigures, figures_json, figures_of_json
from .jobs import LEDGER, LEDGER_SIDECARS, SUMMARY_FILES, BatchConfigError, WellJob
from .ledger import LEASE_S, Busy, Claimed, Ledger, LedgerError, Skipped
from .policy import Check, Mode, Run, Skip, WellState, decide, why
from .progress import Reporter
from .publish import MARKER, WORK_DIR, clean_work_dir, output_on_disk, read_published
from .records import BatchRow, rejection
from .summary import WellResult, counts, write_summary
from .worker import WellOutcome, WellTask

BUSY_POLL_S = 0.5
"""how often a well held by another batch is looked at again"""
PREFETCH = 2
"""wells claimed per worker ahead of time, so no worker waits for the ledger"""
TURN_MAX = 256
"""wells considered in one transaction at most (skips take no worker: a long run of them
would hold the ledger's write lock)"""
CRASH_AT = "GYROPIPE_TEST_CRASH_AT"


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


@dataclass
class _Flight:
    """A claimed well handed to the executor: a run, or a check (``check``)."""

    job: WellJob
    run_id: int
    fingerprint: Fingerprint
    """the claim's (its input hashes as far as the batch process knew them)"""
    reasons: list[str]
    state: WellState
    """what the ledger knew of the well when it was claimed"""
    seen: dict[str, Seen]
    """path → the input and parameter files as the batch process saw them then"""
    known: dict[str, str]
    """path → the hashes the batch process had for them (pending where it had none)"""
    check: Check | None = None
    handed: float = 0.0
    """when its task was made, POSIX s (before any worker read a file for it)"""


@dataclass
class _Turn:
    """What one transaction decided, told and handed out once it has committed."""

    results: list[WellResult] = field(default_factory=list)
    tasks: list[WellTask] = field(default_factory=list)
    busy: list[tuple[WellJob, Busy]] = field(default_factory=list)


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
        self.figures: dict[str, WellFigures] = {}
        """done wells' fleet figures, as their workers read them"""
        self.inflight: dict[int, _Flight] = {}
        self.waiting: dict[str, tuple[float, WellJob]] = {}
        self.noted: set[str] = set()
        self.seeing: set[str] = set()
        """worker hosts seen to publish where the batch process sees OUT"""
        self.slots = max(1, options.workers)
        step, _, count = os.environ.get(CRASH_AT, "").partition(":")
        self.crash_at = (step, int(count or 1)) if step else None
        self.reached: Counter[str] = Counter()

    def run(self, executor: Executor) -> BatchReport:
        try:
            self._size(executor)
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

    def _size(self, executor: Executor) -> None:
        """Tasks the executor runs at once, if it says (a cluster: its workers' threads)."""
        slots = getattr(executor, "slots", None)
        if isinstance(slots, int) and slots > 0:
            self.slots = slots

    def _end(
        self, executor: Executor, status: str, t0: float
    ) -> tuple[list[WellResult], list[Path]]:
        """Stop the executor, close the batch in the ledger, write the summary files."""
        executor.close(cancel=status != "finished")
        for flight in self.inflight.values():
            self._report(WellResult(flight.job.well_id, "interrupted", "the batch was stopped"))
        self.inflight.clear()
        results = [self.results[j.well_id] for j in self.jobs if j.well_id in self.results]
        self.ledger.end_batch(self.batch.id, status, counts(results))
        clean_work_dir(self.out, self.ledger.running_ids())  # a killed batch's late orphans
        files = write_summary(self.out, self.batch, results, self.figures, self.ledger.ledger_id)
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
            self.batch.id, self.plan.file, len(self.jobs), self.options.executor, self.slots
        )

    def _loop(self, executor: Executor) -> None:
        # largest inputs first: the long wells do not end up alone at the end of the batch
        queue = deque(sorted(self.jobs, key=_input_bytes, reverse=True))
        outcomes: list[WellOutcome] = []
        beat = time.monotonic()
        while queue or self.inflight or self.waiting:
            now = time.monotonic()
            for well, (due, job) in list(self.waiting.items()):
                if due <= now:
                    del self.waiting[well]
                    queue.appendleft(job)
            if outcomes or (queue and len(self.inflight) < self.slots * PREFETCH):
                turn = _Turn()
                with self.ledger.group():
                    for outcome in outcomes:
                        self._settle(outcome, turn)
                    self._claim(queue, turn)
                    self._crash_point("commit")
                self._crash_point("committed")
                outcomes = []
                self._tell(turn, executor)
            if self.inflight:
                outcomes = executor.wait(BUSY_POLL_S if self.waiting else LEASE_S / 6)
                if outcomes:
                    self._crash_point("received")
            elif self.waiting and not queue:
                time.sleep(BUSY_POLL_S)
            if time.monotonic() - beat > LEASE_S / 6:
                self.ledger.heartbeat(self.batch.id)
                self._size(executor)
                beat = time.monotonic()

    def _tell(self, turn: _Turn, executor: Executor) -> None:
        """A committed turn: hand out its tasks, tell its results and the wells waited for."""
        self._tell_problems()
        for task in turn.tasks:
            executor.submit(task)
        if turn.tasks:
            self._crash_point("submitted")
        for result in turn.results:
            self._report(result)
        for job, busy in turn.busy:
            if job.well_id not in self.noted:
                self.noted.add(job.well_id)
                self.reporter.note(
                    f"{job.well_id}: being run by batch {busy.batch} (pid {busy.pid} on "
                    f"{busy.host}); waiting for it"
                )
            self.waiting[job.well_id] = (time.monotonic() + BUSY_POLL_S, job)

    def _claim(self, queue: deque[WellJob], turn: _Turn) -> None:
        """Consider wells from ``queue`` until the executor has enough (inside a turn)."""
        for _ in range(TURN_MAX):
            if not queue or len(self.inflight) >= self.slots * PREFETCH:
                return
            self._consider(queue.popleft(), turn)

    def _consider(self, job: WellJob, turn: _Turn) -> None:
        """Claim ``job`` or skip it, from the stat of its files (no file is read)."""
        seen: dict[str, Seen] = {}
        known: dict[str, str] = {}
        hashes: dict[str, str] = {}
        problems: list[str] = []
        for name, path in sorted(job.inputs.items()):
            hashes[name], problem = self._known(str(path), seen, known)
            if problem is not None:
                problems.append(f"input {name!r}: cannot read {str(path)!r}: {problem.strerror}")
        fingerprint = self.identity.fingerprint(job, hashes)
        states: list[WellState] = []

        def choose(state: WellState) -> Run | Skip | Check:
            state = replace(
                state, last_done_published=functools.partial(self._published, state, seen, known)
            )
            states.append(state)
            files = state.last_done.fingerprint.files if state.last_done is not None else {}
            digests = {path: self._known(path, seen, known)[0] for path in files}
            return self._decide(state, fingerprint.reading(files, digests))

        claim = self.ledger.claim(
            job.well_id, self.batch, fingerprint, self.versions, self.out / job.well_id, choose
        )
        if isinstance(claim, Skipped):
            turn.results.append(WellResult(job.well_id, "skipped", claim.reason))
            self._remembered_figures(job, states[-1])
        elif isinstance(claim, Busy):
            turn.busy.append((job, claim))
        elif isinstance(claim, Claimed):
            flight = _Flight(
                job, claim.run_id, fingerprint, claim.reasons, states[-1], seen, known, claim.check
            )
            if problems:
                failed = WellOutcome(job.well_id, claim.run_id, "failed", "; ".join(problems))
                self._record(flight, failed, turn)
            else:
                self.inflight[claim.run_id] = flight
                turn.tasks.append(self._task(flight))

    def _decide(self, state: WellState, current: Fingerprint) -> Run | Skip | Check:
        return decide(
            self.options.mode,
            state,
            current,
            batch_id=self.batch.id,
            batch_started=self.batch.started,
            resume_since=self.resume_since,
        )

    def _known(
        self, path: str, seen: dict[str, Seen], known: dict[str, str]
    ) -> tuple[str, OSError | None]:
        """The hash of ``path`` as its stat tells (the ledger's cache): a SHA-256, or
        ``pending``, or ``unreadable`` with the reason; how it was seen goes into ``seen``,
        the hash into ``known``."""
        found, problem = look(path)
        seen[path] = found
        if found.key is None:
            known[path] = UNREADABLE
        else:
            known[path] = self.ledger.known_hash(found.key) or PENDING
        return known[path], problem

    def _published(
        self, state: WellState, seen: dict[str, Seen], known: dict[str, str]
    ) -> bool | None:
        """Whether the last done run is what OUT/<well> holds, from the stat of its files
        alone: its ``batch.json`` and ``run.json`` hashed (the ledger's cache) as a worker
        found them published, every output it lists a regular file of its size. False where
        either file is missing; None (a worker looks) where their hashes are not known so."""
        done = state.last_done
        if done is None:
            return False
        well_dir = Path(done.out_dir)
        marker = self._known(str(well_dir / MARKER), seen, known)[0]
        manifest = self._known(str(well_dir / MANIFEST), seen, known)[0]
        if UNREADABLE in (marker, manifest):
            return False
        found = state.publication
        if found is None or (found.marker_sha256, found.manifest_sha256) != (marker, manifest):
            return None
        return all(output_on_disk(well_dir, entry) for entry in done.outputs)

    def _remembered_figures(self, job: WellJob, state: WellState) -> None:
        """A skipped well's figures on the fleet page: its last done run's, as the ledger
        holds them (else the page reads them from OUT/<well>)."""
        if state.figures is not None:
            figures = figures_of_json(state.figures)
            if figures is not None:
                self.figures[job.well_id] = figures

    def _task(self, flight: _Flight) -> WellTask:
        flight.handed = time.time()
        job, check = flight.job, flight.check
        return WellTask(
            job.well_id,
            flight.run_id,
            self.batch.id,
            self.ref.digest,
            {name: str(path) for name, path in job.inputs.items()},
            dict(flight.fingerprint.well),
            str(self.out),
            flight.fingerprint.to_json(),
            None if check is None else _check_paths(job, check),
            {} if check is not None else self._settled_hashes(flight),
            self.ledger.ledger_id,
        )

    def _settled_hashes(self, flight: _Flight) -> dict[str, tuple[FileKey, str]]:
        """Input path → (the key the batch process saw, the hash the ledger holds for it)."""
        keys = {path: seen.key for path, seen in flight.seen.items() if seen.key is not None}
        found = {}
        for path in map(str, flight.job.inputs.values()):
            digest = self.ledger.known_hash(keys[path]) if path in keys else None
            if digest is not None:
                found[path] = (keys[path], digest)
        return found

    def _settle(self, outcome: WellOutcome, turn: _Turn) -> None:
        """Record what came back of a task (inside a turn)."""
        flight = self.inflight.pop(outcome.run_id)
        if flight.check is not None:
            self._checked(flight, outcome, turn)
        else:
            self._record(flight, outcome, turn)

    def _checked(self, flight: _Flight, outcome: WellOutcome, turn: _Turn) -> None:
        """A check's hashes: skip the well (its claim dropped) or run it (made a run)."""
        assert flight.check is not None
        paths = _check_paths(flight.job, flight.check)
        digests = {path: outcome.hashes.get(path, UNREADABLE) for path in paths}
        self._learn(flight, digests)
        known = {**flight.known, **digests}
        job, state = flight.job, flight.state
        inputs = {name: known[str(path)] for name, path in job.inputs.items()}
        fingerprint = self.identity.fingerprint(job, inputs)
        files = state.last_done.fingerprint.files if state.last_done is not None else {}
        published = _held_last_done(state, outcome, self.ledger.ledger_id)
        if published:
            self._publication(flight, outcome)
        decision = self._decide(
            replace(state, last_done_published=published), fingerprint.reading(files, known)
        )
        if isinstance(decision, Skip):
            self.ledger.checked(flight.run_id, None)
            turn.results.append(WellResult(job.well_id, "skipped", decision.reason))
            if published and outcome.figures is not None:
                self.figures[job.well_id] = outcome.figures
            return
        assert isinstance(decision, Run)  # every hash is known now
        if not self.ledger.checked(flight.run_id, decision.reasons):
            lost = "its claim was settled by another batch meanwhile (this one was silent)"
            turn.results.append(WellResult(job.well_id, "interrupted", lost))
            return
        ran = replace(
            flight, fingerprint=fingerprint, reasons=decision.reasons, known=known, check=None
        )
        self.inflight[flight.run_id] = ran
        turn.tasks.append(self._task(ran))

    def _record(self, flight: _Flight, outcome: WellOutcome, turn: _Turn) -> None:
        """A run's outcome in the ledger, its reasons from its own hashes (inside a turn)."""
        job = flight.job
        fingerprint, reasons = None, None
        error = self._inconsistency(outcome) if outcome.status == "done" else None
        read = _hashes_read(job, outcome)
        if read:
            fingerprint = flight.fingerprint.completed(outcome.manifest).with_inputs(
                {name: read[str(path)] for name, path in job.inputs.items() if str(path) in read}
            )
            reasons = why(
                flight.state,
                fingerprint,
                _held_last_done(flight.state, outcome, self.ledger.ledger_id),
            )
            self._learn(flight, read)
        self.ledger.finish(outcome, error, fingerprint, reasons)
        if outcome.status == "done" and error is None:
            rejected = rejection(outcome.manifest)
            result = WellResult(
                job.well_id,
                REJECTED if rejected else "done",
                rejected or "; ".join(reasons or flight.reasons),
                outcome.wall_time_s,
                outcome.run_id,
            )
            if outcome.figures is not None:
                self.figures[job.well_id] = outcome.figures
            self._publication(flight, outcome)
        else:
            detail = error or outcome.error or "failed"
            result = WellResult(job.well_id, "failed", detail, outcome.wall_time_s, outcome.run_id)
        turn.results.append(result)

    def _publication(self, flight: _Flight, outcome: WellOutcome) -> None:
        """Remember how a worker found a well published (its fleet figures with it), and the
        hashes of its ``batch.json`` and ``run.json`` by their stat (inside a turn)."""
        found = outcome.publication
        if found is None:
            return
        figures = figures_json(outcome.figures) if outcome.figures is not None else None
        well_dir = self.out / flight.job.well_id
        files = {str(well_dir / MARKER): found.marker_sha256}
        files[str(well_dir / MANIFEST)] = found.manifest_sha256
        self.ledger.published(found, figures, files)
        self._learn(flight, files)

    def _learn(self, flight: _Flight, digests: dict[str, str]) -> None:
        """Remember the hashes a worker took of files whose stat held meanwhile: seen before
        the task and the same after, or — a file the batch process had not looked at (one a
        parameter names, found by the run) — unchanged since before the task was made."""
        entries = []
        for path, digest in digests.items():
            if flight.known.get(path) == digest:
                continue
            after = key_after(path)
            seen = flight.seen.get(path) or Seen(path, after, flight.handed)
            if (
                seen.key is not None
                and seen.settled(after)
                and (self.ledger.known_hash(seen.key) != digest)
            ):
                entries.append((path, seen.key, digest))
        self.ledger.remember(entries)

    def _inconsistency(self, outcome: WellOutcome) -> str | None:
        """Why a worker's done outcome cannot be recorded as done, if it cannot: other
        versions in the worker, or (looked at once per worker host) outputs this process
        does not see."""
        manifest = outcome.manifest
        plugins = self.versions["plugins"]
        if manifest["gyropipe"] != __version__ or manifest["plugins"] != plugins:
            return (
                f"the worker ran gyropipe {manifest['gyropipe']} with plugins "
                f"{manifest['plugins']}, the batch process has {__version__} with "
                f"{plugins}: install the same versions everywhere"
            )
        host = outcome.worker.rpartition(":")[0]
        if host not in self.seeing:
            published = read_published(self.out / outcome.well_id)
            if published is None or not published.publication.is_run(
                self.ledger.ledger_id, outcome.run_id
            ):
                return (
                    f"the outputs are not visible at {self.out / outcome.well_id} from the "
                    "batch process (workers must share the output directory)"
                )
            self.seeing.add(host)
        return None

    def _crash_point(self, step: str) -> None:
        """The test-only kill (module docstring)."""
        if self.crash_at is None or self.crash_at[0] != step:
            return
        self.reached[step] += 1
        if self.reached[step] == self.crash_at[1]:
            os.kill(os.getpid(), signal.SIGKILL)

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
    """Total size of a well's input files (missing files and other kinds count 0), one stat
    each."""
    total = 0
    for path in job.inputs.values():
        with contextlib.suppress(OSError):
            found = path.stat()
            total += found.st_size if stat.S_ISREG(found.st_mode) else 0
    return total


def _held_last_done(state: WellState, outcome: WellOutcome, ledger_id: str) -> bool:
    """Whether ``OUT/<well>`` held the well's last done run (of ledger ``ledger_id``) as the
    task began: its ledger and run id, and its ``batch.json`` as published where the ledger
    holds its hash — another ledger on the same OUT numbers its runs alike, and a marker of
    an earlier version names no ledger (``run.json`` may be edited: it is the run's as long
    as its outputs are)."""
    done, held, known = state.last_done, outcome.held, state.publication
    return (
        done is not None
        and held is not None
        and held.is_run(ledger_id, done.id)
        and (known is None or known.marker_sha256 == held.marker_sha256)
    )


def _check_paths(job: WellJob, check: Check) -> list[str]:
    """The files a check hashes: its inputs' paths, then its parameter files."""
    return [*(str(job.inputs[name]) for name in check.inputs), *check.files]


def _hashes_read(job: WellJob, outcome: WellOutcome) -> dict[str, str]:
    """path → SHA-256 of the files a run's worker hashed: the input and parameter files its
    ``run.json`` lists, or a failed run's inputs."""
    manifest: dict[str, Any] = outcome.manifest
    found = {str(job.inputs[n]): e["sha256"] for n, e in manifest.get("inputs", {}).items()}
    for entry in manifest.get("parameter_inputs", []):
        found.setdefault(entry["path"], entry["sha256"])
    return found or dict(outcome.hashes)

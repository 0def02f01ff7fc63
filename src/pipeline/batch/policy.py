"""Which wells a batch runs, and why.

- default: every well runs, except a well whose current result another batch completed
  while this one was running (it is adopted, never computed twice) and, when the same batch
  command is started again after it was killed, the wells it already completed;
- ``--only-changed``: a well runs if it is new, its last run failed or was interrupted, its
  published outputs are missing, or its fingerprint changed — the files its last done run
  read through parameters compared again (the reasons say what changed);
- ``--rerun-failed``: only wells whose last run failed or was interrupted run.
  With both flags a well runs if either says so.

The batch process decides without reading a file. A hash it does not know from the file's
stat is pending (:data:`~pipeline.batch.fingerprint.PENDING`), and whether the last done
run is still published in OUT/<well> is looked at only when the choice turns on it — known
from the stat of its ``batch.json`` and ``run.json`` where the ledger holds their hashes,
else unknown. A well that runs whatever those hold runs (:func:`why` gives its reasons from
the run's own hashes once it is recorded); one that is skipped only if its files are as its
last done run read them, with a hash pending or the publication unknown, is a
:class:`Check`: a worker hashes the files and looks at OUT/<well>, and :func:`decide`
chooses again with what it found.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

from .fingerprint import Fingerprint, changes
from .publish import Publication
from .records import RunRow


@dataclass(frozen=True)
class Mode:
    """How a batch chooses its wells."""

    only_changed: bool = False
    rerun_failed: bool = False


@dataclass(frozen=True)
class WellState:
    """What the ledger knows about a well when a batch considers it."""

    latest: RunRow | None
    """its latest finished run (done, failed or interrupted)"""
    last_done: RunRow | None
    last_done_published: bool | Callable[[], bool | None] | None
    """the last done run's outputs are still the ones in OUT/<well>; or a function that
    looks, called only when the choice turns on it; None where that cannot be told without
    reading a file there (a worker looks)"""
    publication: Publication | None = None
    """how a worker last found the last done run published (None: never recorded)"""
    figures: str | None = None
    """the last done run's fleet figures (JSON) as that worker read them"""

    def published(self) -> bool | None:
        found = self.last_done_published
        return found() if callable(found) else found


@dataclass(frozen=True)
class Run:
    reasons: list[str]


@dataclass(frozen=True)
class Skip:
    reason: str


@dataclass(frozen=True)
class Check:
    """The choice turns on files whose hash is pending: hash them in a worker (``inputs`` by
    name, ``files`` by path) and look at OUT/<well>; skipped (``then``) if they are as the
    last done run ``previous`` read them and its outputs are still there, else run."""

    inputs: list[str]
    files: list[str]
    previous: int
    then: Skip


def decide(
    mode: Mode,
    state: WellState,
    current: Fingerprint,
    *,
    batch_id: int,
    batch_started: float,
    resume_since: int | None,
) -> Run | Skip | Check:
    """Run or skip a well (module docstring); ``resume_since`` is the first batch of the
    interrupted run of this same batch command, if it is being resumed. A run's reasons are
    those known now (a pending hash taken as unchanged): :func:`why` gives them in full."""
    verdict = functools.partial(
        _verdict,
        mode,
        state,
        batch_id=batch_id,
        batch_started=batch_started,
        resume_since=resume_since,
    )
    done = state.last_done
    if done is None:
        return verdict(current, False)
    as_done = verdict(current.assuming(done.fingerprint), True)
    if isinstance(as_done, Run):
        return as_done  # it runs whatever the pending hashes and OUT/<well> hold
    # without its outputs in place no well is skipped for being as its last done run left it
    otherwise = verdict(current, False)
    if otherwise == as_done:
        return as_done
    inputs, files = current.pending()
    if inputs or files:
        return Check(inputs, files, done.id, as_done)
    published = state.published()
    if published is None:
        return Check([], [], done.id, as_done)
    return as_done if published else otherwise


def why(state: WellState, current: Fingerprint, published: bool) -> list[str]:
    """The reasons of a well's run with fingerprint ``current`` (its own hashes), its last
    done run's outputs ``published`` in OUT/<well> when it started."""
    return _reasons(state, current, published)[0] or ["unchanged, run requested"]


def _reasons(state: WellState, now: Fingerprint, published: bool) -> tuple[list[str], bool]:
    """What differs from the well's last runs, and whether its latest run failed."""
    latest, done = state.latest, state.last_done
    failed = latest is not None and latest.status in ("failed", "interrupted")
    if latest is None:
        return ["new well"], failed
    if failed:
        return [f"previous run {latest.status}", *changes(latest.fingerprint, now)], failed
    assert done is not None  # the latest finished run is done
    reasons = changes(done.fingerprint, now)
    if not published:
        reasons.append("outputs missing")
    return reasons, failed


def _verdict(
    mode: Mode,
    state: WellState,
    now: Fingerprint,
    published: bool,
    *,
    batch_id: int,
    batch_started: float,
    resume_since: int | None,
) -> Run | Skip:
    """:func:`decide` with every hash and the publication known."""
    latest, done = state.latest, state.last_done
    same_done = done is not None and done.fingerprint == now and published
    if same_done and done is not None and done.batch != batch_id:
        if done.finished is not None and done.finished >= batch_started:
            return Skip(f"done by batch {done.batch} meanwhile")
        if resume_since is not None and done.batch >= resume_since:
            return Skip(f"done before the interruption (batch {done.batch})")
    reasons, failed = _reasons(state, now, published)
    if mode.only_changed and reasons:
        return Run(reasons)
    if mode.rerun_failed and failed:
        return Run(reasons)
    if mode.only_changed:
        return Skip("unchanged")
    if mode.rerun_failed:
        return Skip("last run did not fail" if latest is not None else "never run")
    return Run(reasons or ["unchanged, run requested"])

"""Which wells a batch runs, and why.

- default: every well runs, except a well whose current result another batch completed
  while this one was running (it is adopted, never computed twice) and, when the same batch
  command is started again after it was killed, the wells it already completed;
- ``--only-changed``: a well runs if it is new, its last run failed or was interrupted, its
  published outputs are missing, or its fingerprint changed — the files its last done run
  read through parameters hashed again (the reasons say what changed);
- ``--rerun-failed``: only wells whose last run failed or was interrupted run.
  With both flags a well runs if either says so.
"""

from __future__ import annotations

from dataclasses import dataclass

from .fingerprint import Fingerprint, changes
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
    last_done_published: bool
    """the last done run's outputs are still the ones in OUT/<well>"""


@dataclass(frozen=True)
class Run:
    reasons: list[str]


@dataclass(frozen=True)
class Skip:
    reason: str


def decide(
    mode: Mode,
    state: WellState,
    current: Fingerprint,
    *,
    batch_id: int,
    batch_started: float,
    resume_since: int | None,
) -> Run | Skip:
    """Run or skip a well (module docstring); ``resume_since`` is the first batch of the
    interrupted run of this same batch command, if it is being resumed."""
    latest, done = state.latest, state.last_done
    now = current.reading(done.fingerprint.files) if done is not None else current
    same_done = done is not None and done.fingerprint == now and state.last_done_published
    if same_done and done is not None and done.batch != batch_id:
        if done.finished is not None and done.finished >= batch_started:
            return Skip(f"done by batch {done.batch} meanwhile")
        if resume_since is not None and done.batch >= resume_since:
            return Skip(f"done before the interruption (batch {done.batch})")
    failed = latest is not None and latest.status in ("failed", "interrupted")
    if latest is None:
        reasons = ["new well"]
    elif failed:
        reasons = [f"previous run {latest.status}", *changes(latest.fingerprint, current)]
    else:
        assert done is not None  # the latest finished run is done
        reasons = changes(done.fingerprint, now)
        if not state.last_done_published:
            reasons.append("outputs missing")
    if mode.only_changed and reasons:
        return Run(reasons)
    if mode.rerun_failed and failed:
        return Run(reasons)
    if mode.only_changed:
        return Skip("unchanged")
    if mode.rerun_failed:
        return Skip("last run did not fail" if latest is not None else "never run")
    return Run(reasons or ["unchanged, run requested"])

"""Timing helpers of the reader benchmarks: interleaved repetitions, medians, machine load.

Every candidate runs once per round, rounds repeat (each in its own shuffled order, seeded,
so that no candidate always follows the same one: one that runs right after another can pay
for its memory), and each candidate's median wall and CPU time
(this process's, all threads) is reported, so that a change of load during the run weighs on
every candidate alike. CPU time is this process's user + system time
(``resource.getrusage``). ``uptime`` is printed before and after.

:func:`thread_counts` and :func:`floor_lines` serve the reader benchmarks: the same
candidates at every reader thread count the machine allows, each reader's CPU and wall time
as a ratio to its floor's.
"""

from __future__ import annotations

import os
import random
import resource
import statistics
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass
class Timing:
    """Wall and CPU seconds of each run of one candidate, and its last result."""

    wall: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    result: Any = None

    @property
    def median(self) -> float:
        return statistics.median(self.wall)

    @property
    def cpu_median(self) -> float:
        return statistics.median(self.cpu)


def uptime() -> str:
    """The machine's ``uptime`` line (load averages over 1, 5 and 15 minutes)."""
    try:
        return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    except OSError:
        return "uptime unavailable"


def cpu_seconds() -> float:
    """User + system CPU seconds of this process so far (all its threads)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def thread_counts(cores: int) -> list[int]:
    """Reader thread counts to measure on ``cores`` cores: 1, then powers of two, then
    ``cores`` itself (1, 2 on two cores; 1, 2, 4, 8, 16 on sixteen)."""
    counts = [1]
    while counts[-1] * 2 < cores:
        counts.append(counts[-1] * 2)
    return [*counts, cores] if cores > 1 else counts


def load() -> str:
    """The load averages over 1, 5 and 15 minutes."""
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def interleaved(candidates: dict[str, Callable[[], Any]], rounds: int) -> dict[str, Timing]:
    """Run every candidate once per round, ``rounds`` times, in a shuffled order each round;
    only the last round's results are kept (earlier ones are freed before the next run)."""
    timings = {name: Timing() for name in candidates}
    names = list(candidates)
    order = random.Random(19)
    for round_ in range(rounds):
        for name in order.sample(names, len(names)):
            cpu, wall = cpu_seconds(), time.perf_counter()
            result = candidates[name]()
            timings[name].wall.append(time.perf_counter() - wall)
            timings[name].cpu.append(cpu_seconds() - cpu)
            timings[name].result = result if round_ == rounds - 1 else None
            del result
    return timings


def table(timings: dict[str, Timing], ours: str, width: int = 40) -> str:
    """One line per candidate: median wall and CPU ms, and each as a ratio to ``ours``
    (peer / ours: above 1, ours is faster)."""
    base = timings[ours]
    lines = [f"{'reader':<{width}}{'wall ms':>9}{'× ours':>8}{'cpu ms':>9}{'× ours':>8}"]
    for name, t in timings.items():
        lines.append(
            f"{name:<{width}}{t.median * 1e3:>9.0f}{t.median / base.median:>8.2f}"
            f"{t.cpu_median * 1e3:>9.0f}{t.cpu_median / base.cpu_median:>8.2f}"
        )
    return "\n".join(lines)


def floor_lines(
    threads: int, timings: dict[str, Timing], floor: str, readers: list[str], label: str = "floor"
) -> list[str]:
    """One line per reader at ``threads`` reader threads: median CPU and wall ms, and each
    as ours / the ``floor``'s (named ``label``; below 1: under the floor), with the load
    now."""
    base = timings[floor]
    lines = []
    for name in readers:
        t = timings[name]
        lines.append(
            f"threads {threads:>2}  {name:<24} CPU {t.cpu_median * 1e3:6.0f} ms / {label} "
            f"{base.cpu_median * 1e3:6.0f} = {t.cpu_median / base.cpu_median:5.2f}   wall "
            f"{t.median * 1e3:6.0f} ms / {label} {base.median * 1e3:6.0f} = "
            f"{t.median / base.median:5.2f}   (load {load()})"
        )
    return lines

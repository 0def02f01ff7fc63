"""Timing helpers of the reader benchmarks: interleaved repetitions, medians, machine load.

Every candidate runs once per round, rounds repeat (each in its own shuffled order, seeded,
so that no candidate always follows the same one: one that runs right after another can pay
for its memory), and each candidate's median wall and CPU time
(this process's, all threads) is reported, so that a change of load during the run weighs on
every candidate alike. ``uptime`` is printed before and after.
"""

from __future__ import annotations

import random
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


def interleaved(candidates: dict[str, Callable[[], Any]], rounds: int) -> dict[str, Timing]:
    """Run every candidate once per round, ``rounds`` times, in a shuffled order each round;
    only the last round's results are kept (earlier ones are freed before the next run)."""
    timings = {name: Timing() for name in candidates}
    names = list(candidates)
    order = random.Random(19)
    for round_ in range(rounds):
        for name in order.sample(names, len(names)):
            cpu, wall = time.process_time(), time.perf_counter()
            result = candidates[name]()
            timings[name].wall.append(time.perf_counter() - wall)
            timings[name].cpu.append(time.process_time() - cpu)
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

"""How the text readers share the machine: blocks worked on threads a few ahead and handed
on in order (:func:`~pipeline.io.arrow_text.in_order`), and the other processes' load
told from this process's own (:func:`~pipeline.io.arrow_text.others_load`)."""

from __future__ import annotations

import os
import random
import threading
import time

import pytest

from pipeline.io import arrow_text
from pipeline.io.arrow_text import CpuTimes, cpu_times, in_order, others_load


def _slow_square(started: list[int]) -> object:
    """Work that notes what it started and takes a random while (so threads finish out of
    order)."""
    rng = random.Random(3)
    pauses = [rng.uniform(0.0, 0.004) for _ in range(64)]

    def work(item: int) -> int:
        started.append(item)
        time.sleep(pauses[item])
        return item * item

    return work


@pytest.mark.parametrize("threads", [1, 2, 3])
def test_results_come_in_order_at_most_threads_ahead(threads: int) -> None:
    started: list[int] = []
    handed = []
    for item, result in in_order(range(40), _slow_square(started), threads):  # type: ignore[arg-type]
        assert result == item * item
        assert max(started) <= item + threads  # never more than `threads` items ahead
        handed.append(item)
    assert handed == list(range(40))
    assert sorted(started) == list(range(40))  # each worked once


def test_an_error_is_raised_at_its_item_and_later_work_stops() -> None:
    started: list[int] = []

    def work(item: int) -> int:
        started.append(item)
        if item == 5:
            raise ValueError("bad item 5")
        return item

    blocks = in_order(range(40), work, 2)
    handed = [next(blocks)[0] for _ in range(5)]
    with pytest.raises(ValueError, match="bad item 5"):
        next(blocks)
    assert handed == [0, 1, 2, 3, 4]
    assert max(started) <= 6  # none past the two ahead of the last one handed on (4)


def test_a_consumer_that_stops_leaves_no_thread_working() -> None:
    before = threading.active_count()
    started: list[int] = []
    blocks = in_order(range(1000), _slow_square(started), 3)
    for item, _ in blocks:
        if item == 4:
            break
    blocks.close()  # type: ignore[attr-defined]
    assert threading.active_count() == before
    assert max(started) <= 7
    count = len(started)
    time.sleep(0.02)
    assert len(started) == count


def test_the_other_processes_load_leaves_out_this_process() -> None:
    """Over 2 s the machine's cores were busy 3.1 s, 1.9 s of it this process's threads:
    the others kept 0.6 of a core busy."""
    before, after = CpuTimes(10.0, 500.0, 7.0), CpuTimes(12.0, 503.1, 8.9)
    assert others_load(before, after) == pytest.approx(0.6)
    assert others_load(after, CpuTimes(13.0, 503.5, 9.4)) == 0.0  # tick rounding: never < 0


def test_this_process_busy_shows_in_its_own_cpu_time() -> None:
    before = cpu_times()
    if before is None:
        pytest.skip("no /proc/stat on this system")
    end = time.process_time() + 0.3  # /proc counts in 10 ms ticks, sampled: a margin
    while time.process_time() < end:
        pass
    after = cpu_times()
    assert after is not None
    assert after.own - before.own >= 0.2
    assert after.machine - before.machine >= 0.15  # the machine saw it (10 ms ticks)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork on this system")
def test_a_forked_process_does_not_compare_its_time_with_its_parents() -> None:
    """A batch worker forked from a process that has looked: its own CPU time restarts
    from zero, so it looks afresh."""
    arrow_text.use_threads()
    assert arrow_text._last or arrow_text.cpu_times() is None
    pid = os.fork()
    if pid == 0:  # the child: exit status 0 if it starts with no previous look
        os._exit(0 if not arrow_text._last else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0

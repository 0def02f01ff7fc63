"""How the text readers work on threads: blocks worked on threads a few ahead and handed
on in order (:func:`~pipeline.io.arrow_text.in_order`)."""

from __future__ import annotations

import random
import threading
import time

import pytest

from pipeline.io.arrow_text import in_order


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

"""The executor ``serial``: each well of a batch run in the batch process itself, one after
another, as it is submitted — what a plugin writes to add an executor (Ray, a cluster
scheduler), reduced to its simplest. It imports gyropipe only from :mod:`pipeline.plugin`."""

from __future__ import annotations

from collections.abc import Callable

from pipeline.plugin import ExecutorDef, ExecutorSetup, WellOutcome, WellTask, hookimpl, run_well


class SerialExecutor:
    """Runs each task at once in this process; ``wait`` hands back what has run since."""

    def __init__(self, setup: ExecutorSetup) -> None:
        self._ref = setup.ref  # the batch's pipeline: run_well builds its plan once
        self._finished: list[WellOutcome] = []

    def submit(self, task: WellTask) -> None:
        self._finished.append(run_well(task, self._ref))

    def wait(self, timeout: float) -> list[WellOutcome]:
        finished, self._finished = self._finished, []
        return finished

    def close(self, cancel: bool) -> None:
        self._finished = []


@hookimpl
def gyropipe_register_executors(register: Callable[[ExecutorDef], None]) -> None:
    register(
        ExecutorDef("serial", "every well in the batch process, one at a time", SerialExecutor)
    )

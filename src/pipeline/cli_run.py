"""What ``gyropipe run`` says of a finished run: the input-file and survey-check warnings
raised while it ran, the validity verdicts, and its last line — the run's status, its
acceptance and its QC verdict. Imported when ``run`` runs, not at ``--help``."""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path

import click
import pyarrow as pa

from pipeline.api.run import RunResult
from pipeline.graph import Plan
from pipeline.manifest import REJECTED
from pipeline.qc.gates import failed_gates


@contextlib.contextmanager
def warnings_echoed() -> Iterator[None]:
    """Print each input-file and survey-check warning raised inside as one ``warning:``
    line on stderr (every time, in order); other warnings are left to Python."""
    from pipeline.errors import InputFileWarning, SurveyCheckWarning

    caught: list[warnings.WarningMessage] = []
    try:
        with warnings.catch_warnings(record=True) as recorded:
            caught = recorded
            warnings.simplefilter("always", InputFileWarning)
            warnings.simplefilter("always", SurveyCheckWarning)
            yield
    finally:
        for warning in caught:
            if issubclass(warning.category, (InputFileWarning, SurveyCheckWarning)):
                click.echo(f"warning: {warning.message}", err=True)
            else:
                warnings.warn_explicit(
                    warning.message, warning.category, warning.filename, warning.lineno
                )


def qc_lines(plan: Plan, result: RunResult) -> list[str]:
    """The verdicts of the run's validity summaries (other outputs are not read back)."""
    from pipeline.qc.tables import QcSummary, diagnosis_lines

    return [
        line
        for stage in plan.stages
        for port, contract in stage.definition.outputs.items()
        if contract is QcSummary
        for line in diagnosis_lines(f"{stage.id}.{port}", result.tables[f"{stage.id}.{port}"])
    ]


def qc_verdict_of(plan: Plan, result: RunResult) -> str | None:
    """The run's QC verdict line (:func:`pipeline.qc.verdict.qc_verdict`) over its check
    tables, a free gyro's in-run/out-run comparisons, the checks of stations files' own
    positions its trajectories record (each once: later stages keep a trajectory's record)
    and the stations its validity summaries and compassing rejects drop."""
    from pipeline.drift.tables import InOutQc
    from pipeline.qc.dropped import dropped_stations
    from pipeline.qc.tables import QcResults, QcSummary
    from pipeline.qc.verdict import inout_checks, qc_verdict
    from pipeline.survey.crosscheck import PositionCheck, position_check_of
    from pipeline.tables import CheckResults, CompassRejects, Trajectory

    checks: list[pa.Table] = []
    others: list[tuple[str, int, Sequence[float]]] = []
    dropping: list[pa.Table] = []
    positions: list[PositionCheck] = []
    for stage in plan.stages:
        for port, contract in stage.definition.outputs.items():
            if issubclass(contract, CheckResults | QcResults):
                checks.append(result.tables[f"{stage.id}.{port}"])
            elif issubclass(contract, InOutQc):
                others.extend(inout_checks(result.tables[f"{stage.id}.{port}"]))
            elif issubclass(contract, QcSummary | CompassRejects):
                dropping.append(result.tables[f"{stage.id}.{port}"])
            elif issubclass(contract, Trajectory):
                check = position_check_of(result.tables[f"{stage.id}.{port}"])
                if check is not None and check not in positions:
                    positions.append(check)
    return qc_verdict(
        checks,
        [*others, *(("file_positions", c.compared, c.beyond_md) for c in positions)],
        dropped_stations([*dropping, *checks]),
    )


def verdict_line(plan: Plan, result: RunResult, manifest: Path) -> str:
    """``ok: OUT/run.json — QC: …`` or ``rejected: OUT/run.json — acceptance FAILED (…);
    QC: …``: the status ``run.json`` records, then what the run found."""
    said = [qc_verdict_of(plan, result)]
    if result.manifest["status"] == REJECTED:
        said.insert(0, f"acceptance FAILED ({', '.join(failed_gates(result.manifest))})")
    verdict = "; ".join(s for s in said if s)
    return f"{result.manifest['status']}: {manifest}" + (f" — {verdict}" if verdict else "")

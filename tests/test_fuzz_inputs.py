"""Every input kind, fuzzed (harness: ``fuzz_support``; long run:
``benchmarks/fuzz_inputs.py``): a few hundred seeded, mutated inputs, each refused with an
error naming the file and a location, or accepted with finite, contract-valid output (its
copy readable again); never a traceback, never a hang. Refused inputs of each family also
go through the ``gyropipe`` command: exit 1 or 2, one ``error:`` line, no traceback."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from fuzz_support import (
    ACCEPTED,
    BAD,
    INPUT_KIND_NAMES,
    MULTILINE,
    NONFINITE,
    REFUSED,
    UNLOCATED,
    Context,
    Fuzzer,
    Outcome,
    check_table,
)
from pipeline.tables import Stations
from tests_support import CliResult, gyropipe_cli

SEED = 20261121
COUNT = 25
"""Inputs per kind: 12 kinds × 25 in a few seconds (the fault kinds: test_fuzz_faults)."""
NOT_ALLOWED = BAD | {UNLOCATED, MULTILINE}


@pytest.fixture(scope="module")
def fuzzer(tmp_path_factory: pytest.TempPathFactory) -> Fuzzer:
    return Fuzzer(tmp_path_factory.mktemp("fuzz"))


SPOT = {
    "csv-stations": ("convert", "{input}", "{out}.parquet"),
    "mcap": ("convert", "--kind", "samples", "{input}", "{out}.csv"),
    "pipeline": ("validate", "{input}"),
}
"""Commands the CLI spot check runs on a refused input of each kind (a text file, a binary
file, a YAML file)."""

Spot = tuple[str, Outcome, Path, CliResult]


@pytest.fixture(scope="module")
def spot(fuzzer: Fuzzer, tmp_path_factory: pytest.TempPathFactory) -> list[Spot]:
    """The first refused input of each :data:`SPOT` kind, given to ``gyropipe``."""
    work = tmp_path_factory.mktemp("spot")
    done = []
    for kind, command in SPOT.items():
        outcome = next(o for o in fuzzer.fuzz(kind, SEED, COUNT) if o.label == REFUSED and o.data)
        path = work / f"refused-{kind}-{outcome.index}{outcome.suffix}"
        path.write_bytes(outcome.data)
        args = [a.format(input=path, out=work / f"out-{kind}") for a in command]
        done.append((kind, outcome, path, gyropipe_cli(*args)))
    return done


@pytest.fixture(scope="module")
def outcomes(fuzzer: Fuzzer) -> dict[str, list[Outcome]]:
    return {kind: list(fuzzer.fuzz(kind, SEED, COUNT)) for kind in INPUT_KIND_NAMES}


def shown(bad: list[Outcome]) -> str:
    return "\n".join(
        f"{o.kind} #{o.index} ({o.label}) {list(o.mutations)}: {o.detail[:500]}" for o in bad
    )


def test_every_seed_is_accepted(fuzzer: Fuzzer) -> None:
    """The seeds are valid inputs (the mutations, not the seeds, make the refusals)."""
    for kind in (fuzzer.kinds[name] for name in INPUT_KIND_NAMES):
        for seed in kind.seeds:
            for index in (0, 1):  # the kind found (auto), the kind asked for
                ctx = Context(kind, seed, lambda table: None, table=seed.table)
                outcome = fuzzer.run(kind, index, seed.data, seed, ctx)
                assert outcome.label == ACCEPTED, f"{kind.name}/{seed.name}: {outcome.detail}"


@pytest.mark.parametrize("kind", INPUT_KIND_NAMES)
def test_fuzzed_inputs_are_refused_located_or_accepted_valid(
    outcomes: dict[str, list[Outcome]], kind: str
) -> None:
    done = outcomes[kind]
    bad = [o for o in done if o.label in NOT_ALLOWED]
    assert not bad, shown(bad)
    warned = [f"{o.kind} #{o.index}: {o.warnings}" for o in done if o.warnings]
    assert not warned, warned  # NumPy's overflow warnings and the like: printed on stderr
    labels = Counter(o.label for o in done)
    assert labels[REFUSED], f"no {kind} input was refused: {labels}"


def test_the_same_seed_makes_the_same_inputs(fuzzer: Fuzzer) -> None:
    for kind in ("csv-stations", "parquet", "pipeline"):
        spec = fuzzer.kinds[kind]
        assert fuzzer.make(spec, SEED, 3)[0] == fuzzer.make(spec, SEED, 3)[0]
        assert fuzzer.make(spec, SEED, 3)[0] != fuzzer.make(spec, SEED + 1, 3)[0]


def test_refused_inputs_through_the_cli(spot: list[Spot]) -> None:
    """A refused input of a text, a binary and a YAML kind through ``gyropipe``: exit 1 or
    2, one ``error:`` line, the file named (a pipeline's problems follow the line,
    indented), warnings aside; no traceback."""
    for kind, outcome, path, result in spot:
        stderr = result.stderr
        where = f"{kind} #{outcome.index} {list(outcome.mutations)}:\n{stderr}"
        assert result.returncode in (1, 2), where
        assert "Traceback" not in stderr, where
        lines = [line for line in stderr.splitlines() if not line.startswith("warning:")]
        assert lines and lines[0].startswith("error:"), where
        assert all(line.startswith("  ") for line in lines[1:]), where
        assert path.name in stderr, where


def test_an_undefined_azimuth_is_non_finite_only_off_vertical() -> None:
    """The harness's own statement of the rule: NaN azimuth within 1° of vertical is an
    undefined azimuth; anywhere else it is a non-finite output."""
    stations = Stations.compiled()
    vertical = stations.make_table(
        {"md": [0.0, 30.0], "inc": [0.5, 10.0], "azi": [float("nan"), 40.0]},
        north_reference="true",
    )
    inclined = stations.make_table(
        {"md": [0.0, 30.0], "inc": [5.0, 10.0], "azi": [float("nan"), 40.0]},
        north_reference="true",
    )
    assert check_table(vertical, "stations") is None
    outcome = check_table(inclined, "stations")
    assert outcome is not None and outcome[0] == NONFINITE

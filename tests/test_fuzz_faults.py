"""The fault kinds of the fuzz suite (``fuzz_faults``; long run: ``benchmarks/
fuzz_inputs.py``): the same seed makes the same faults; special files named in a manifest
(FIFO, socket, /dev/zero, a directory, symlinks) are refused located or accepted, never a
hang or a traceback; a ledger fault is really made in the copy of a finished batch."""

from __future__ import annotations

import json
import random
import sqlite3
from collections import Counter
from pathlib import Path

import pytest

from fuzz_faults import FAULT_KINDS, LEDGER, MANIFEST_SPECIAL, SPECIALS, _corrupt, make_fault
from fuzz_support import ACCEPTED, REFUSED, SPECIAL_MANIFEST, Fuzzer

SEED = 20261201


@pytest.fixture(scope="module")
def fuzzer(tmp_path_factory: pytest.TempPathFactory) -> Fuzzer:
    return Fuzzer(tmp_path_factory.mktemp("faults"))


@pytest.mark.parametrize("kind", FAULT_KINDS)
def test_the_same_seed_makes_the_same_faults(kind: str) -> None:
    def made(seed: int, index: int) -> bytes:
        return make_fault(kind, random.Random(f"{seed}/{kind}/{index}"), SPECIAL_MANIFEST)[0]

    assert made(SEED, 3) == made(SEED, 3)
    assert len({made(SEED, i) for i in range(20)}) > 1


def test_special_files_in_a_manifest_are_refused_or_skipped_never_hung(fuzzer: Fuzzer) -> None:
    done = list(fuzzer.fuzz(MANIFEST_SPECIAL, SEED, 24))
    labels = Counter(o.label for o in done)
    assert set(labels) <= {ACCEPTED, REFUSED}, [(o.mutations, o.detail) for o in done]
    made = {m.split("@")[0].removeprefix("special-") for o in done for m in o.mutations}
    assert made <= set(SPECIALS) and len(made) >= 8, made


def test_a_ledger_fault_edits_the_ledger(tmp_path: Path) -> None:
    ledger = tmp_path / "ledger.sqlite"
    with sqlite3.connect(ledger) as db:
        db.execute("CREATE TABLE runs (reasons TEXT NOT NULL, status TEXT CHECK (status = 'a'))")
        db.execute("INSERT INTO runs VALUES ('[]', 'a')")
    _corrupt(tmp_path, ["sql", "runs", "reasons", "'not json'"])
    _corrupt(tmp_path, ["sql", "runs", "status", "'bogus'"])  # past the CHECK
    with sqlite3.connect(ledger) as db:
        assert db.execute("SELECT reasons, status FROM runs").fetchall() == [("not json", "bogus")]
    faults = json.loads(make_fault(LEDGER, random.Random(1), b"")[0])
    assert faults and all(f[0] in ("sql", "marker", "file") for f in faults)

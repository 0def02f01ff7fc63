"""Two ledgers (``--ledger``) publishing into one OUT number their runs alike (each ledger's
run ids are its own row ids): a run is known by (ledger id, run id), the ledger's identity
written into ``batch.json`` with the run id. Crash recovery and the fleet page take another
ledger's run of the same id for none of theirs; a ``batch.json`` naming no ledger (an
earlier version's) is known by its run id alone."""

from __future__ import annotations

import contextlib
import html
import json
import sqlite3
from pathlib import Path

from batch_support import change_one_azimuth, make_wells, runs, summary

from pipeline.batch.fingerprint import PENDING, PlanIdentity
from pipeline.batch.fleet import well_figures
from pipeline.batch.jobs import jobs_from_glob
from pipeline.batch.ledger import Ledger
from pipeline.batch.policy import Run
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.spec import load_spec
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli


def ledger_id(path: Path) -> str:
    """The identity a ledger file holds (read with plain sqlite3)."""
    with contextlib.closing(sqlite3.connect(path)) as db:
        (found,) = db.execute("SELECT id FROM ledger").fetchone()
    return str(found)


def batch(survey: Path, inputs: Path, out: Path, ledger: Path, *flags: str) -> None:
    result = gyropipe_cli(
        "batch", survey, "--inputs", inputs / "*.csv", "--out", out, "--ledger", ledger, *flags
    )
    assert result.returncode == 0, result.output


def wells_of_two_ledgers(tmp_path: Path) -> tuple[Path, Path]:
    """W1 from the bundled stations (``in``) and from other stations (``other``)."""
    make_wells(tmp_path / "in", ["W1"])
    (theirs,) = make_wells(tmp_path / "other", ["W1"])
    change_one_azimuth(theirs)
    return tmp_path / "in", tmp_path / "other"


def test_a_dead_claim_is_not_recovered_from_another_ledgers_run_of_its_id(
    tmp_path: Path, survey: Path
):
    """The first ledger's batch claims W1 (its run 1) and is gone (silent past the lease)
    before it publishes; the second ledger's run 1 of W1, from other stations, is published
    there meanwhile. The first ledger's next batch settles its run 1 interrupted — not done
    with the other ledger's manifest and hashes — and runs W1 again from its own stations."""
    mine, theirs = wells_of_two_ledgers(tmp_path)
    out, first, second = tmp_path / "out", tmp_path / "first.sqlite", tmp_path / "second.sqlite"
    registry = load_registry()
    plan = build_plan(load_spec(survey), registry)
    (job,) = jobs_from_glob(str(mine / "*.csv"), ["stations"], WellMetadata())
    fingerprint = PlanIdentity.of(plan, registry).fingerprint(job, {"stations": PENDING})
    ledger = Ledger(first)
    dead = ledger.start_batch("key", str(survey), plan.digest, out, {})
    claim = ledger.claim("W1", dead, fingerprint, {}, out / "W1", lambda _: Run(["new well"]))
    ledger.close()
    with contextlib.closing(sqlite3.connect(first, isolation_level=None)) as db:
        db.execute("UPDATE batches SET heartbeat = 0")  # silent since 1970: taken for dead

    batch(survey, theirs, out, second)
    marker = json.loads((out / "W1" / "batch.json").read_text())
    assert (marker["run_id"], marker["ledger_id"]) == (claim.run_id, ledger_id(second))

    batch(survey, mine, out, first, "--only-changed")
    settled, again = runs(first)
    assert (settled["id"], settled["status"]) == (claim.run_id, "interrupted")
    assert json.loads(settled["inputs"]) == {}  # not the other ledger's run.json
    assert again["status"] == "done" and summary(out)["W1"]["status"] == "done"
    manifest = json.loads((out / "W1" / "run.json").read_text())
    assert manifest["inputs"]["stations"]["path"] == str(mine / "W1.csv")


def test_the_fleet_page_tells_another_ledgers_run_of_the_same_id(tmp_path: Path, survey: Path):
    """Each ledger's run 1 of W1 published in turn: the first ledger's page tells that the
    outputs there are the other ledger's run (not its own run 1); the second's does not."""
    mine, theirs = wells_of_two_ledgers(tmp_path)
    out, first, second = tmp_path / "out", tmp_path / "first.sqlite", tmp_path / "second.sqlite"
    batch(survey, mine, out, first)
    batch(survey, theirs, out, second)
    told = (
        f"the outputs published are of run 1 of another ledger ({ledger_id(second)}), "
        "not this ledger's run 1"
    )
    assert told in well_figures(out / "W1", 1, ledger_id=ledger_id(first)).problems
    assert well_figures(out / "W1", 1, ledger_id=ledger_id(second)).problems == ()

    pages = {}
    for name, ledger in (("first", first), ("second", second)):
        page = tmp_path / f"{name}.html"
        status = gyropipe_cli("status", out, "--ledger", ledger, "--html", page)
        assert status.returncode == 0, status.output
        pages[name] = html.unescape(page.read_text())
    assert f"Output: {told}" in pages["first"]
    assert "another ledger" not in pages["second"]


def test_a_ledger_has_one_identity_and_an_earlier_ledger_gets_one_on_open(tmp_path: Path):
    path = tmp_path / "ledger.sqlite"
    Ledger(path).close()
    made = ledger_id(path)
    assert len(made) == 36 and made != ledger_id(_new(tmp_path / "other.sqlite"))
    opened = Ledger(path)
    assert opened.ledger_id == made
    opened.close()
    with contextlib.closing(sqlite3.connect(path, isolation_level=None)) as db:
        db.execute("DROP TABLE ledger")  # as an earlier version made it
    opened = Ledger(path)
    assert opened.ledger_id == ledger_id(path) != made
    opened.close()
    opened = Ledger(path)
    assert opened.ledger_id == ledger_id(path)  # kept from then on
    opened.close()


def _new(path: Path) -> Path:
    Ledger(path).close()
    return path

"""A damaged ledger or published marker is read defensively: ``status``, ``history`` and
``batch`` tell the row that does not parse (well, run id, column) as a warning line and leave
it out, and a well whose rows or marker cannot be read runs again; never a traceback. The
ledgers are real SQLite files damaged with plain ``sqlite3`` (issue 32 item 8)."""

from __future__ import annotations

import json
import os
import shutil
import sqlite3
from pathlib import Path

import pytest
from batch_support import make_wells, runs, spawn, summary, survey_pipeline

from tests_support import gyropipe_cli

WELLS = ["C1", "C2"]


@pytest.fixture(scope="module")
def batch_done(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """A finished batch of two wells: (its pipeline, its output directory)."""
    root = tmp_path_factory.mktemp("corrupt")
    survey = survey_pipeline(root)
    make_wells(root / "in", WELLS)
    out = root / "out"
    gyropipe_cli("batch", survey, "--inputs", root / "in" / "*.csv", "--out", out, check=True)
    return survey, out


@pytest.fixture
def damaged(batch_done: tuple[Path, Path], tmp_path: Path) -> tuple[Path, Path]:
    """A copy of the finished batch's output tree (pipeline, OUT) to damage."""
    survey, out = batch_done
    copy = tmp_path / "out"
    shutil.copytree(out, copy)
    for well in WELLS:  # the markers name the copy's directories, as the batch wrote them
        manifest = json.loads((copy / well / "run.json").read_text())
        for entry in manifest["outputs"]:
            entry["path"] = str(copy / well / entry["file"])
        (copy / well / "run.json").write_text(json.dumps(manifest))
    with sqlite3.connect(copy / "ledger.sqlite") as db:
        db.execute("UPDATE runs SET out_dir = replace(out_dir, ?, ?)", (str(out), str(copy)))
    return survey, copy


def run_id(out: Path, well: str) -> int:
    return int(next(r["id"] for r in runs(out / "ledger.sqlite") if r["well"] == well))


def damage(out: Path, sql: str, *params: object) -> None:
    with sqlite3.connect(out / "ledger.sqlite") as db:
        db.execute("PRAGMA ignore_check_constraints = ON")
        db.execute(sql, params)


CORRUPTIONS = {
    "reasons": ("UPDATE runs SET reasons = 'new well, not JSON' WHERE well = 'C1'", "is not JSON"),
    "fingerprint": (
        "UPDATE runs SET fingerprint = json_set(fingerprint, '$.extra', 1) WHERE well = 'C1'",
        "is not an object with exactly the keys",
    ),
    "wall_time_s": ("UPDATE runs SET wall_time_s = 'slow' WHERE well = 'C1'", "is not valid"),
    "status": ("UPDATE runs SET status = 'exploded' WHERE well = 'C1'", "is 'exploded'"),
    "note": (
        "UPDATE runs SET note = CAST(x'c328ff' AS TEXT) WHERE well = 'C1'",
        "is not valid UTF-8",
    ),
}


@pytest.mark.parametrize("column", sorted(CORRUPTIONS))
def test_status_and_history_tell_a_damaged_run_row_and_leave_it_out(
    damaged: tuple[Path, Path], column: str
):
    _, out = damaged
    sql, problem = CORRUPTIONS[column]
    bad = run_id(out, "C1")
    damage(out, sql)
    warning = f"run {bad} of well 'C1': {column} {problem}"

    status = gyropipe_cli("status", out)
    assert status.returncode == 0, status.output
    assert warning in status.stderr and status.stderr.startswith("warning: ledger ")
    assert status.stderr.rstrip().endswith("; the row is left out")
    wells = [line.split()[0] for line in status.stdout.splitlines()[3:]]
    assert wells == ["C2"]
    document = gyropipe_cli("status", out, "--json")
    assert [w["well"] for w in json.loads(document.stdout)["wells"]] == ["C2"]

    history = gyropipe_cli("history", "C1", "--dir", out)
    assert history.returncode == 2  # no readable run of C1 is left
    assert warning in history.stderr and "error: no runs of well 'C1'" in history.stderr
    assert gyropipe_cli("history", "C2", "--dir", out).returncode == 0


@pytest.mark.parametrize("column", ["fingerprint", "status"])
def test_a_batch_runs_a_well_whose_ledger_row_is_damaged_again(
    damaged: tuple[Path, Path], column: str
):
    survey, out = damaged
    bad = run_id(out, "C1")
    damage(out, CORRUPTIONS[column][0])
    inputs = out.parent / "in"
    make_wells(inputs, WELLS)
    again = gyropipe_cli(
        "batch", survey, "--inputs", inputs / "*.csv", "--out", out, "--only-changed", "--quiet"
    )
    assert again.returncode == 0, again.output
    assert f"run {bad} of well 'C1': {column} " in again.stderr
    assert {w: r["status"] for w, r in summary(out).items()} == {"C1": "done", "C2": "skipped"}
    assert json.loads((out / "C1" / "batch.json").read_text())["run_id"] > bad


def test_a_damaged_batch_row_is_told_and_its_runs_still_shown(damaged: tuple[Path, Path]):
    _, out = damaged
    damage(out, "UPDATE batches SET options = '{not json' WHERE id = 1")
    status = gyropipe_cli("status", out)
    assert status.returncode == 0, status.output
    assert "batch 1: options is not JSON; the row is left out" in status.stderr
    assert [line.split()[0] for line in status.stdout.splitlines()[2:]] == ["C1", "C2"]


MARKERS = {
    "batch.json {}": ("batch.json", lambda text: "{}"),
    "batch.json not JSON": ("batch.json", lambda text: text[:-5]),
    "run.json without sizes": (
        "run.json",
        lambda text: json.dumps(
            {
                **json.loads(text),
                "outputs": [
                    {k: v for k, v in o.items() if k != "bytes"}
                    for o in json.loads(text)["outputs"]
                ],
            }
        ),
    ),
    "run.json outputs not a list": (
        "run.json",
        lambda text: json.dumps({**json.loads(text), "outputs": {"a": 1}}),
    ),
}


@pytest.mark.parametrize("case", sorted(MARKERS))
def test_a_damaged_published_marker_makes_its_well_run_again(damaged: tuple[Path, Path], case: str):
    survey, out = damaged
    name, edit = MARKERS[case]
    marker = out / "C2" / name
    marker.write_text(edit(marker.read_text()))
    assert gyropipe_cli("status", out).returncode == 0
    inputs = out.parent / "in"
    make_wells(inputs, WELLS)
    before = sorted(p.name for p in (out / "C2").iterdir())
    again = gyropipe_cli(
        "batch", survey, "--inputs", inputs / "*.csv", "--out", out, "--only-changed", "--quiet"
    )
    last = summary(out)
    assert last["C1"]["status"] == "skipped"
    if case == "run.json outputs not a list":  # which files are the run's is unknown: kept
        assert again.returncode == 1
        assert last["C2"]["status"] == "failed"
        assert "holds files that are not a previous run's" in last["C2"]["detail"]
        assert sorted(p.name for p in (out / "C2").iterdir()) == before
    else:
        assert again.returncode == 0, again.output
        assert last["C2"]["status"] == "done" and last["C2"]["detail"] == "outputs missing"


@pytest.mark.parametrize("name", ["run.json", "batch.json"])
def test_a_fifo_in_place_of_a_published_file_is_named_not_waited_on(
    damaged: tuple[Path, Path], name: str
):
    """A FIFO where a well's ``run.json`` or ``batch.json`` belongs (a hostile user, a
    broken copy): ``status --html`` writes the page, naming it, and the batch ends —
    neither waits for good on a FIFO no one writes to (real processes, stopped after
    60 s). Without a readable ``run.json`` which files are the run's is unknown: the well
    fails, its directory kept; a ``batch.json`` is the batch's own: the well runs again."""
    survey, out = damaged
    (out / "C2" / name).unlink()
    os.mkfifo(out / "C2" / name)
    inputs = out.parent / "in"
    make_wells(inputs, WELLS)
    for args in (["status", out, "--html"], ["batch", survey, "--inputs", inputs / "*.csv",
                 "--out", out, "--only-changed", "--quiet"]):  # fmt: skip
        process = spawn(*args, stderr=out.parent / "stderr.txt")
        try:
            process.wait(60)
        finally:
            process.kill()
        assert process.returncode == (0 if args[0] == "status" or name == "batch.json" else 1)
        if args[0] == "status" and name == "run.json":
            page = (out / "fleet.html").read_text(encoding="utf-8")
            assert "run.json cannot be read (not a regular file (a FIFO))" in page
    last = summary(out)
    assert last["C1"]["status"] == "skipped"
    if name == "run.json":
        assert last["C2"]["status"] == "failed"
        assert "holds files that are not a previous run's" in last["C2"]["detail"]
        assert (out / "C2" / name).is_fifo()
    else:
        assert (last["C2"]["status"], last["C2"]["detail"]) == ("done", "outputs missing")
        newest = max(int(r["id"]) for r in runs(out / "ledger.sqlite") if r["well"] == "C2")
        assert json.loads((out / "C2" / name).read_text())["run_id"] == newest

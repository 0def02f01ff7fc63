"""Reprocessing: ``--only-changed`` re-runs exactly the wells whose inputs, pipeline,
params, header or software changed and says why; ``--rerun-failed``; and the reasons
themselves (fingerprint comparison) for plugin and version changes."""

from __future__ import annotations

import json
import os
from pathlib import Path

from batch_support import (
    assert_complete,
    change_one_azimuth,
    corrupt,
    log_events,
    make_wells,
    runs,
    summary,
)

from pipeline.batch.fingerprint import PENDING, Fingerprint, changes
from pipeline.batch.policy import Check, Mode, Run, Skip, WellState, decide, why
from pipeline.batch.records import RunRow
from tests_support import gyropipe_cli


def test_only_changed_reruns_exactly_the_touched_well_and_says_why(tmp_path: Path, survey: Path):
    paths = make_wells(tmp_path / "in", ["W1", "W2", "W3", "W4"])
    out = tmp_path / "out"
    pattern = tmp_path / "in" / "*.csv"
    first = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--workers", "2")
    assert first.returncode == 0, first.output
    before = {w: (out / w / "trajectory.csv").read_bytes() for w in ("W1", "W2", "W3", "W4")}

    change_one_azimuth(paths[1])  # W2: new content
    stat = paths[2].stat()  # W3: touched (newer mtime), same bytes
    os.utime(paths[2], ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))

    again = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--only-changed")
    assert again.returncode == 0, again.output
    rows = summary(out)
    assert {w: (r["status"], r["detail"]) for w, r in rows.items()} == {
        "W1": ("skipped", "unchanged"),
        "W2": ("done", "input changed: stations"),
        "W3": ("skipped", "unchanged"),
        "W4": ("skipped", "unchanged"),
    }
    logged = {e["well"]: e["detail"] for e in log_events(again.stderr) if e["event"] == "well"}
    assert logged["W2"] == "input changed: stations"
    assert [r["well"] for r in runs(out / "ledger.sqlite")][4:] == ["W2"]  # one new run
    assert (out / "W2" / "trajectory.csv").read_bytes() != before["W2"]
    for well in ("W1", "W3", "W4"):
        assert (out / well / "trajectory.csv").read_bytes() == before[well]
    assert_complete(out / "W2")

    # a changed parameter re-runs every well and names the parameter
    params = gyropipe_cli(
        "batch", survey, "--inputs", pattern, "--out", out, "--only-changed",
        "--set", "trajectory.vs_azimuth=37.5",
    )  # fmt: skip
    assert params.returncode == 0, params.output
    assert {r["detail"] for r in summary(out).values()} == {
        "params changed: trajectory.vs_azimuth 0.0→37.5"
    }
    # a header override (manifest column) re-runs that well only
    manifest = tmp_path / "wells.csv"
    manifest.write_text(
        "well_id,stations,latitude\n"
        + "".join(f"W{i},{paths[i - 1]},{61.25 if i != 4 else 61.5}\n" for i in range(1, 5))
    )
    header = gyropipe_cli(
        "batch", survey, "--manifest", manifest, "--out", out, "--only-changed",
        "--set", "trajectory.vs_azimuth=37.5",
    )  # fmt: skip
    assert header.returncode == 0, header.output
    details = {w: r["detail"] for w, r in summary(out).items()}
    assert details["W4"] == "well header changed: latitude unset→61.5"
    assert details["W1"] == "well header changed: latitude unset→61.25"


def test_rerun_failed_runs_only_the_failed_wells(tmp_path: Path, survey: Path):
    paths = make_wells(tmp_path / "in", ["ok", "broken"])
    corrupt(paths[1])
    out = tmp_path / "out"
    pattern = tmp_path / "in" / "*.csv"
    assert gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out).returncode == 1

    still = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--rerun-failed")
    assert still.returncode == 1
    assert summary(out)["ok"] == {**summary(out)["ok"], "status": "skipped"}
    assert summary(out)["broken"]["detail"].startswith("stage 'read'")

    make_wells(tmp_path / "in", ["broken"])  # fixed
    fixed = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--rerun-failed")
    assert fixed.returncode == 0, fixed.output
    rows = summary(out)
    assert rows["ok"]["status"] == "skipped"
    assert rows["ok"]["detail"] == "last run did not fail"
    assert rows["broken"]["status"] == "done"
    assert rows["broken"]["detail"] == "previous run failed; input changed: stations"
    assert [r["status"] for r in runs(out / "ledger.sqlite") if r["well"] == "broken"] == [
        "failed",
        "failed",
        "done",
    ]


def test_deleted_outputs_are_a_reason_to_run_again(tmp_path: Path, survey: Path):
    make_wells(tmp_path / "in", ["W"])
    out = tmp_path / "out"
    pattern = tmp_path / "in" / "*.csv"
    assert gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out).returncode == 0
    (out / "W" / "trajectory.csv").unlink()
    again = gyropipe_cli("batch", survey, "--inputs", pattern, "--out", out, "--only-changed")
    assert again.returncode == 0
    assert summary(out)["W"]["detail"] == "outputs missing"
    assert_complete(out / "W")


FP = Fingerprint(
    inputs={"stations": "a" * 64},
    pipeline="p" * 64,
    params={"trajectory": {"vs_azimuth": 0.0}},
    gyropipe="0.1.0",
    plugins={"acme": "1.2"},
    well={},
)


def replaced(**changes: object) -> Fingerprint:
    return Fingerprint(**{**FP.__dict__, **changes})  # type: ignore[arg-type]


def test_reasons_name_what_changed():
    assert changes(FP, FP) == []
    assert changes(FP, replaced(plugins={"acme": "1.3"})) == ["plugin acme 1.2→1.3"]
    assert changes(FP, replaced(plugins={"acme": "1.2", "zeta": "0.1"})) == [
        "plugin zeta added (0.1)"
    ]
    assert changes(FP, replaced(plugins={})) == ["plugin acme removed (was 1.2)"]
    assert changes(FP, replaced(gyropipe="0.2.0")) == ["gyropipe 0.1.0→0.2.0"]
    assert changes(FP, replaced(pipeline="q" * 64)) == ["pipeline changed"]
    assert changes(FP, replaced(inputs={"stations": "b" * 64, "cal": "c" * 64})) == [
        "new input cal",
        "input changed: stations",
    ]
    assert changes(FP, replaced(well={"latitude": 61.25})) == [
        "well header changed: latitude unset→61.25"
    ]


def row(run_id: int, status: str, fingerprint: Fingerprint, batch: int, finished: float) -> RunRow:
    return RunRow(run_id, "W", batch, status, [], fingerprint, {}, "/out/W", finished - 1, finished)


def test_policy_table():
    done = row(1, "done", FP, batch=1, finished=100.0)
    failed = row(2, "failed", FP, batch=2, finished=200.0)
    kw = {"batch_id": 5, "batch_started": 500.0, "resume_since": None}
    published = WellState(done, done, True)
    assert decide(Mode(), WellState(None, None, False), FP, **kw) == Run(["new well"])
    assert decide(Mode(), published, FP, **kw) == Run(["unchanged, run requested"])
    assert decide(Mode(only_changed=True), published, FP, **kw) == Skip("unchanged")
    assert decide(Mode(only_changed=True), WellState(done, done, False), FP, **kw) == Run(
        ["outputs missing"]
    )
    assert decide(Mode(only_changed=True), WellState(failed, done, True), FP, **kw) == Run(
        ["previous run failed"]
    )
    assert decide(Mode(rerun_failed=True), published, FP, **kw) == Skip("last run did not fail")
    assert decide(Mode(rerun_failed=True), WellState(None, None, False), FP, **kw) == Skip(
        "never run"
    )
    # another batch completed the same work while this one ran: adopted, not recomputed
    meanwhile = row(3, "done", FP, batch=4, finished=600.0)
    assert decide(Mode(), WellState(meanwhile, meanwhile, True), FP, **kw) == Skip(
        "done by batch 4 meanwhile"
    )
    # the same command started again after a kill: wells it completed are not recomputed
    resumed = {**kw, "resume_since": 1}
    assert decide(Mode(), published, FP, **resumed) == Skip(
        "done before the interruption (batch 1)"
    )
    assert decide(Mode(), published, replaced(gyropipe="0.2.0"), **resumed) == Run(
        ["gyropipe 0.1.0→0.2.0"]
    )


def test_fingerprint_round_trips_through_json():
    assert Fingerprint.from_json(FP.to_json()) == FP
    assert json.loads(FP.to_json())["params"] == {"trajectory": {"vs_azimuth": 0.0}}


def test_a_choice_that_turns_on_a_pending_hash_is_a_check():
    done = row(1, "done", FP, batch=1, finished=100.0)
    kw = {"batch_id": 5, "batch_started": 500.0, "resume_since": None}
    pending = replaced(inputs={"stations": PENDING})
    looked: list[str] = []

    def published() -> bool:
        looked.append("OUT/W")
        return True

    state = WellState(done, done, published)
    # runs whatever the file holds: no check, no look at OUT/W, reasons from what is known
    assert decide(Mode(), state, pending, **kw) == Run(["unchanged, run requested"])
    newer = replaced(inputs={"stations": PENDING}, gyropipe="0.2.0")
    assert decide(Mode(only_changed=True), state, newer, **kw) == Run(["gyropipe 0.1.0→0.2.0"])
    assert looked == []
    # skipped only if the file is as the last done run read it: a worker hashes it
    assert decide(Mode(only_changed=True), state, pending, **kw) == Check(
        ["stations"], [], 1, Skip("unchanged")
    )
    resumed = {**kw, "resume_since": 1}
    assert decide(Mode(), state, pending, **resumed) == Check(
        ["stations"], [], 1, Skip("done before the interruption (batch 1)")
    )
    assert decide(Mode(rerun_failed=True), state, pending, **kw) == Skip("last run did not fail")
    assert looked == []
    # every hash known: the publication decides, looked at once
    assert decide(Mode(only_changed=True), state, FP, **kw) == Skip("unchanged")
    assert looked == ["OUT/W"]
    # the reasons of a run come from its own hashes
    changed = replaced(inputs={"stations": "b" * 64})
    assert why(state, changed, published=False) == ["input changed: stations", "outputs missing"]


def test_a_run_of_another_ledger_published_over_the_well_is_not_taken_for_its_own(
    tmp_path: Path, survey: Path
):
    """Two ledgers (``--ledger``) publishing into one OUT number their runs alike: the
    second's run 1 of W1, from other stations, published over the first's run 1. The first
    ledger's ``--only-changed`` batch runs W1 again (its outputs are not its run's) rather
    than skipping it as unchanged with the other stations' trajectory in OUT/W1."""
    (mine,) = make_wells(tmp_path / "in", ["W1"])
    (theirs,) = make_wells(tmp_path / "other", ["W1"])
    change_one_azimuth(theirs)
    out = tmp_path / "out"

    def batch(inputs: Path, ledger: str, *flags: str) -> dict[str, tuple[str, str]]:
        result = gyropipe_cli(
            "batch", survey, "--inputs", inputs / "*.csv", "--out", out,
            "--ledger", tmp_path / ledger, *flags,
        )  # fmt: skip
        assert result.returncode == 0, result.output
        return {w: (r["status"], r["detail"]) for w, r in summary(out).items()}

    assert batch(tmp_path / "in", "first.sqlite") == {"W1": ("done", "new well")}
    ours = (out / "W1" / "trajectory.csv").read_bytes()
    assert batch(tmp_path / "other", "second.sqlite") == {"W1": ("done", "new well")}
    assert json.loads((out / "W1" / "batch.json").read_text())["run_id"] == 1
    assert (out / "W1" / "trajectory.csv").read_bytes() != ours

    assert batch(tmp_path / "in", "first.sqlite", "--only-changed") == {
        "W1": ("done", "outputs missing")
    }
    assert (out / "W1" / "trajectory.csv").read_bytes() == ours
    assert json.loads((out / "W1" / "run.json").read_text())["inputs"]["stations"]["path"] == (
        str(mine)
    )

"""``gyropipe batch``: corrupt wells fail alone, the summary (table, JSON, CSV, log lines),
manifests with header overrides, and the exit codes."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from batch_support import (
    assert_complete,
    corrupt,
    log_events,
    make_wells,
    no_staging_left,
    runs,
    summary,
)

from tests_support import gyropipe_cli


def test_corrupt_wells_fail_alone_and_the_good_ones_complete(tmp_path: Path, survey: Path):
    paths = make_wells(tmp_path / "in", ["A-1", "A-2", "B-1", "B-2", "C-1"])
    bad_line = corrupt(paths[1])
    paths[3].write_bytes(b"\x00\xff not a station listing\n")
    out = tmp_path / "out"

    args = ("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    # a terminal wide enough for the table's rows (the details name long temporary paths)
    result = gyropipe_cli(*args, "--workers", "2", env={"COLUMNS": "200"})

    assert result.returncode == 1, result.output
    rows = summary(out)
    assert {w: r["status"] for w, r in rows.items()} == {
        "A-1": "done",
        "A-2": "failed",
        "B-1": "done",
        "B-2": "failed",
        "C-1": "done",
    }
    assert f"{paths[1]}:{bad_line}" in rows["A-2"]["detail"]  # file:line of the bad row
    assert "expected 3 cells" in rows["A-2"]["detail"]
    assert str(paths[3]) in rows["B-2"]["detail"]
    for well in ("A-1", "B-1", "C-1"):
        assert rows[well]["detail"] == "new well"
        assert rows[well]["time_s"] > 0
        assert_complete(out / well)
    assert not (out / "A-2").exists() and not (out / "B-2").exists()
    assert no_staging_left(out)

    # the table on stdout, the same rows in summary.csv, one JSON log line per well
    table = result.stdout.splitlines()
    assert table[0].split() == ["well", "status", "time", "s", "detail"]
    assert [line.split()[:2] for line in table[1:6]] == [
        ["A-1", "done"],
        ["A-2", "failed"],
        ["B-1", "done"],
        ["B-2", "failed"],
        ["C-1", "done"],
    ]
    # a failure's cause is shown whole and readable: stage, file:line, message (wrapped)
    joined = " ".join(result.stdout.split())
    assert "A-2 failed" in joined and f"read: A-2.csv:{bad_line}: " in joined
    cause = rows["A-2"]["detail"].split(f"A-2.csv:{bad_line}", 1)[1]
    assert " ".join(cause.split()) in joined
    assert "…" not in result.stdout and "InputFileError" not in result.stdout
    with open(out / "summary.csv", newline="") as fh:
        assert [(r["well"], r["status"]) for r in csv.DictReader(fh)] == [
            (w, r["status"]) for w, r in rows.items()
        ]
    events = log_events(result.stderr)
    assert [e["event"] for e in events] == ["start", *["well"] * 5, "end"]
    assert events[-1]["counts"] == {
        "done": 3,
        "rejected": 0,
        "failed": 2,
        "skipped": 0,
        "interrupted": 0,
    }

    # the ledger recorded every run with hashes, versions and the published outputs
    recorded = {r["well"]: r for r in runs(out / "ledger.sqlite")}
    assert {w: r["status"] for w, r in recorded.items()} == {
        w: r["status"] for w, r in rows.items()
    }
    done = recorded["A-1"]
    manifest = json.loads((out / "A-1" / "run.json").read_text())
    assert json.loads(done["inputs"]) == manifest["inputs"]
    assert json.loads(done["outputs"]) == manifest["outputs"]
    assert json.loads(done["versions"])["plugins"] == manifest["plugins"]
    assert json.loads(done["fingerprint"])["inputs"] == {
        "stations": manifest["inputs"]["stations"]["sha256"]
    }
    assert recorded["A-2"]["error"] == rows["A-2"]["detail"]


def test_manifest_maps_wells_to_files_and_header_overrides(tmp_path: Path, survey: Path):
    a, b = make_wells(tmp_path / "in", ["north", "south"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(
        "# two wells of one pad\n"
        "well_id,stations,latitude,longitude,tool_serial\n"
        f"N-1,in/{a.name},61.5,73.25,IG50-0417\n"
        f"S-1,{b},,,\n"
    )
    out = tmp_path / "out"

    result = gyropipe_cli(
        "batch", survey, "--manifest", manifest, "--out", out, "--well", "field=Samotlor"
    )

    assert result.returncode == 0, result.output
    north = assert_complete(out / "N-1")
    assert north["inputs"]["stations"]["path"] == str(a)
    assert north["well"]["latitude"] == 61.5  # the manifest cell beats the file's 61.25
    assert north["well"]["longitude"] == 73.25
    assert north["well"]["tool_serial"] == "IG50-0417"
    assert north["well"]["field"] == "Samotlor"
    south = assert_complete(out / "S-1")
    assert south["well"]["latitude"] == 61.25  # empty cell: the file header stands
    fingerprints = {r["well"]: json.loads(r["fingerprint"]) for r in runs(out / "ledger.sqlite")}
    assert fingerprints["N-1"]["well"] == {
        "field": "Samotlor",
        "latitude": 61.5,
        "longitude": 73.25,
        "tool_serial": "IG50-0417",
    }


@pytest.mark.parametrize(
    ("manifest_text", "message"),
    [
        ("well_id,stations,colour\nW,a.csv,red\n", "wells.csv:1: unknown column(s) colour"),
        ("well_id,latitude\nW,61\n", "wells.csv:1: missing column(s) stations"),
        ("well_id,stations\nW,a.csv\nW,a.csv\n", "wells.csv:3: well 'W' already listed on line 2"),
        (  # fuzz: 'A' and 'a' collide on a case-insensitive file system
            "well_id,stations\nA,a.csv\nB,b.csv\na,c.csv\n",
            "wells.csv:4: well 'a' equals well 'A' of ",
        ),
        ("well_id,stations\n../up,a.csv\n", "wells.csv:2: well id '../up' is not a plain"),
        ("well_id,stations,latitude\nW,a.csv,north\n", "wells.csv:2: well 'W': latitude"),
        ("well_id,stations\nW,a.csv,extra\n", "wells.csv:2: 3 cells, the header has 2"),
        ("well_id,stations\n", "no wells listed"),
        (  # fuzz: a ValueError out of Path.resolve
            "well_id,stations\nW,a\x00.csv\n",
            "wells.csv:2: column 'stations': a NUL byte in 'a\\x00.csv'",
        ),
        ("well_id,stations,tool_serial\nW,a.csv,S\x00\n", "wells.csv:2: column 'tool_serial'"),
    ],
)
def test_bad_manifest_is_a_configuration_error(
    tmp_path: Path, survey: Path, manifest_text: str, message: str
):
    manifest = tmp_path / "wells.csv"
    manifest.write_text(manifest_text)
    result = gyropipe_cli("batch", survey, "--manifest", manifest, "--out", tmp_path / "out")
    assert result.returncode == 2
    assert message in result.stderr
    assert not (tmp_path / "out").exists()


def test_manifest_wells_equal_up_to_case_are_refused_naming_both_lines(
    tmp_path: Path, survey: Path
):
    manifest = tmp_path / "wells.csv"
    manifest.write_text("well_id,stations\nA,a.csv\nB,b.csv\na,c.csv\n")
    result = gyropipe_cli("batch", survey, "--manifest", manifest, "--out", tmp_path / "out")
    assert result.returncode == 2
    assert (
        f"{manifest}:4: well 'a' equals well 'A' of {manifest}:2 up to case: their output "
        "directories would collide on a case-insensitive file system"
    ) in result.stderr


def test_input_files_naming_wells_equal_up_to_case_are_refused(tmp_path: Path, survey: Path):
    """Fuzz: wells 'A-1' and 'a-1' from a glob would share one output directory on a
    case-insensitive file system."""
    make_wells(tmp_path / "in", ["A-1", "B-1"])
    (tmp_path / "in" / "a-1.csv").write_bytes((tmp_path / "in" / "A-1.csv").read_bytes())
    out = tmp_path / "out"
    result = gyropipe_cli("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    assert result.returncode == 2, result.output
    first, second = tmp_path / "in" / "A-1.csv", tmp_path / "in" / "a-1.csv"
    assert f"{first} and {second} would be wells 'A-1' and 'a-1', equal up to case" in result.output
    assert not out.exists()


def test_configuration_errors_exit_2_and_a_clean_batch_exits_0(tmp_path: Path, survey: Path):
    make_wells(tmp_path / "in", ["W1", "W2"])
    out = tmp_path / "out"
    pattern = str(tmp_path / "in" / "*.csv")
    bad_pipeline = tmp_path / "bad.yaml"
    bad_pipeline.write_text("name: bad\nversion: 1\nstages:\n  - {id: a, uses: no_such_stage}\n")
    cases = [
        (["batch", survey, "--out", out], "either --inputs GLOB or --manifest FILE"),
        (["batch", survey, "--inputs", pattern, "--manifest", pattern, "--out", out], "either"),
        (["batch", survey, "--inputs", tmp_path / "none*.csv", "--out", out], "matches no file"),
        (["batch", bad_pipeline, "--inputs", pattern, "--out", out], "unknown stage"),
        (
            ["batch", survey, "--inputs", pattern, "--out", out, "--scheduler", "x"],
            "--scheduler needs an executor that takes one (dask), not 'local'",
        ),
        (
            ["batch", survey, "--inputs", pattern, "--out", out, "--executor", "dsak"],
            "no executor named 'dsak'; did you mean 'dask'? (registered: dask, local)",
        ),
        (["batch", survey, "--inputs", pattern, "--out", out, "--well", "latitude"], "FIELD=VALUE"),
        (["batch", survey, "--inputs", pattern, "--out", out, "--workers", "0"], "--workers"),
    ]
    for args, message in cases:
        result = gyropipe_cli(*args)
        assert result.returncode == 2, (args, result.output)
        assert message in result.output, (args, result.output)
    assert not out.exists()

    ok = gyropipe_cli(
        "batch", survey, "--inputs", pattern, "--out", out, "--workers", "1", "--quiet"
    )
    assert ok.returncode == 0, ok.output
    assert ok.stdout == ""  # --quiet: no table, only JSON log lines on stderr
    assert [e["status"] for e in log_events(ok.stderr) if e["event"] == "well"] == ["done"] * 2


def test_missing_input_file_fails_that_well_only(tmp_path: Path, survey: Path):
    (a,) = make_wells(tmp_path / "in", ["present"])
    manifest = tmp_path / "wells.csv"
    manifest.write_text(f"well_id,stations\nP,{a}\nM,{tmp_path / 'gone.csv'}\n")
    out = tmp_path / "out"
    result = gyropipe_cli("batch", survey, "--manifest", manifest, "--out", out, "--workers", "1")
    assert result.returncode == 1
    rows = summary(out)
    assert rows["P"]["status"] == "done"
    assert rows["M"]["status"] == "failed"
    assert f"cannot read '{tmp_path / 'gone.csv'}'" in rows["M"]["detail"]

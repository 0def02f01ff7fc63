"""An executor added by a plugin: the test plugin ``gyropipe-serial`` (``gyropipe-serial/``,
installed offline: fixture ``serial_site``) registers ``serial``, which runs each
well in the batch process itself. A real batch runs on it end to end, through the command
line (in process) and the Python API: every well published and recorded done in the ledger
by this very process; docs/batch.md shows this plugin's code. An executor name that is not registered is refused (exit 2) naming
the registered ones, and a disabled plugin's executor names its plugin."""

from __future__ import annotations

import io
import json
import os
import re
import sqlite3
from pathlib import Path
from typing import Any

import pytest

import pipeline as gp
from pipeline.batch.jobs import BatchConfigError
from pipeline.plugins import forget_shared_registries
from tests_support import ROOT, CliResult, gyropipe_cli, stage, survey_stages, write_pipeline

STATIONS = ROOT / "examples" / "stations-j-well.csv"
WELLS = ["north", "south", "west"]
LAST_STATION = "2520,44.99,45.35,"
PLUGIN = Path(__file__).parent / "gyropipe-serial" / "src" / "gyropipe_serial" / "plugin.py"


@pytest.fixture
def survey(tmp_path: Path) -> Path:
    """A survey pipeline (stations → trajectory, written as CSV)."""
    trajectory = {"table": "trajectory.trajectory"}
    stages = [
        *survey_stages(),
        stage("export_csv", "write", trajectory, writer="csv", filename="trajectory.csv"),
    ]
    return write_pipeline(tmp_path, stages, name="survey")


@pytest.fixture
def wells(tmp_path: Path) -> str:
    """Three wells, copies of the bundled station listing; their glob."""
    (tmp_path / "in").mkdir()
    for name in WELLS:
        (tmp_path / "in" / f"{name}.csv").write_text(STATIONS.read_text())
    return str(tmp_path / "in" / "*.csv")


def runs(ledger: Path) -> list[dict[str, Any]]:
    with sqlite3.connect(ledger) as db:
        db.row_factory = sqlite3.Row
        return [dict(r) for r in db.execute("SELECT * FROM runs ORDER BY well")]


def assert_ran_here(out: Path) -> None:
    """Every well done and published, each run by this process (the serial executor)."""
    rows = runs(out / "ledger.sqlite")
    assert [(r["well"], r["status"]) for r in rows] == [(w, "done") for w in sorted(WELLS)]
    assert {int(str(r["worker"]).rsplit(":", 1)[1]) for r in rows} == {os.getpid()}
    for well in WELLS:
        manifest = json.loads((out / well / "run.json").read_text())
        assert manifest["plugins"]["serial"] == "0.2.0"
        trajectory = (out / well / "trajectory.csv").read_text().splitlines()
        assert trajectory[-1].startswith(LAST_STATION)  # md, inc, azi as the input has them


def batch(survey: Path, wells: str, out: Path, *args: str, site: Path | None) -> CliResult:
    return gyropipe_cli(
        "batch", survey, "--inputs", wells, "--out", out, "--quiet", *args, site=site
    )


def test_a_plugin_executor_runs_a_batch_from_the_command_line(
    serial_site: Path, survey: Path, wells: str, tmp_path: Path
):
    out = tmp_path / "out"
    result = batch(survey, wells, out, "--executor", "serial", site=serial_site)
    assert result.returncode == 0, result.stderr
    assert_ran_here(out)
    start = json.loads(result.stderr.splitlines()[0])
    assert (start["event"], start["executor"]) == ("start", "serial")


def test_plugins_lists_the_executors(serial_site: Path):
    listing = gyropipe_cli("plugins", site=serial_site, check=True).stdout
    assert "serial 0.2.0 (third-party): executor:serial" in listing
    assert "  serial (serial 0.2.0): every well in the batch process, one at a time" in listing
    assert "  local (builtin.executors 0.1.0): a process pool on this machine" in listing
    assert "  dask (builtin.executors 0.1.0): a Dask distributed cluster" in listing


REFUSALS = [
    (
        ("--executor", "serail"),
        "error: --executor serail: no executor named 'serail'; did you mean 'serial'? "
        "(registered: dask, local, serial)",
    ),
    (
        ("--executor", "serial", "--disable-plugin", "serial"),
        "error: --executor serial: executor 'serial' is provided by plugin serial, which is "
        "disabled (--disable-plugin serial)",
    ),
    (
        ("--executor", "local", "--disable-plugin", "builtin.executors"),
        "error: --executor local: executor 'local' is provided by plugin builtin.executors, "
        "which is disabled (--disable-plugin builtin.executors)",
    ),
    (
        ("--executor", "serial", "--scheduler", "tcp://127.0.0.1:8786"),
        "error: --scheduler needs an executor that takes one (dask), not 'serial'",
    ),
]


@pytest.mark.parametrize(("args", "message"), REFUSALS)
def test_an_executor_that_cannot_run_the_batch_is_refused_before_anything_is_made(
    serial_site: Path, survey: Path, wells: str, tmp_path: Path, args: tuple[str, ...], message: str
):
    result = batch(survey, wells, tmp_path / "out", *args, site=serial_site)
    assert (result.returncode, result.stderr.strip()) == (2, message)
    assert not (tmp_path / "out").exists()


def test_without_the_plugin_its_executor_is_not_registered(
    survey: Path, wells: str, tmp_path: Path
):
    result = batch(survey, wells, tmp_path / "out", "--executor", "serial", site=None)
    assert result.returncode == 2
    assert "no executor named 'serial' (registered: dask, local)" in result.stderr


def test_a_plugin_executor_runs_a_batch_from_python(
    serial_site: Path, survey: Path, wells: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    monkeypatch.syspath_prepend(str(serial_site))  # installed for this test only
    forget_shared_registries()
    try:
        log = io.StringIO()
        report = gp.run_batch(survey, wells, out=tmp_path / "out", executor="serial", log=log)
        assert report.exit_code == 0
        assert sorted((r.well, r.status) for r in report.results) == [
            (w, "done") for w in sorted(WELLS)
        ]
        assert_ran_here(tmp_path / "out")
        assert json.loads(log.getvalue().splitlines()[0])["executor"] == "serial"
        with pytest.raises(BatchConfigError, match=r"did you mean 'serial'\?"):
            gp.run_batch(survey, wells, out=tmp_path / "again", executor="serail")
        assert not (tmp_path / "again").exists()
    finally:
        forget_shared_registries()


def test_the_guide_s_example_executor_is_the_test_plugin():
    """docs/batch.md shows, under "Executors", the code of the plugin these tests run."""
    doc = (ROOT / "docs" / "batch.md").read_text()
    section = doc[doc.index("\n## Executors\n") : doc.index("\n## The ledger\n")]
    (block,) = re.findall(r"```python\n(.*?)```", section, flags=re.DOTALL)
    assert "@hookimpl\ndef gyropipe_register_executors" in block
    assert block in PLUGIN.read_text()


def test_a_plugin_executor_runs_the_checks_of_an_only_changed_batch(
    serial_site: Path, survey: Path, wells: str, tmp_path: Path
):
    """Files rewritten since the last batch have no hash the batch process knows: their
    wells are checked (the executor runs a task that only hashes), then skipped or run."""
    out = tmp_path / "out"
    assert batch(survey, wells, out, "--executor", "serial", site=serial_site).returncode == 0
    north, south = tmp_path / "in" / "north.csv", tmp_path / "in" / "south.csv"
    north.write_bytes(north.read_bytes())  # the same bytes, written again
    south.write_text(STATIONS.read_text().replace("2520.00,44.99,45.35", "2520.00,44.99,46.35"))
    again = batch(survey, wells, out, "--executor", "serial", "--only-changed", site=serial_site)
    assert again.returncode == 0, again.stderr
    told = [json.loads(line) for line in again.stderr.splitlines()]
    assert {e["well"]: (e["status"], e["detail"]) for e in told if e["event"] == "well"} == {
        "north": ("skipped", "unchanged"),
        "south": ("done", "input changed: stations"),
        "west": ("skipped", "unchanged"),
    }
    rows = runs(out / "ledger.sqlite")
    assert [(r["well"], r["status"]) for r in rows] == [
        ("north", "done"), ("south", "done"), ("south", "done"), ("west", "done")
    ]  # fmt: skip
    last = (out / "south" / "trajectory.csv").read_text().splitlines()[-1]
    assert last.startswith("2520,44.99,46.35,")

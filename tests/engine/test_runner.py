"""The runner end to end: CLI run on the bundled sample, manifest, bad inputs, failing
stages, contract checks at boundaries, and atomic outputs under SIGKILL."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import textwrap
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from pydantic import BaseModel

import pipeline.runner as runner
from pipeline.contracts import implies
from pipeline.errors import ContractViolation, StageError
from pipeline.graph import PlannedStage, build_plan
from pipeline.hashing import file_key, sha256_file
from pipeline.inputfiles import InputPath
from pipeline.plugins import load_registry
from pipeline.registry import StageContext, StageDef
from pipeline.runner import InputChangedError, RunInputError, run_plan
from pipeline.spec import load_spec
from pipeline.stages.exports import QcTable
from pipeline.survey.mincurve import minimum_curvature
from pipeline.tables import CheckResults, Stations, Trajectory
from pipeline.well import WellMetadata, attach
from tests_support import (
    ROOT,
    faults_of,
    gyropipe,
    gyropipe_cli,
    pythonpath,
    stage,
    survey_stages,
    write_pipeline,
)

SAMPLE = ROOT / "examples" / "stations-j-well.csv"
SURVEY = ROOT / "pipelines" / "survey.yaml"


def sample_values() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MD, inclination and azimuth of the sample, parsed independently of the reader."""
    lines = SAMPLE.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("MD (m)")) + 1
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[start:] if line])
    return rows[:, 0], rows[:, 1], rows[:, 2]


def test_survey_job_end_to_end_from_the_cli(tmp_path: Path):
    out_dir = tmp_path / "out"
    result = gyropipe_cli("run", str(SURVEY), "--input", str(SAMPLE), "--out", str(out_dir))
    assert result.returncode == 0, result.stderr
    names = sorted(p.name for p in out_dir.iterdir())
    assert names == [
        "dls_check.results.parquet",
        "report.html",
        "report.pdf",
        "run.json",
        "summary.json",
        "trajectory.csv",
        "trajectory.las",
        "trajectory.trajectory.parquet",
        "trajectory.xml",
    ]

    trajectory = pq.read_table(out_dir / "trajectory.trajectory.parquet")
    Trajectory.validate_table(trajectory)  # units and north reference survived the file
    md, inc, azi = sample_values()
    expected = minimum_curvature(md, np.radians(inc), np.radians(azi), tie_tvd=md[0])
    np.testing.assert_allclose(trajectory.column("md").to_numpy(), md)
    np.testing.assert_allclose(trajectory.column("tvd").to_numpy(), expected.tvd, atol=1e-9)
    np.testing.assert_allclose(trajectory.column("north").to_numpy(), expected.north, atol=1e-9)
    np.testing.assert_allclose(trajectory.column("east").to_numpy(), expected.east, atol=1e-9)
    assert trajectory.schema.field("azi").metadata[b"north_reference"] == b"true"
    # closure of the last station from north/east, vertical section along azimuth 0 = north
    n, e = expected.north[-1], expected.east[-1]
    assert trajectory.column("closure_distance")[-1].as_py() == pytest.approx(np.hypot(n, e))
    np.testing.assert_allclose(trajectory.column("vertical_section").to_numpy(), expected.north)

    manifest = json.loads((out_dir / "run.json").read_text())
    plan = build_plan(load_spec(SURVEY), __import__("pipeline.plugins").plugins.load_registry())
    assert manifest["status"] == "ok"
    assert manifest["pipeline"]["sha256"] == plan.digest
    assert (
        manifest["inputs"]["stations"]["sha256"] == hashlib.sha256(SAMPLE.read_bytes()).hexdigest()
    )
    assert [s["id"] for s in manifest["stages"]] == [
        "read",
        "trajectory",
        "dls_check",
        "export_csv",
        "export_las",
        "export_witsml",
        "export_summary",
        "report",
    ]
    assert manifest["stages"][1]["rows_out"] == {"trajectory": len(md)}
    assert manifest["plugins"]["builtin.survey"]
    assert manifest["well"]["well"] == "J-12" and manifest["well"]["latitude"] == 61.25
    assert manifest["well"]["north_reference"] == "true"
    for entry in manifest["outputs"]:
        assert hashlib.sha256(Path(entry["path"]).read_bytes()).hexdigest() == entry["sha256"]

    qc = pq.read_table(out_dir / "dls_check.results.parquet")
    assert qc.num_rows == len(md) and all(qc.column("passed").to_pylist())


def test_a_command_in_process_leaves_the_process_as_it_was(tmp_path: Path):
    """What the helper and the command set up for the process (the pandas deferral's import
    hooks, the SIGTERM handler, the environment, the working directory, the warning filters)
    is as it was afterwards: the tests that follow see a plain process."""

    def state() -> tuple[object, ...]:
        return (
            list(sys.meta_path),
            signal.getsignal(signal.SIGTERM),
            dict(os.environ),
            os.getcwd(),
            list(warnings.filters),
        )

    before = state()
    args = ["--input", str(SAMPLE), "--out", str(tmp_path / "out")]
    done = gyropipe_cli("run", SURVEY, *args, env={"SOURCE_DATE_EPOCH": "0"}, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert state() == before


def test_a_file_longer_than_the_hash_buffer_hashes_whole(tmp_path: Path):
    """Hashed through a reused buffer: every block counts, the last partial one too."""
    path = tmp_path / "big.bin"
    data = np.random.default_rng(3).bytes((3 << 20) + 7)
    path.write_bytes(data)
    assert sha256_file(path) == hashlib.sha256(data).hexdigest()


HASH_FAULTS = """
import resource, sys
from pathlib import Path
from pipeline.hashing import file_key, sha256_file
from pipeline.inputfiles import InputPath
from pipeline.streams import use_returning_memory_pool

use_returning_memory_pool()
path = Path(sys.argv[1])
sha256_file(path)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
sha256_file(path)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@pytest.mark.process("glibc's mmap threshold fixed as in a batch process, from a fresh heap")
@pytest.mark.skipif(sys.platform != "linux", reason="glibc's mallopt")
def test_hashing_at_the_batch_mmap_threshold_maps_no_block_afresh(tmp_path: Path):
    """At the batch's fixed mmap threshold a fresh 1 MiB block per read was mapped and
    faulted in afresh (11,521 page faults for 47 MB); one reused buffer is not."""
    path = tmp_path / "big.bin"
    path.write_bytes(np.random.default_rng(4).bytes(16 << 20))  # 4,096 pages
    faults = faults_of(HASH_FAULTS, path, timeout=60)
    assert faults < 256, faults


def test_cli_overrides_and_well_metadata(tmp_path: Path):
    out_dir = tmp_path / "out"
    result = gyropipe_cli(
        "run",
        str(SURVEY),
        "--input",
        f"stations={SAMPLE}",
        "--out",
        str(out_dir),
        "--set",
        "trajectory.vs_azimuth=90",
        "--well",
        "tool_serial=GX-7",
    )
    assert result.returncode == 0, result.stderr
    trajectory = pq.read_table(out_dir / "trajectory.trajectory.parquet")
    np.testing.assert_allclose(
        trajectory.column("vertical_section").to_numpy(),
        trajectory.column("east").to_numpy(),
        atol=1e-9,
    )
    manifest = json.loads((out_dir / "run.json").read_text())
    assert manifest["well"]["tool_serial"] == "GX-7"


BAD_INPUTS = {
    "missing column": ("MD (m),Inc (deg)\n0,0\n30,1\n", ["azi", "accepted"]),
    "non-numeric cell": ("MD (m),Inc (deg),Azi True (deg)\n0,0,0\n30,abc,1\n", [":3", "abc"]),
    "md not increasing": (
        "MD (m),Inc (deg),Azi True (deg)\n0,0,0\n30,1,1\n20,2,2\n",
        ["stage 'read'", "column 'md': monotonic", "row 2 (line 4): 20.0"],
    ),
    "inclination out of range": (
        "MD (m),Inc (deg),Azi True (deg)\n0,0,0\n30,181,1\n",
        ["bad.csv:3 (column 'inc')", "inclination 181.0° is outside [0, 180]"],
    ),
    "azimuth not finite": (
        "MD (m),Inc (deg),Azi True (deg)\n0,0,0\n30,1,inf\n",
        [":3 (column 'Azi True (deg)')", "expected a number, got 'inf'"],
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_is_a_clear_error_and_writes_nothing(case: str, tmp_path: Path):
    text, fragments = BAD_INPUTS[case]
    bad = tmp_path / "bad.csv"
    bad.write_text(text)
    out_dir = tmp_path / "out"
    result = gyropipe_cli("run", str(SURVEY), "--input", str(bad), "--out", str(out_dir))
    assert result.returncode == 1
    assert str(bad) in result.stderr
    for fragment in fragments:
        assert fragment in result.stderr, result.stderr
    assert "Traceback" not in result.stderr
    assert not out_dir.exists()  # a failed run publishes nothing


@pytest.mark.parametrize(
    ("header", "expected"), [("Azi (deg)", b"true"), ("Azimuth Grid (deg)", b"grid")]
)
def test_file_north_reference_wins_over_the_pipeline_default(
    header: str, expected: bytes, tmp_path: Path
):
    src = tmp_path / "st.csv"
    src.write_text(f"MD (m),Inc (deg),{header}\n0,0,0\n30,1,1\n")
    out_dir = tmp_path / "out"
    result = gyropipe_cli("run", str(SURVEY), "--input", str(src), "--out", str(out_dir))
    assert result.returncode == 0, result.stderr
    trajectory = pq.read_table(out_dir / "trajectory.trajectory.parquet")
    assert trajectory.schema.field("azi").metadata[b"north_reference"] == expected


def test_missing_input_file_is_a_configuration_error(tmp_path: Path):
    result = gyropipe_cli(
        "run", str(SURVEY), "--input", str(tmp_path / "nope.csv"), "--out", str(tmp_path / "out")
    )
    assert result.returncode == 2
    assert "no such file" in result.stderr


def make_plan(write_yaml, registry, body: str):
    path = write_yaml(
        "name: t\nversion: 1\ninputs: {stations: {}}\nstages:\n" + textwrap.dedent(body)
    )
    return build_plan(load_spec(path), registry)


def stations_table() -> pa.Table:
    return Stations.compiled().make_table(
        {"md": [0.0, 30.0, 60.0], "inc": [0.0, 3.0, 6.0], "azi": [0.0, 45.0, 45.0]},
        north_reference="grid",
    )


def test_stage_with_undeclared_ports_or_bad_output_is_reported(
    write_yaml, registry, add_stage, tmp_path: Path
):
    def wrong_ports(inputs: Mapping[str, pa.Table], params: object, ctx: StageContext):
        return {"oops": inputs["stations"]}

    def breaks_contract(inputs: Mapping[str, pa.Table], params: object, ctx: StageContext):
        return {"trajectory": inputs["stations"]}  # no tvd/north/east…

    add_stage(
        StageDef(
            "tests.wrong_ports",
            wrong_ports,
            "bad",
            inputs={"stations": Stations},
            outputs={"trajectory": Trajectory},
        )
    )
    add_stage(
        StageDef(
            "tests.breaks",
            breaks_contract,
            "bad",
            inputs={"stations": Stations},
            outputs={"trajectory": Trajectory},
        )
    )
    src = tmp_path / "st.parquet"
    pq.write_table(stations_table(), src)
    for uses, error, fragment in [
        (
            "tests.wrong_ports",
            StageError,
            "stage 't1' (tests.wrong_ports from plugin tests.helpers 9.9) failed: ValueError: "
            "returned ports ['oops'], declared ['trajectory']",
        ),
        (
            "tests.breaks",
            ContractViolation,
            "pipeline 't' stage 't1' output port 'trajectory': table violates contract Trajectory",
        ),
    ]:
        plan = make_plan(
            write_yaml,
            registry,
            f"""
          - id: read
            uses: read_stations
          - id: t1
            uses: {uses}
            inputs: {{stations: read}}
            persist: true
        """,
        )
        out_dir = tmp_path / uses
        with pytest.raises(error) as info:
            run_plan(plan, registry, inputs={"stations": src}, out_dir=out_dir)
        assert fragment in str(info.value)
        assert not out_dir.exists()
        assert not list(tmp_path.glob(f".{uses}.gyropipe-staging-*"))  # staging removed


def test_the_runs_well_is_what_stages_report_not_what_tables_carry(
    write_yaml, registry, add_stage, tmp_path: Path
):
    """The input's header and what a stage reports (``ctx.update_well``) make the run's well,
    under the overrides; a header attached to an output table is that table's, no report."""
    seen: list[WellMetadata] = []

    def stamps(inputs: Mapping[str, pa.Table], params: object, ctx: StageContext):
        seen.append(ctx.well)
        return {"stations": attach(inputs["stations"], WellMetadata(well="B-2", latitude=-10.0))}

    def reports(inputs: Mapping[str, pa.Table], params: object, ctx: StageContext):
        seen.append(ctx.well)
        ctx.update_well(WellMetadata(tool_serial="SN-7", latitude=-20.0))
        return {"stations": inputs["stations"]}

    for name, func in (("stamps", stamps), ("reports", reports), ("looks", stamps)):
        add_stage(
            StageDef(
                f"tests.{name}",
                func,
                name,
                inputs={"stations": Stations},
                outputs={"stations": Stations},
            )
        )
    src = tmp_path / "st.parquet"
    pq.write_table(attach(stations_table(), WellMetadata(well="A-1", elevation=12.0)), src)
    plan = make_plan(
        write_yaml,
        registry,
        """
      - id: read
        uses: read_stations
      - id: a
        uses: tests.stamps
        inputs: {stations: read}
      - id: b
        uses: tests.reports
        inputs: {stations: a}
      - id: c
        uses: tests.looks
        inputs: {stations: b}
    """,
    )
    result = run_plan(
        plan, registry, inputs={"stations": src}, out_dir=None, well=WellMetadata(latitude=60.0)
    )
    fields = ("well", "elevation", "latitude", "tool_serial")
    assert [tuple(getattr(w, f) for f in fields) for w in seen] == [
        ("A-1", 12.0, 60.0, None),
        ("A-1", 12.0, 60.0, None),
        ("A-1", 12.0, 60.0, "SN-7"),
    ]
    assert tuple(getattr(result.well, f) for f in fields) == ("A-1", 12.0, 60.0, "SN-7")
    assert result.manifest["well"]["well"] == "A-1"


def test_inputs_must_match_declaration(write_yaml, registry, tmp_path: Path):
    plan = make_plan(write_yaml, registry, "  - id: read\n    uses: read_stations\n")
    with pytest.raises(RunInputError, match="missing input 'stations'"):
        run_plan(plan, registry, inputs={}, out_dir=tmp_path / "o")
    with pytest.raises(RunInputError, match="unknown input 'other'"):
        run_plan(
            plan, registry, inputs={"stations": SAMPLE, "other": SAMPLE}, out_dir=tmp_path / "o"
        )


KILLER = """
import os, signal
from pipeline.hookspecs import hookimpl
from pipeline.registry import WriterDef

def write(table, path, well):
    with open(path, "wb") as fh:
        fh.write(b"partial,data\\n" * 1000)
        fh.flush()
        os.kill(os.getpid(), signal.SIGKILL)

@hookimpl
def gyropipe_register_writers(register):
    register(WriterDef("killer", "dies mid-write", "csv", write))
"""


KILL = ("--set", "export_csv.writer=killer")


@pytest.mark.process("the run SIGKILLs its own process mid-write")
def test_run_killed_mid_write_leaves_no_final_file(tmp_path: Path):
    site = tmp_path / "site"
    site.mkdir()
    (site / "killerplugin.py").write_text(KILLER)
    info = site / "killerplugin-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: killerplugin\nVersion: 1.0\n")
    (info / "entry_points.txt").write_text("[gyropipe]\nkillerplugin = killerplugin\n")
    out_dir = tmp_path / "out"
    killed = subprocess.run(
        [*gyropipe(), "run", str(SURVEY), "--input", str(SAMPLE), "--out", str(out_dir), *KILL],
        capture_output=True,
        text=True,
        env=pythonpath(site),
        timeout=120,
    )
    assert killed.returncode == -9
    assert not out_dir.exists()  # nothing published
    assert list(tmp_path.glob(".out.gyropipe-staging-*"))  # the dead run's private staging

    again = gyropipe_cli("run", str(SURVEY), "--input", str(SAMPLE), "--out", str(out_dir))
    assert again.returncode == 0, again.stderr
    assert sorted(p.name for p in out_dir.iterdir()) == [
        "dls_check.results.parquet",
        "report.html",
        "report.pdf",
        "run.json",
        "summary.json",
        "trajectory.csv",
        "trajectory.las",
        "trajectory.trajectory.parquet",
        "trajectory.xml",
    ]
    assert not list(tmp_path.glob(".out.gyropipe-staging-*"))  # the dead run's was cleaned up


def test_a_table_is_checked_once_per_contract_whatever_its_consumers(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """The check's results reach two export stages as their ``qc`` (QcTable, not the
    check's own output contract): the runner checks the table once per contract, not once
    per consumer — and not against QcTable at all, whose rules its output contract
    (CheckResults) implies (:func:`~pipeline.contracts.implies`)."""
    stages = [
        *survey_stages(),
        stage(
            "dls_check", "check", {"table": "trajectory.trajectory"}, check="dls_limit",
            params={"limit": 10.0},
        ),
        *(
            stage(name, "export", {"trajectory": "trajectory.trajectory", "qc": "dls_check.results"},
                  writer="json_summary")
            for name in ("summary_a", "summary_b")
        ),
    ]  # fmt: skip
    survey = write_pipeline(tmp_path, stages)
    registry = load_registry()
    plan = build_plan(load_spec(survey), registry)
    checks: list[tuple[str, int]] = []
    original = runner._check_contracts

    def recorded(
        pipeline: str, st: PlannedStage, tables: Mapping[str, pa.Table], direction: str
    ) -> None:
        contracts = st.definition.inputs if direction == "input" else st.definition.outputs
        checks.extend((contracts[port].__name__, id(t)) for port, t in tables.items())
        original(pipeline, st, tables, direction)

    monkeypatch.setattr(runner, "_check_contracts", recorded)
    result = run_plan(plan, registry, inputs={"stations": SAMPLE}, out_dir=tmp_path / "out")
    assert len(checks) == len(set(checks))  # no table checked twice against one contract
    assert ("Trajectory", id(result.tables[("trajectory", "trajectory")])) in checks
    results = id(result.tables[("dls_check", "results")])
    assert implies(CheckResults, QcTable)
    assert [name for name, table in checks if table == results] == ["CheckResults"]
    assert (tmp_path / "out" / "summary_b.json").is_file()


class NoteParams(BaseModel):
    note: InputPath
    """a file the stage reads; the stage then appends to it (or to ``also``), as another
    program writing it while the run goes on would"""
    also: Path | None = None


def test_a_file_changed_while_the_run_read_it_publishes_nothing(
    write_yaml, registry, add_stage, tmp_path: Path
):
    """A parameter file or an input written to between its hash and the end of the run:
    ``run.json`` could not say which bytes the outputs come from, so the run fails naming
    the file, and the previous run in ``out_dir`` stays whole."""

    def edits(inputs: Mapping[str, pa.Table], params: NoteParams, ctx: StageContext):
        params.note.read_bytes()
        with open(params.also or params.note, "ab") as fh:
            fh.write(b"\n")
        return {"stations": inputs["stations"]}

    add_stage(
        StageDef(
            "tests.edits",
            edits,
            "reads a file, then changes it or another",
            inputs={"stations": Stations},
            outputs={"stations": Stations},
            params=NoteParams,
        )
    )
    src = tmp_path / "st.parquet"
    pq.write_table(stations_table(), src)
    note = tmp_path / "note.txt"
    note.write_text("a profile\n")
    untouched = tmp_path / "other.txt"
    untouched.write_text("x")
    out_dir = tmp_path / "out"

    def run(also: Path | None) -> None:
        plan = make_plan(
            write_yaml,
            registry,
            f"""
          - id: read
            uses: read_stations
          - id: edit
            uses: tests.edits
            inputs: {{stations: read}}
            with: {{note: {note}, also: {also or "null"}}}
            persist: true
        """,
        )
        run_plan(plan, registry, inputs={"stations": src}, out_dir=out_dir)

    run(untouched)  # another file changed: not one the run read, published
    before = {p.name: p.read_bytes() for p in out_dir.iterdir()}
    manifest = json.loads(before["run.json"])
    assert [p["path"] for p in manifest["parameter_inputs"]] == [str(note)]
    for changed, also in [(note, None), (src, src)]:
        with pytest.raises(InputChangedError) as info:
            run(also)
        assert info.value.paths == [str(changed)]
        assert f"changed while the run read it: {changed};" in str(info.value)
        assert {p.name: p.read_bytes() for p in out_dir.iterdir()} == before


def test_an_input_changed_after_its_known_hash_was_taken_publishes_nothing(
    write_yaml, registry, tmp_path: Path
):
    """A batch worker hashes an input before the run and gives the runner its hash with the
    file's stat key from before the hash: a write in between fails the run, naming the
    file, though the file is unchanged while the run itself reads it."""
    src = tmp_path / "st.parquet"
    pq.write_table(stations_table(), src)
    key, digest = file_key(src), sha256_file(src)
    pq.write_table(stations_table().slice(0, 2), src)  # rewritten after its hash
    plan = make_plan(write_yaml, registry, "  - id: read\n    uses: read_stations\n")
    out_dir = tmp_path / "out"
    with pytest.raises(InputChangedError) as info:
        run_plan(
            plan,
            registry,
            inputs={"stations": src},
            out_dir=out_dir,
            known_inputs={"stations": (digest, key)},
        )
    assert info.value.paths == [str(src)]
    assert not out_dir.exists()
    run_plan(  # the key of the file as it is: published
        plan,
        registry,
        inputs={"stations": src},
        out_dir=out_dir,
        known_inputs={"stations": (sha256_file(src), file_key(src))},
    )
    assert (out_dir / "run.json").exists()

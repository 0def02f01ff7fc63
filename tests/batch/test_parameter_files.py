"""Files named by parameters are inputs: the offset wells a clearance manifest lists, a CSV
reader profile, a tool-model file given by path and the file it extends are hashed into
``run.json`` (``parameter_inputs``) and the batch fingerprint, so ``--only-changed`` re-runs
a well when one of them changes — and only then — naming the file; ``validate`` refuses a
parameter naming a file that does not exist, at its YAML line."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from batch_support import STATIONS, change_one_azimuth, runs, summary
from pydantic import BaseModel, ValidationError

import pipeline as gp
from pipeline.api import stages
from pipeline.batch.fingerprint import Fingerprint, changes, hashed
from pipeline.errors import SpecError
from pipeline.inputfiles import InputPath, parameter_paths
from pipeline.stages import toolmodels
from pipeline.stages.clearance import offset_tables
from pipeline.uncertainty import toolmodel
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli, stage, write_pipeline

MANIFEST_HEADER = "well_id,file,model,hole_diameter (in),north (m),east (m)\n"


def clearance_pipeline(directory: Path) -> Path:
    """Reference stations (read with a profile) against the offset wells of a manifest, the
    reference's position uncertainty by a tool-model file given by path."""
    return write_pipeline(
        directory,
        [
            stage(
                "read",
                "read_stations",
                input="reference",
                reader="csv",
                options={"profile": "profile.yaml"},
            ),
            stage("offsets", "read_offsets", input="offsets"),
            stage("trajectory", "minimum_curvature", {"stations": "read.stations"}),
            stage(
                "uncertainty",
                "position_uncertainty",
                {"trajectory": "trajectory.trajectory"},
                ["trajectory"],
                model="models/acme.yaml",
            ),
            stage(
                "clearance",
                "clearance",
                {
                    "reference": "read.stations",
                    "offsets": "offsets.stations",
                    "wells": "offsets.wells",
                },
                ["clearance"],
                reference_hole_diameter=0.3112,
            ),
        ],
        name="parameter-files",
        inputs=("reference", "offsets"),
    )


def short_listing(path: Path, stations: int = 25) -> None:
    """The bundled station listing's header and first ``stations`` stations."""
    lines = STATIONS.read_text().splitlines()
    first = next(i for i, line in enumerate(lines) if line.startswith("MD (m)")) + 1
    path.write_text("\n".join(lines[: first + stations]) + "\n")


def make_fleet(root: Path) -> Path:
    """Two wells W1, W2 with the same reference listing, each against its own offset
    manifest (W1: offsets/a.csv, W2: offsets/b.csv); a CSV profile; a tool-model file
    extending another. Returns the batch manifest."""
    (root / "offsets").mkdir()
    (root / "models").mkdir()
    for name in ("ref.csv", "offsets/a.csv", "offsets/b.csv"):
        short_listing(root / name)
    (root / "wa.csv").write_text(MANIFEST_HEADER + "off-a,offsets/a.csv,GYRO-NS,12.25,0,30\n")
    (root / "wb.csv").write_text(MANIFEST_HEADER + "off-b,offsets/b.csv,GYRO-NS,12.25,30,0\n")
    (root / "profile.yaml").write_text("description: the J-12 listing\n")
    (root / "models" / "base.yaml").write_text(
        "format: gyropipe-tool-model/1\nname: TEST-BASE\ntitle: Test base\n"
        "extends: GYRO-NS\nmagnitudes: {GXY-RN: 0.25}\n"
    )
    (root / "models" / "acme.yaml").write_text(
        "format: gyropipe-tool-model/1\nname: TEST-ACME\ntitle: Test Acme\nextends: base.yaml\n"
    )
    wells = root / "wells.csv"
    wells.write_text("well_id,reference,offsets\nW1,ref.csv,wa.csv\nW2,ref.csv,wb.csv\n")
    return wells


def batch(root: Path, pipeline: Path, *flags: str) -> dict[str, tuple[str, str]]:
    """``gyropipe batch`` of the fleet from ``root``: each well's (status, detail)."""
    result = gyropipe_cli(
        "batch", pipeline, "--manifest", "wells.csv", "--out", "out", "--workers", "1", *flags,
        cwd=root,
    )  # fmt: skip
    assert result.returncode == 0, result.output
    return {well: (row["status"], row["detail"]) for well, row in summary(root / "out").items()}


def test_only_changed_reruns_the_wells_whose_parameter_files_changed(tmp_path: Path):
    make_fleet(tmp_path)
    pipeline = clearance_pipeline(tmp_path)
    assert batch(tmp_path, pipeline) == {"W1": ("done", "new well"), "W2": ("done", "new well")}

    recorded = json.loads((tmp_path / "out" / "W2" / "run.json").read_text())["parameter_inputs"]
    expected = [
        ("profile.yaml", "read", "options.profile", "profile"),
        ("offsets/b.csv", "offsets", "input", "offset file"),
        ("models/acme.yaml", "uncertainty", "model", "tool-model file"),
        ("models/base.yaml", "uncertainty", "model", "tool-model file"),
    ]
    assert [(e["path"], e["stage"], e["param"], e["what"]) for e in recorded] == [
        (str(tmp_path / name), *rest) for name, *rest in expected
    ]
    for entry in recorded:
        assert entry["sha256"] == hashlib.sha256(Path(entry["path"]).read_bytes()).hexdigest()

    unchanged = {"W1": ("skipped", "unchanged"), "W2": ("skipped", "unchanged")}
    assert batch(tmp_path, pipeline, "--only-changed") == unchanged

    change_one_azimuth(tmp_path / "offsets" / "b.csv")  # W2's offset well only
    assert batch(tmp_path, pipeline, "--only-changed") == {
        "W1": ("skipped", "unchanged"),
        "W2": ("done", "offset file offsets/b.csv changed"),
    }

    # every well reads these two; W2's run above recorded the new offset file's hash
    (tmp_path / "profile.yaml").write_text("description: the J-12 listing, checked\n")
    with open(tmp_path / "models" / "base.yaml", "a") as fh:  # the file acme.yaml extends
        fh.write("revision: '2'\n")
    both = ("done", "tool-model file models/base.yaml changed; profile profile.yaml changed")
    assert batch(tmp_path, pipeline, "--only-changed") == {"W1": both, "W2": both}
    assert [r["well"] for r in runs(tmp_path / "out" / "ledger.sqlite")] == [
        "W1", "W2", "W2", "W1", "W2",
    ]  # fmt: skip


def test_a_batch_from_another_directory_reruns_wells_whose_parameters_name_files_there(
    tmp_path: Path,
):
    """One pipeline whose profile and tool-model file are given by relative paths, batched
    into one OUT from a/, then from b/ (the same fleet, b's base tool model noisier): the
    same parameters now name b's files, so ``--only-changed`` runs every well again, saying
    why, and their σ is b's model's (it said "skipped, unchanged", OUT holding a's)."""
    a, b = tmp_path / "a", tmp_path / "b"
    for root in (a, b):
        root.mkdir()
        make_fleet(root)
    base = b / "models" / "base.yaml"
    base.write_text(base.read_text().replace("GXY-RN: 0.25", "GXY-RN: 0.5"))
    pipeline = clearance_pipeline(tmp_path)
    out = tmp_path / "out"

    def batch_from(root: Path, *flags: str) -> dict[str, tuple[str, str]]:
        args = ["batch", pipeline, "--manifest", "wells.csv", "--out", out, "--workers", "1"]
        result = gyropipe_cli(*args, *flags, cwd=root)
        assert result.returncode == 0, result.output
        return {well: (row["status"], row["detail"]) for well, row in summary(out).items()}

    def major_at_td() -> float:
        table = pq.read_table(out / "W1" / "uncertainty.trajectory.parquet")
        return float(table["ellipse_major"][-1].as_py())

    assert batch_from(a) == {"W1": ("done", "new well"), "W2": ("done", "new well")}
    from_a = major_at_td()
    moved = (
        "done",
        f"working directory changed: {a}→{b} (read.options.profile, uncertainty.model name "
        "files relative to it)",
    )
    assert batch_from(b, "--only-changed") == {"W1": moved, "W2": moved}
    assert major_at_td() > from_a
    recorded = json.loads((out / "W1" / "run.json").read_text())["parameter_inputs"]
    assert str(base) in [entry["path"] for entry in recorded]
    unchanged = ("skipped", "unchanged")
    assert batch_from(b, "--only-changed") == {"W1": unchanged, "W2": unchanged}


def test_a_tool_model_file_changed_changes_the_numbers_of_the_next_batch_in_the_process(
    tmp_path: Path,
):
    """Batches one after the other in one process (the API, a notebook; a pool's workers are
    forked from it): the base file a tool-model file extends edited, then replaced by one of
    the same size and times — each time the wells run again and their position σ is the new
    model's (its gyro compassing noise larger: the ellipses grow), not a model kept from the
    file's earlier bytes while ``run.json`` records the new file's hash."""
    make_fleet(tmp_path)
    pipeline = clearance_pipeline(tmp_path)
    base = tmp_path / "models" / "base.yaml"

    def major_at_td() -> float:
        table = pq.read_table(tmp_path / "out" / "W1" / "uncertainty.trajectory.parquet")
        return float(table["ellipse_major"][-1].as_py())

    batch(tmp_path, pipeline)
    first = major_at_td()

    base.write_text(base.read_text().replace("GXY-RN: 0.25", "GXY-RN: 0.5"))
    rerun = ("done", "tool-model file models/base.yaml changed")
    assert batch(tmp_path, pipeline, "--only-changed") == {"W1": rerun, "W2": rerun}
    second = major_at_td()
    assert second > first

    before = base.stat()
    swapped = base.with_name("swapped.yaml")
    swapped.write_text(base.read_text().replace("GXY-RN: 0.5", "GXY-RN: 0.9"))
    os.utime(swapped, ns=(before.st_atime_ns, before.st_mtime_ns))
    os.replace(swapped, base)
    assert (base.stat().st_size, base.stat().st_mtime_ns) == (before.st_size, before.st_mtime_ns)
    assert batch(tmp_path, pipeline, "--only-changed") == {"W1": rerun, "W2": rerun}
    assert major_at_td() > second


def test_an_offset_file_changed_after_its_read_is_recorded_as_it_was_read(tmp_path: Path):
    """An operator rewrites an offset well's file just after the clearance stage read it:
    the hash recorded (``run.json``, the fingerprint) is that of the bytes the stage read,
    so the next ``--only-changed`` batch sees the change and runs the well again, rather
    than the new file's hash recorded beside the old file's clearance."""
    make_fleet(tmp_path)
    offset = tmp_path / "offsets" / "a.csv"
    read_bytes = []

    def read_then_rewritten(path: Path) -> tuple[pa.Table, WellMetadata]:
        read_bytes.append(path.read_bytes())
        found = stages.registry().read(path, "stations", well=WellMetadata())
        change_one_azimuth(path)
        return found

    wells, _ = offset_tables(
        tmp_path / "wa.csv", read_then_rewritten, WellMetadata(), toolmodels.of_registry(None)
    )
    assert len(read_bytes) == 1 and offset.read_bytes() != read_bytes[0]
    assert wells["sha256"].to_pylist() == [hashlib.sha256(read_bytes[0]).hexdigest()]


def test_a_tool_model_file_edited_after_its_parse_is_recorded_as_it_was_parsed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    """An operator edits the base file a tool-model file extends just after each parse of
    it: the hash recorded (``run.json``) is that of the bytes the run's model was parsed
    from — so the next ``--only-changed`` batch sees the edit — not the edited file's,
    which would make a run of the old model pass for one of the new."""
    make_fleet(tmp_path)
    pipeline = clearance_pipeline(tmp_path)
    monkeypatch.chdir(tmp_path)
    base = tmp_path / "models" / "base.yaml"
    parsed: list[str] = []
    parse = toolmodel.parse_tool_model

    def parse_then_edited(text: str, file: str, *args: Any) -> toolmodel.ToolModel:
        model = parse(text, file, *args)
        if Path(file) == base:
            parsed.append(text)
            with open(base, "a") as fh:
                fh.write(f"# edited after parse {len(parsed)}\n")
        return model

    monkeypatch.setattr(toolmodel, "parse_tool_model", parse_then_edited)
    result = gp.run(pipeline, {"reference": "ref.csv", "offsets": "wa.csv"})
    (recorded,) = [e for e in result.manifest["parameter_inputs"] if e["path"] == str(base)]
    assert parsed and base.read_text() != parsed[-1]
    assert recorded["sha256"] == hashlib.sha256(parsed[-1].encode()).hexdigest()


def test_validate_refuses_a_missing_profile_at_its_line(tmp_path: Path):
    make_fleet(tmp_path)
    pipeline = clearance_pipeline(tmp_path)
    (tmp_path / "profile.yaml").unlink()
    result = gyropipe_cli("validate", pipeline, cwd=tmp_path)
    assert result.returncode != 0
    line = next(
        i for i, text in enumerate(pipeline.read_text().splitlines(), 1) if "profile" in text
    )
    assert f"{pipeline.name}:{line}:" in result.output
    assert "no such file: 'profile.yaml'" in result.output
    assert "Traceback" not in result.output


def test_a_simulation_plan_s_stations_file_is_recorded(tmp_path: Path):
    (tmp_path / "st.csv").write_text(
        "MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n30,0,0\n60,3,45\n90,6,45\n"
    )
    (tmp_path / "plan.yaml").write_text(
        "name: small\nseed: 7\nsite: {latitude: 61.25, date: 2026-11-21}\n"
        "well: {stations: st.csv}\ntool: {preset: mems-vrg}\n"
        "survey: {mode: point, every: 30, dwell: 5, move_time: 1}\n"
    )
    pipeline = write_pipeline(
        tmp_path, [stage("sim", "simulate", persist=["stations"])], name="sim", inputs=("plan",)
    )
    result = gyropipe_cli(
        "run", pipeline, "--input", "plan=plan.yaml", "--out", "out", cwd=tmp_path
    )
    assert result.returncode == 0, result.output
    recorded = json.loads((tmp_path / "out" / "run.json").read_text())["parameter_inputs"]
    digest = hashlib.sha256((tmp_path / "st.csv").read_bytes()).hexdigest()
    assert recorded == [
        {
            "path": str(tmp_path / "st.csv"),
            "sha256": digest,
            "stage": "sim",
            "param": "plan",
            "what": "stations file",
        }
    ]


def test_the_python_api_records_and_refuses_the_same_files(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
):
    make_fleet(tmp_path)
    pipeline = clearance_pipeline(tmp_path)
    monkeypatch.chdir(tmp_path)
    result = gp.run(pipeline, {"reference": "ref.csv", "offsets": "wa.csv"})
    recorded = result.manifest["parameter_inputs"]
    assert [(Path(e["path"]).relative_to(tmp_path).as_posix(), e["what"]) for e in recorded] == [
        ("profile.yaml", "profile"),
        ("offsets/a.csv", "offset file"),
        ("models/acme.yaml", "tool-model file"),
        ("models/base.yaml", "tool-model file"),
    ]
    wells = result.tables["offsets.wells"]
    assert wells.column("sha256").to_pylist() == [recorded[1]["sha256"]]  # the same record
    (tmp_path / "profile.yaml").unlink()
    with pytest.raises(SpecError, match=r"no such file: 'profile\.yaml'") as refused:
        gp.run(pipeline, {"reference": "ref.csv", "offsets": "wa.csv"})
    assert refused.value.problems[0].location.file == str(pipeline)


def test_a_definitive_survey_records_each_run_s_model_file(tmp_path: Path):
    make_fleet(tmp_path)
    pipeline = write_pipeline(
        tmp_path,
        [
            stage("read", "read_stations", input="reference"),
            stage(
                "definitive",
                "definitive_survey",
                {"run1": "read.stations"},
                ["survey"],
                runs={"run1": {"model": "models/acme.yaml"}},
            ),
        ],
        name="definitive",
        inputs=("reference",),
    )
    result = gyropipe_cli(
        "run", pipeline, "--input", "reference=ref.csv", "--out", "out", cwd=tmp_path
    )
    assert result.returncode == 0, result.output
    recorded = json.loads((tmp_path / "out" / "run.json").read_text())["parameter_inputs"]
    assert [(e["path"], e["param"], e["what"]) for e in recorded] == [
        (str(tmp_path / "models" / name), "runs.run1.model", "tool-model file")
        for name in ("acme.yaml", "base.yaml")
    ]


def test_a_recorded_file_gone_is_a_change_named_so(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    monkeypatch.chdir(tmp_path)
    offset = tmp_path / "w3.csv"
    offset.write_text("MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n")
    digest = hashlib.sha256(offset.read_bytes()).hexdigest()
    base = Fingerprint(inputs={}, pipeline="p", params={}, gyropipe="1", plugins={}, well={})
    manifest = {
        "parameter_inputs": [
            {"path": str(offset), "sha256": digest, "stage": "o", "param": "input",
             "what": "offset file"},
        ]
    }  # fmt: skip
    done = base.completed(manifest)
    assert done.files == {str(offset): {"sha256": digest, "what": "offset file"}}
    assert Fingerprint.from_json(done.to_json()) == done

    def now() -> Fingerprint:
        return base.reading(done.files, {path: hashed(path) for path in done.files})

    assert now() == done
    assert changes(done, now()) == []
    assert changes(done, base.reading(done.files, {})) == []  # a pending hash is no reason
    offset.unlink()
    assert changes(done, now()) == ["offset file w3.csv changed (now unreadable)"]


def test_parameter_paths_finds_every_input_path_of_a_params_model(tmp_path: Path):
    class Inner(BaseModel):
        table: InputPath

    class Params(BaseModel):
        profile: InputPath | None = None
        files: list[InputPath] = []
        inner: Inner
        name: Path = Path("not-read")

    for name in ("a.yaml", "b.csv", "c.csv", "d.csv"):
        (tmp_path / name).write_text("x\n")
    params = Params(
        profile=tmp_path / "a.yaml",
        files=[tmp_path / "b.csv", tmp_path / "c.csv"],
        inner=Inner(table=tmp_path / "d.csv"),
    )
    assert list(parameter_paths(params)) == [
        ("profile", tmp_path / "a.yaml"),
        ("files.0", tmp_path / "b.csv"),
        ("files.1", tmp_path / "c.csv"),
        ("inner.table", tmp_path / "d.csv"),
    ]
    with pytest.raises(ValidationError, match="not a regular file"):
        Inner(table=tmp_path)

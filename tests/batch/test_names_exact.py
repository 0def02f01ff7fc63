"""Names checked once, exactly (issue 32 item 15): a name is matched to its very end
(``\\Z``: ``$`` also matched before a final newline), so an output file name or a well id
ending in a newline is refused; reserved names are refused up to case; a quoted line break
in a manifest cell is refused at its line, not joined away (``w1w2``); and publishing over
a well directory that is a symlink leaves no ``.trash`` link behind."""

from __future__ import annotations

from pathlib import Path

import pytest
from batch_support import make_wells

from pipeline.atomic import replace_dir
from pipeline.filenames import check_output_filename
from tests_support import ROOT, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"


def test_an_output_name_ending_in_a_newline_is_refused_by_validate(tmp_path: Path) -> None:
    """Before: ``trajectory.csv\\n`` passed the plain-name check and was written so."""
    path = tmp_path / "survey.yaml"
    text = SURVEY.read_text()
    assert "filename: trajectory.csv\n" in text
    path.write_text(text.replace("filename: trajectory.csv\n", 'filename: "trajectory.csv\\n"\n'))
    result = gyropipe_cli("validate", path)
    assert result.returncode == 2
    (problem,) = result.stderr.splitlines()[1:]
    assert problem.startswith(f"  {path}:")
    assert "not a plain file name" in problem


@pytest.mark.parametrize("name", ["run.json\n", "RUN.JSON", "Run.Json"])
def test_the_runs_manifest_name_is_reserved_exactly_and_up_to_case(name: str) -> None:
    with pytest.raises(ValueError, match=r"not a plain file name|the run's manifest"):
        check_output_filename(name)


def _manifest(tmp_path: Path, rows: str) -> Path:
    make_wells(tmp_path, ["a"])
    path = tmp_path / "wells.csv"
    path.write_text(f"well_id,stations\n{rows}")
    return path


def test_a_quoted_line_break_in_a_manifest_id_is_refused_at_its_line(
    tmp_path: Path, survey: Path
) -> None:
    """Before: the two lines were joined into well ``w1w2``."""
    manifest = _manifest(tmp_path, 'w0,a.csv\n"w1\nw2",a.csv\n')
    out = tmp_path / "out"
    result = gyropipe_cli("batch", survey, "--manifest", manifest, "--out", out)
    assert result.returncode == 2
    assert result.stderr.splitlines() == [
        f"error: {manifest}:3: column 'well_id': a line break in 'w1\\nw2' (a quoted cell "
        "spans lines): a manifest cell is one line"
    ]
    assert not out.exists()


@pytest.mark.parametrize(
    ("rows", "refusal"),
    [
        # a record after a multi-line one is named by its own line (3 cells on line 2)
        ('w0,"a.csv\n",x\nw1,a.csv\n', ":2: 3 cells, the header has 2"),
        # fuzz finding: resolving a symlink loop raised RuntimeError out of the reader
        ("w1,loop.csv\n", ":2: well 'w1': stations 'loop.csv': "),
        ("LEDGER.SQLITE,a.csv\n", ":2: well id 'LEDGER.SQLITE' names a file the batch keeps"),
        ("", ":1: no wells listed below the header"),  # fuzz finding: the header's line
    ],
)
def test_manifest_rows_refused_at_their_line(
    tmp_path: Path, survey: Path, rows: str, refusal: str
) -> None:
    (tmp_path / "loop.csv").symlink_to(tmp_path / "loop.csv")
    manifest = _manifest(tmp_path, rows)
    result = gyropipe_cli("batch", survey, "--manifest", manifest, "--out", tmp_path / "out")
    assert result.returncode == 2
    assert f"error: {manifest}{refusal}" in result.stderr


def test_a_well_id_from_a_file_name_ending_in_a_newline_is_refused(
    tmp_path: Path, survey: Path
) -> None:
    """Before: the well's directory was created with the newline in its name."""
    make_wells(tmp_path / "in", ["w1\n"])
    out = tmp_path / "out"
    result = gyropipe_cli("batch", survey, "--inputs", tmp_path / "in" / "*.csv", "--out", out)
    assert result.returncode == 2
    (line,) = result.stderr.splitlines()  # the file's name shown escaped: one line
    assert line.endswith(
        "w1\\n.csv': well id 'w1\\n' is not a plain directory name (letters, "
        "digits, '.', '_', '-'; starting with a letter or digit)"
    )
    assert not out.exists()


def test_publishing_over_a_symlinked_well_directory_leaves_no_trash_link(tmp_path: Path) -> None:
    """Before: the swapped-out link was left at ``<staging>.trash`` (rmtree refuses links)."""
    user = tmp_path / "user"
    user.mkdir()
    (user / "notes.txt").write_text("mine")
    out = tmp_path / "out"
    out.mkdir()
    (out / "w1").symlink_to(user, target_is_directory=True)
    staging = tmp_path / ".w1.staging"
    staging.mkdir()
    (staging / "run.json").write_text("{}")
    replace_dir(staging, out / "w1")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "user"]
    assert not (out / "w1").is_symlink() and (out / "w1" / "run.json").is_file()
    assert (user / "notes.txt").read_text() == "mine"  # the link went, not what it named

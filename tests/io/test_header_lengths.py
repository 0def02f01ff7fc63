"""Header texts of CSV and LAS files are bounded as WITSML's are (TEXT_MAX characters a value,
HEADER_LINE_MAX a line): before, a megabyte well name in a CSV title line or a LAS ~Well item
was read and copied into every table, header and file written from it (a 5-million-character
one: 10 MB CSV and 11.7 MB Parquet outputs). Refused at its line, through ``gp.read`` and the
CLI; a value of the limit is read, and gyropipe writes no header it would refuse."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import pipeline as gp
from hostile_inputs import csv_named, las_named
from pipeline.errors import InputFileError
from pipeline.io.limits import HEADER_LINE_MAX, TEXT_MAX
from pipeline.uncertainty.tieon import TieOn, TieOnRecord
from tests_support import gyropipe_cli

LONGER = f"longer than the {TEXT_MAX:,} gyropipe reads in a header (a real one's names, numbers"

HUGE = {
    "well.csv": (csv_named(1_000_000), 1, "the value of 'Well' is 1,000,000 characters"),
    "comment.csv": (
        csv_named(1_000_000, key="# well.well="),
        1,
        "the value of 'well.well' is 1,000,000 characters",
    ),
    "company.csv": (
        b"North Reference: true\n Company:\t" + b"c" * 5_000_000 + b",,\nMD (m),Inc (deg),Azi"
        b"muth (deg)\n0,0,0\n100,1,10\n",
        2,
        "the value of 'Company' is 5,000,000 characters",
    ),
    "free.csv": (
        b"# " + b"a(" * 40_000 + b"\n" + csv_named(1),
        1,
        f"the title line is 80,002 characters, longer than the {HEADER_LINE_MAX:,}",
    ),
    "well.las": (las_named(5_000_000), 8, "the value of 'WELL' is 5,000,000 characters"),
    "unit.las": (
        las_named(1).replace(b" INCL.DEG", b" INCL." + b"d" * 70_000),
        11,
        "the unit of 'INCL' is 70,000 characters",
    ),
    "descr.las": (
        las_named(1).replace(b": inclination", b": " + b"i" * 1_000_000),
        11,
        "the description of 'INCL' is 1,000,000 characters",
    ),
}
"""Files whose header holds a text too long: the line and the message's start."""


@pytest.mark.parametrize("name", sorted(HUGE))
def test_a_header_text_over_the_limit_is_refused_at_its_line(tmp_path: Path, name: str):
    data, line, problem = HUGE[name]
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(InputFileError) as caught:
        gp.read(path, kind="stations")
    assert caught.value.line == line and caught.value.reason.startswith(problem), caught.value
    out = tmp_path / "out"
    result = gyropipe_cli("run", "pipelines/survey.yaml", "--input", str(path), "--out", str(out))
    assert result.returncode == 1, result.stderr[:1000]
    assert f"InputFileError: {path}:{line}: {problem}" in result.stderr, result.stderr[:1000]
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert not list(out.glob("*.csv")), "nothing is written from the file"


@pytest.mark.parametrize("suffix", [".csv", ".las"])
def test_a_well_name_of_the_limit_is_read_one_more_is_refused(tmp_path: Path, suffix: str):
    named = csv_named if suffix == ".csv" else las_named
    path = tmp_path / f"longest{suffix}"
    path.write_bytes(named(TEXT_MAX))
    frame = gp.read(path, kind="stations")
    assert frame.attrs["well"]["well"] == "x" * TEXT_MAX and list(frame["md"]) == [0.0, 100.0]
    path.write_bytes(named(TEXT_MAX + 1))
    with pytest.raises(InputFileError, match=re.escape(f"is 65,537 characters, {LONGER}")):
        gp.read(path, kind="stations")


def test_long_legitimate_title_lines_are_read(tmp_path: Path):
    """A guard: a ``# tie_on=`` record of 500 surveys (110 characters a survey: 43,898) and
    a free comment line of HEADER_LINE_MAX characters are no header texts too long."""
    surveys = [TieOn(survey="run-000", md=0.0, basis="wellhead")] + [
        TieOn(survey=f"run-{i:03d}", md=100.0 * i, basis="survey", parent=f"run-{i - 1:03d}")
        for i in range(1, 500)
    ]
    record = TieOnRecord(surveys=tuple(surveys)).model_dump_json()
    rows = "".join(f"{100.0 * i},{i % 5},10,run-{i:03d}\n" for i in range(500))
    path = tmp_path / "ties.csv"
    path.write_text(
        f"# {'c' * (HEADER_LINE_MAX - 2)}\n# north_reference=true\n# tie_on={record}\n"
        f"md[m],inc[deg],azi[deg],survey\n{rows}"
    )
    assert len(record) > 40_000
    assert len(gp.read(path, kind="stations")) == 500


@pytest.mark.parametrize("suffix", [".csv", ".las", ".xml"])
def test_no_writer_writes_a_header_text_its_reader_refuses(tmp_path: Path, suffix: str):
    """A company of TEXT_MAX + 1 characters (given with --well) is refused by the writer,
    naming it (before: CSV and LAS wrote it, a file their readers now refuse); one of
    TEXT_MAX is written and reads back whole."""
    source = tmp_path / "small.csv"
    source.write_bytes(csv_named(3))
    for chars in (TEXT_MAX + 1, TEXT_MAX):
        out = tmp_path / f"{chars}{suffix}"
        result = gyropipe_cli("convert", source, out, "--well", f"company={'c' * chars}")
        if chars > TEXT_MAX:
            assert result.returncode == 2 and len(result.stderr) < 600, result.stderr[:1000]
            assert f"cannot be written to {out.name}" in result.stderr and not out.exists()
            assert "65,537 characters" in result.stderr, result.stderr
        else:
            assert result.returncode == 0, result.stderr[:1000]
            assert gp.read(out, kind="stations").attrs["well"]["company"] == "c" * TEXT_MAX

"""A footer (trailing text lines after the data: ``End of survey``, ``Total,,,1234``) is left
out of the data — and said so, at its line: a row left out is never left out quietly."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from click.testing import CliRunner

import pipeline as gp
from pipeline.cli import main
from pipeline.errors import InputFileWarning

ROOT = Path(__file__).resolve().parents[2]
ROWS = "MD (m),Inc (deg),Azimuth True (deg)\n0,0,0\n30,1,10\n60,2,20\n90,3,30\n"


def test_a_footer_is_left_out_with_a_warning_at_its_line(tmp_path: Path):
    path = tmp_path / "stations.csv"
    path.write_text(ROWS + "\nEnd of survey\nTotal,,,1234\n")
    with pytest.warns(InputFileWarning) as caught:
        stations = gp.read(path)
    assert len(stations) == 4
    messages = [str(w.message) for w in caught]
    assert messages == [
        f"{path}:7: 2 trailing lines after the last data row read as a footer (text, no "
        "number where a row has one) and left out, the first: 'End of survey'"
    ]


def test_a_text_row_at_the_end_is_told_by_the_cli(tmp_path: Path):
    """A bad last row that the footer rule takes (no number in it) is named, not lost
    without a word."""
    path = tmp_path / "stations.csv"
    path.write_text(ROWS + "not,a,number\n")
    out = tmp_path / "out"
    args = ["run", str(ROOT / "pipelines" / "survey.yaml"), "--input", str(path), "--out", str(out)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert f"{path}:6: a trailing line after the last data row read as a footer" in result.output
    assert "'not,a,number'" in result.output


def test_a_file_without_a_footer_warns_nothing(tmp_path: Path):
    path = tmp_path / "stations.csv"
    path.write_text(ROWS)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        assert len(gp.read(path)) == 4

"""A LAS 3.0 directional survey: stations in ``~Inclinometry_Definition`` and
``~Inclinometry_Data`` (the spec's data set for surveys), other sections after it, read as
survey stations by ``gp.read`` and ``gyropipe run`` (issue 28 item 11, LAS 3.0 data
sections under other names). A file with a ``~Log_Data`` section reads its log, as before."""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import InputFileError
from tests_support import gyropipe_cli

SURVEY = """~Version
VERS.   3.0 : CWLS LOG ASCII STANDARD - VERSION 3.0
WRAP.   NO  :
DLM.    COMMA :
~Well
WELL.  W-1 :
NULL.  -999.25 :
~Inclinometry_Definition
MD.m    : measured depth
INC.deg : inclination
AZI.deg : azimuth (true north)
~Inclinometry_Data | Inclinometry_Definition
0, 0, 0
100, 5, 45
200, 10, 46
{extra}
~Tops_Definition
TOPT.   : top name
TOPD.m  : top depth
~Tops_Data | Tops_Definition
Top A, 150
"""


def test_inclinometry_data_reads_as_stations(tmp_path: Path):
    source = tmp_path / "survey.las"
    source.write_text(SURVEY.format(extra=""))
    stations = gp.read(source, kind="stations")
    assert stations.md.tolist() == [0.0, 100.0, 200.0]
    assert stations.inc.tolist() == [0.0, 5.0, 10.0]
    assert stations.azi.tolist() == [0.0, 45.0, 46.0]
    out = tmp_path / "out"
    done = gyropipe_cli("run", "pipelines/survey.yaml", "--input", source, "--out", out)
    assert done.returncode == 0, done.stderr
    assert pq.read_table(out / "trajectory.trajectory.parquet").num_rows == 3


def test_a_bad_inclinometry_row_is_located(tmp_path: Path):
    source = tmp_path / "survey.las"
    source.write_text(SURVEY.format(extra="300, 12"))  # file line 16
    with pytest.raises(InputFileError, match="expected 3 values") as caught:
        gp.read(source, kind="stations")
    assert caught.value.line == 16


def test_a_log_data_section_is_read_before_the_inclinometry(tmp_path: Path):
    log = SURVEY.format(extra="") + (
        "~Log_Definition\nDEPT.m : depth\nGR.gAPI : gamma ray\n~Log_Data | Log_Definition\n"
        "1000, 55\n1001, 56\n"
    )
    source = tmp_path / "both.las"
    source.write_text(log)
    table = gp.read(source, kind="log")
    assert [c for c in table.columns if c != "source_line"] == ["DEPT", "GR"]
    assert table.GR.tolist() == [55.0, 56.0]

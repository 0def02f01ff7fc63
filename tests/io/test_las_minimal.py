"""Minimal LAS files that lasio reads (issue 28 item 11): a barebones file of ``~C`` and
``~A`` only (lasio's ``barebones.las``) or ``~A`` only (``barebones2.las``), and a
header-only log (``header_only.las``: ~V ~W ~C and no ~A; ``issue79.las``: a data title
``~   DEPTH …`` that is not ``~A``) read as logs — the latter as zero-row tables with their
curves and units — through ``gp.read``, ``--kind auto`` and ``gyropipe convert``; a file
``auto`` cannot read is named in one line."""

from __future__ import annotations

import warnings
from pathlib import Path

import lasio
import pytest

import pipeline as gp
from pipeline.errors import InputFileWarning, WrongKindError
from tests_support import ROOT, gyropipe_cli

BAREBONES = """\
#-----------------------------------------------------------------------------
~CURVE INFORMATION
#MNEM.UNIT   API CODE                                  DESCRIPTION
#---- -----  --------                                  -----------------------
DEPT .F                                                :DEPTH (BOREHOLE) {F10.1}
#-----------------------------------------------------------------------------
#     DEPT
~A
     200.0
     201.0"""
HEADER_ONLY = """\
~VERSION INFORMATION
VERS  .    2.0                     :CWLS Log ASCII Standard - VERSION 2.0
WRAP  .    NO                      :One Line per Depth step
~WELL INFORMATION
STRT  .ft              9000.00000  :START DEPTH
STOP  .ft             10000.00000  :STOP DEPTH
STEP  .ft                     0.5  :STEP
NULL  .                   -999.25  :NULL VALUE
WELL  .                    GUSHER  :WELL NAME
~CURVE INFORMATION
DEPT            .ft                :Depth Index
F3_S11_PHA      .deg               :Frequency 3 Mudcake Probe S11 Reflection Phase
PWXO            .ft3/ft3           :Invaded Zone Water-filled Porosity
#-------------------------------------------------------------
"""
ISSUE79 = """\
~Version Information
 VERS.  3.0   : CWLS LOG ASCII STANDARD
 WRAP.  NO    : One line per depth step
 DLM .  SPACE : Delimiting character
~Well Information
 STRT .F                 1088.1737       : First Index Value
 STOP .F                 8211.6737       : Last Index Value
 STEP .F                    0.5000       : Step
 NULL .                  -999.2500       : Null Value
~Curve
 DEPT  .F                                : Depth {F}
 TENS  .LBF                              : Tension {F}
 GAMMA .                                 : GR {F}
~   DEPTH     TENSION     GR
  1088.1737   339.4208    35.2786
  1088.6737   339.4208    35.2786
"""
FILES = {"barebones.las": BAREBONES, "header_only.las": HEADER_ONLY, "issue79.las": ISSUE79}


def _file(tmp_path: Path, name: str) -> Path:
    if name == "barebones2.las":  # lasio's own file: ~A only, no ~V, ~W or ~C
        return ROOT / "tests" / "data" / "las" / "lasio" / name
    path = tmp_path / name
    path.write_text(FILES[name])
    return path


@pytest.mark.parametrize(
    "name", ["barebones.las", "barebones2.las", "header_only.las", "issue79.las"]
)
@pytest.mark.parametrize("kind", ["log", "auto"])
def test_read_as_lasio_reads_it(tmp_path: Path, name: str, kind: str) -> None:
    path = _file(tmp_path, name)
    expected = lasio.read(str(path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frame = gp.read(path, kind=kind)
    assert list(frame.columns) == [*expected.keys(), "source_line"]
    assert len(frame) == len(expected.data)
    units = {c.mnemonic: c.unit for c in expected.curves if c.unit}
    assert {k: v for k, v in frame.attrs["units"].items() if k in units} == units
    for curve in expected.curves:
        assert frame[curve.mnemonic].tolist() == pytest.approx(list(curve.data), abs=1e-12)


def test_header_only_log_is_a_zero_row_table_with_its_curves_and_units(tmp_path: Path) -> None:
    path = _file(tmp_path, "header_only.las")
    with pytest.warns(InputFileWarning, match="no ~A"):
        frame = gp.read(path)
    assert len(frame) == 0
    assert list(frame.columns) == ["DEPT", "F3_S11_PHA", "PWXO", "source_line"]
    assert frame.attrs["units"]["DEPT"] == "ft" and frame.attrs["units"]["PWXO"] == "ft3/ft3"
    with (
        pytest.raises(WrongKindError, match="not survey stations"),
        pytest.warns(InputFileWarning, match="no ~A"),  # tried as a log, to name that kind
    ):
        gp.read(path, kind="stations")


@pytest.mark.parametrize(
    ("name", "rows"),
    [("barebones.las", 2), ("barebones2.las", 3), ("header_only.las", 0), ("issue79.las", 0)],
)
def test_convert(tmp_path: Path, name: str, rows: int) -> None:
    out = tmp_path / "out.csv"
    result = gyropipe_cli("convert", str(_file(tmp_path, name)), str(out), check=False)
    assert result.returncode == 0, result.output
    assert f"well log, {rows} rows" in result.stdout
    lines = [line for line in out.read_text().splitlines() if not line.startswith("#")]
    assert len(lines) == rows + 1  # the header and the rows


def test_convert_kind_stations_of_a_header_only_log_names_the_kind(tmp_path: Path) -> None:
    path = _file(tmp_path, "header_only.las")
    result = gyropipe_cli("convert", str(path), str(tmp_path / "o.csv"), "--kind", "stations")
    assert result.returncode == 1
    assert "not survey stations" in result.stderr and "use --kind log" in result.stderr


def test_an_auto_failure_says_what_the_file_is_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "table.csv"
    path.write_text("a,b\n1,2\n")
    result = gyropipe_cli("convert", str(path), str(tmp_path / "o.parquet"), check=False)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1, result.stderr
    assert errors[0].startswith(
        f"error: {path}: a csv file that reads as none of stations, samples, readings; "
        "as stations: no header row with md, inc, azi columns"
    )

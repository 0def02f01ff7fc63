"""The LAS reader's ``log`` kind: any LAS 1.2/2.0/3.0 log, compared with lasio on files of
lasio's own test suite (``tests/data/las/lasio``, MIT) and on small files of our own
(``tests/data/las``), each odd case on its own; the LAS writer's output of a log read back
by lasio and by us; ``gyropipe convert`` of a log to Parquet, CSV and LAS and back."""

from __future__ import annotations

import io
import logging
import math
import re
import warnings
from pathlib import Path
from typing import Any

import lasio
import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.contracts import DESCRIPTION_KEY, SOURCE_LINE, UNIT_KEY
from pipeline.convert import read_kind
from pipeline.errors import InputFileError, InputFileWarning, WrongKindError
from pipeline.io import las as las_plugin
from pipeline.io.las.header import utf16_codec
from pipeline.io.precision import DECIMALS
from pipeline.plugins import load_registry
from pipeline.tables import LogTable
from pipeline.well import WellMetadata
from tests_support import (
    ROOT,
    assert_exported,
    byte_mutations,
    comparable_cell,
    gyropipe_cli,
    mutate_bytes,
    plugin_io,
)

logging.getLogger("lasio").setLevel(logging.CRITICAL)

READER, WRITER = plugin_io(las_plugin)
DATA = ROOT / "tests" / "data" / "las"
LASIO = DATA / "lasio"

SAME_AS_LASIO = [
    "1.2/sample.las",
    "1.2/issue-264-dot-delimiter.las",
    "2.0/sample_2.0.las",
    "2.0/sample_2.0_wrapped.las",
    "3.0/sample_3.0.las",
    "3.0/sample_3.0_tab_dlm.las",
    "null_policy_(null).las",
    "null_policy_dashes.las",
    "null_policy_runon.las",
    "comma_decimal_mark.las",
    "data_characters.las",
    "lasio_issue_271.las",
    "barebones2.las",
    "index_null.las",
    "mnemonic_duplicate.las",
]
"""lasio's files gyropipe reads as lasio does (text nulls as nulls where lasio keeps text)."""
OURS_SAME_AS_LASIO = ["gr.las", "latin1.las", "time_log.las", "las3_space_decimal_comma.las"]


def read_log(path: Path, **options: Any) -> tuple[pa.Table, WellMetadata, list[str]]:
    """The log, its well metadata and the warnings given while reading it."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table, well = READER.read(path, "log", READER.options.model_validate(options))
    messages = [str(w.message) for w in caught if issubclass(w.category, InputFileWarning)]
    return table, well, messages


def values(table: pa.Table, name: str) -> list[Any]:
    return list(table.column(name).to_pylist())


def unit(table: pa.Table, name: str) -> str | None:
    raw = (table.schema.field(name).metadata or {}).get(UNIT_KEY)
    return raw.decode() if raw else None


def assert_same_table(table: pa.Table, expected: pa.Table) -> None:
    """Same columns, types, units and values (NaN equal to NaN)."""
    assert table.column_names == expected.column_names
    for name in expected.column_names:
        assert table.schema.field(name).type == expected.schema.field(name).type, name
        assert unit(table, name) == unit(expected, name), name
        assert [comparable_cell(v) for v in values(table, name)] == [
            comparable_cell(v) for v in values(expected, name)
        ], name


def assert_same_as_lasio(table: pa.Table, path: Path) -> None:
    """Mnemonics, units and values (NaN for nulls) equal lasio's reading of ``path``."""
    las = lasio.read(str(path))
    null = las.well["NULL"].value if "NULL" in las.well else None
    names = [n for n in table.column_names if n != SOURCE_LINE]
    assert names == [c.mnemonic for c in las.curves]
    assert [unit(table, n) or "" for n in names] == [c.unit for c in las.curves]
    for name, curve in zip(names, las.curves, strict=True):
        ours = [comparable_cell(v) for v in values(table, name)]
        assert ours == [comparable_cell(v, null) for v in curve.data.tolist()], name


# ----------------------------------------------------------------------- peer: lasio


@pytest.mark.parametrize("name", SAME_AS_LASIO)
def test_lasio_test_files_read_as_lasio_reads_them(name: str) -> None:
    table, _, _ = read_log(LASIO / name)
    assert_same_as_lasio(table, LASIO / name)
    assert table.column_names[-1] == SOURCE_LINE
    LogTable.validate_table(table)


@pytest.mark.parametrize("name", OURS_SAME_AS_LASIO)
def test_our_files_read_as_lasio_reads_them(name: str) -> None:
    table, _, _ = read_log(DATA / name)
    assert_same_as_lasio(table, DATA / name)


@pytest.mark.parametrize("name", ["encodings_utf16lebom.las", "encodings_utf16be.las"])
def test_utf16_files_lasio_cannot_read(tmp_path: Path, name: str) -> None:
    path = LASIO / name
    with pytest.raises((KeyError, lasio.exceptions.LASHeaderError)):  # no section found
        lasio.read(str(path))
    table, _, _ = read_log(path)
    codec = utf16_codec(path.read_bytes())
    assert codec is not None
    copy = tmp_path / "utf8.las"  # lasio reads the same text as UTF-8 (with a BOM)
    copy.write_text(path.read_bytes().decode(codec).removeprefix("\ufeff"), "utf-8-sig")
    assert_same_as_lasio(table, copy)
    assert table.column_names[2] == "ºᶟᵌᴬŃ"
    assert READER.sniff(path)


def test_utf8_without_bom_is_utf8() -> None:
    """lasio takes it for Windows-1252 (units 'Ð¼ÐµÑ‚ÐµÑ€'); it is UTF-8: 'метер'."""
    table, _, _ = read_log(LASIO / "sample_cyrillic_depth_unit.las")
    assert (unit(table, "DEPT"), unit(table, "DT")) == ("метер", "US/м")
    assert lasio.read(str(LASIO / "sample_cyrillic_depth_unit.las")).curves[0].unit != "метер"


@pytest.mark.parametrize(
    ("name", "line", "message"),
    [
        ("lasio/excess_curves.las", 27, "expected 6 values (one per curve: DEPTH, TVD, VS"),
        ("lasio/sample_lastcolblanked.las", 45, "expected 8 values"),
        ("wrong_count.las", 26, "expected 4 values (one per curve: DEPT, GR, RHOB, NPHI), got 3"),
    ],
)
def test_a_wrong_value_count_is_an_error_naming_its_line(
    name: str, line: int, message: str
) -> None:
    """lasio reshapes the values into rows (filling or shifting them) or fails; we name the
    row."""
    with pytest.raises(InputFileError) as info:
        read_log(DATA / name)
    assert info.value.line == line
    assert message in str(info.value)
    assert str(info.value).startswith(f"{DATA / name}:{line}: ")


def test_windows_indeterminate_values_are_nulls() -> None:
    """lasio reads '-1.#IND0000' as -1.0 in one curve and NaN in the other."""
    table, _, _ = read_log(LASIO / "null_policy_ind.las")
    assert all(math.isnan(v) for v in values(table, "CN") + values(table, "CD"))
    assert values(table, "GR")[0] == 141.53386454
    assert lasio.read(str(LASIO / "null_policy_ind.las"))["CN"][0] == -1.0


# ------------------------------------------------------------------------- the table


def test_ordinary_log() -> None:
    table, well, warned = read_log(DATA / "gr.las")
    assert table.column_names == ["DEPT", "GR", "RHOB", "NPHI", SOURCE_LINE]
    assert [unit(table, n) for n in ("DEPT", "GR", "RHOB", "NPHI")] == ["M", "GAPI", "G/CC", "V/V"]
    assert table.schema.field("GR").metadata[DESCRIPTION_KEY] == b"gamma ray"
    assert values(table, "DEPT") == [1500.0, 1500.5, 1501.0, 1501.5, 1502.0]
    assert math.isnan(values(table, "GR")[1]) and math.isnan(values(table, "RHOB")[3])
    assert table.column("GR").null_count == 0  # NaN, not null
    assert values(table, SOURCE_LINE) == [24, 25, 26, 27, 28]
    assert (well.well, well.field, well.company) == ("GR-7", "North Field", "Example Oil Co.")
    assert (well.uwi, well.latitude, well.longitude) == (
        "100/07-12-045-06W5/00",
        52.8771,
        -114.8245,
    )
    assert str(well.survey_date) == "2021-03-14"
    assert warned == []


def test_las_1_2() -> None:
    table, well, _ = read_log(LASIO / "1.2/sample.las")
    assert table.column_names[:3] == ["DEPT", "DT", "RHOB"]
    assert values(table, "DT") == [123.45] * 3
    assert well.well == "ANY ET AL OIL WELL #12"  # LAS 1.2: the value after the colon


def test_las_3_log_definition_and_data() -> None:
    """Only ~Log_Data is the log (not ~Drilling_Data, ~Core_Data…); DLM COMMA; a {S} curve
    is text; array elements NMR[1]… are curves."""
    table, well, _ = read_log(LASIO / "3.0/sample_3.0.las")
    assert table.num_rows == 3
    assert table.schema.field("CDES").type == pa.string()
    assert values(table, "CDES") == ["DOLOMITE WI/VUGS", "LIMESTOVE", "LOST INTERVAL"]
    assert values(table, "YME") == [1.45e12, 1.47e12, 2.85e12]
    assert values(table, "NMR[5]") == [13.0, 25.0, 17.0]
    assert unit(table, "NMR[1]") == "ms"
    assert well.well == "ANY ET AL 12-34-12-34"
    tab, _, _ = read_log(LASIO / "3.0/sample_3.0_tab_dlm.las")
    assert tab.drop_columns(SOURCE_LINE).equals(table.drop_columns(SOURCE_LINE))


def test_las_3_space_delimited_with_decimal_commas_and_declared_text() -> None:
    table, _, _ = read_log(DATA / "las3_space_decimal_comma.las")
    assert values(table, "DEPT") == [100.0, 100.2, 100.4]
    assert values(table, "PERM")[::2] == [12.5, 8.25] and math.isnan(values(table, "PERM")[1])
    assert values(table, "LITH") == ["fine sand", "shale", None]  # {S}; -999.25 is NULL
    assert values(table, "SAMP") == ["01/02/2020", "02/02/2020", "03/02/2020"]  # {DD/MM/YYYY}
    assert table.schema.field("LITH").metadata[DESCRIPTION_KEY] == b"lithology"


def test_decimal_comma_only_where_commas_cannot_delimit() -> None:
    table, _, _ = read_log(LASIO / "comma_decimal_mark.las")
    assert values(table, "SFLU")[1] == 123.42


def test_wrapped() -> None:
    table, _, _ = read_log(LASIO / "2.0/sample_2.0_wrapped.las")
    assert table.num_columns == 36 + 1 and table.num_rows == 2
    assert values(table, "DEPT") == [910.0, 909.875]


def test_latin_1() -> None:
    table, well, _ = read_log(DATA / "latin1.las")
    assert (unit(table, "TEMP"), unit(table, "DT")) == ("°C", "µs/ft")
    assert well.well == "Puits Élodie-2"


def test_text_nulls() -> None:
    table, _, _ = read_log(DATA / "time_log.las")
    hook, spp = values(table, "HKLD"), values(table, "SPP")
    assert hook[0] == 181.2 and math.isnan(hook[1])  # -1.#IND
    assert math.isnan(spp[0]) and spp[1] == 2450.0 and math.isnan(spp[2])  # NaN, (null)
    nulls, _, _ = read_log(LASIO / "null_policy_(null).las")
    assert nulls.schema.field("RHOB").type == pa.float64()
    assert values(nulls, "RHOB")[:2] == [2550.0, 2550.0] and math.isnan(values(nulls, "RHOB")[2])
    dashes, _, _ = read_log(LASIO / "null_policy_dashes.las")
    rhob = values(dashes, "RHOB")
    assert math.isnan(rhob[0]) and rhob[1] == -2550.0 and math.isnan(rhob[2])


def test_times_of_day_are_text() -> None:
    table, _, _ = read_log(DATA / "time_log.las")
    assert table.column_names[0] == "ETIM"
    assert table.schema.field("CLOCK").type == pa.string()
    assert values(table, "CLOCK") == ["23:59:58", "23:59:59", "00:00:00"]
    chars, _, _ = read_log(LASIO / "data_characters.las")
    assert values(chars, "TIME") == ["00:00:00", "00:00:01"]  # a text index is kept as text
    assert values(chars, "DATE") == ["01-Jan-20", "01-Jan-20"]


def test_text_curves_and_quotes() -> None:
    table, _, _ = read_log(LASIO / "lasio_issue_271.las")
    assert values(table, "ZONE")[2:4] == ["pick gamma", "pick delta"]
    assert math.isnan(values(table, "TEST")[4])


def test_other_text_makes_a_text_curve(tmp_path: Path) -> None:
    """'ERR' is no null: the curve is text, its cells as written, as lasio keeps it."""
    path = tmp_path / "err.las"
    path.write_text((DATA / "gr.las").read_text().replace("  52.90 ", "    ERR "))
    table, _, _ = read_log(path)
    assert table.schema.field("GR").type == pa.string()
    assert values(table, "GR") == ["45.20", None, "ERR", "61.00", "58.40"]
    assert_same_as_lasio(table, path)


def test_run_on_values() -> None:
    table, _, warned = read_log(LASIO / "null_policy_runon.las")
    assert values(table, "C05")[2] == -19508.961  # '7.330-19508.961'
    assert values(table, "C04")[2] == 7.33
    assert math.isnan(values(table, "C04")[1]) and math.isnan(values(table, "C05")[1])
    assert any(":33: '7.020101130.188' holds 2 values run together (C04, C05)" in w for w in warned)


def test_no_curve_section() -> None:
    table, _, warned = read_log(LASIO / "barebones2.las")
    assert table.column_names[:-1] == [f"UNKNOWN:{i}" for i in range(1, 9)]
    assert any("no ~Curve section" in w for w in warned)


def test_repeated_mnemonics() -> None:
    table, _, _ = read_log(LASIO / "mnemonic_duplicate.las")
    assert table.column_names[4:6] == ["SFLU:1", "SFLU:2"]


def test_the_null_value_is_not_applied_to_the_index() -> None:
    table, _, _ = read_log(LASIO / "index_null.las")  # NULL 999.25
    assert values(table, "DEPT") == [999.0, 999.25, 999.5]
    assert math.isnan(values(table, "DT")[0])


def test_header_contradicting_the_data_is_a_warning(tmp_path: Path) -> None:
    path = tmp_path / "stop.las"
    path.write_text((DATA / "gr.las").read_text().replace("1502.0 : stop", "1600.0 : stop"))
    table, _, warned = read_log(path)
    assert table.num_rows == 5
    assert warned == [
        f"{path}:28: STOP is 1600 but the last index value (DEPT) is 1502 on line 28: the file "
        "may be truncated; the data are kept"
    ]


def test_unreadable_well_items_are_left_out_with_a_warning(tmp_path: Path) -> None:
    path = tmp_path / "date.las"
    path.write_text((DATA / "gr.las").read_text().replace("2021-03-14", "05/06/2021"))
    _, well, warned = read_log(path)
    assert well.survey_date is None and well.well == "GR-7"
    assert any(":15: DATE '05/06/2021': ambiguous" in w and "left out" in w for w in warned)


def test_no_data_section(tmp_path: Path) -> None:
    path = tmp_path / "header.las"
    path.write_text((DATA / "gr.las").read_text().split("~A")[0])
    table, _, warned = read_log(path)
    assert table.num_rows == 0 and table.column_names[:-1] == ["DEPT", "GR", "RHOB", "NPHI"]
    assert any("no ~A (data) section" in w for w in warned)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("100.0, 0.63, 302.19\n", "not a LAS file"),
        ((DATA / "gr.las").read_text().replace("  52.90 ", "  1e999 "), "'1e999' is out of range"),
    ],
)
def test_refused(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "bad.las"
    path.write_text(content)
    with pytest.raises(InputFileError, match=re.escape(message)):
        read_log(path)


def test_survey_options_are_refused_for_a_log() -> None:
    with pytest.raises(InputFileError, match="option columns names canonical columns"):
        read_log(DATA / "gr.las", columns={"md": "DEPT"})


def test_a_log_is_not_a_survey() -> None:
    path = DATA / "gr.las"
    with pytest.raises(WrongKindError) as info:
        READER.read(path, "stations", READER.options.model_validate({}))
    assert str(info.value) == (
        f"{path}: a depth-indexed LAS log with curves GR, RHOB, NPHI; not survey stations "
        "(needs MD, INC, AZI)"
    )


# ---------------------------------------------------------------------------- writer


@pytest.mark.parametrize(
    "name",
    ["gr.las", "time_log.las", "lasio/3.0/sample_3.0.las", "lasio/1.2/issue-264-dot-delimiter.las"],
)
def test_written_log_reads_back_in_lasio_and_gyropipe(tmp_path: Path, name: str) -> None:
    table, well, _ = read_log(DATA / name)
    path = tmp_path / "out.las"
    WRITER.write(table.drop_columns(SOURCE_LINE), path, well)
    assert_same_as_lasio(table, path)
    back, again, _ = read_log(path)
    assert_same_table(back.drop_columns(SOURCE_LINE), table.drop_columns(SOURCE_LINE))
    assert again.well == well.well


def test_written_curves_of_unlisted_units_read_back_exactly(tmp_path: Path) -> None:
    """Curves whose unit has no DECIMALS entry (gAPI, none) keep every bit, whatever the
    magnitude; a curve in m is written at its unit's decimals."""
    rng = np.random.default_rng(5)
    wide = rng.normal(0, 1e3, 200) * 10.0 ** rng.integers(-300, 300, 200)
    assert "gAPI" not in DECIMALS
    schema = pa.schema(
        [
            pa.field("DEPT", pa.float64(), metadata={UNIT_KEY: b"m"}),
            pa.field("GR", pa.float64(), metadata={UNIT_KEY: b"gAPI"}),
            pa.field("RATIO", pa.float64()),
        ]
    )
    depth = np.arange(200) * 0.1 + 1000.00004
    table = pa.table({"DEPT": depth, "GR": wide, "RATIO": wide[::-1]}, schema=schema)
    path = tmp_path / "wide.las"
    WRITER.write(table, path, WellMetadata())
    back, _, _ = read_log(path)
    for name in ("GR", "RATIO"):
        written = table.column(name).to_numpy().view(np.int64)
        assert np.array_equal(back.column(name).to_numpy().view(np.int64), written), name
    assert_exported(back, table, ["DEPT"])
    assert values(back, "DEPT")[:2] == [1000.0, 1000.1]


def test_written_log_keeps_repeated_mnemonics_and_descriptions(tmp_path: Path) -> None:
    table, well, _ = read_log(LASIO / "mnemonic_duplicate.las")
    path = tmp_path / "dup.las"
    WRITER.write(table, path, well)
    text = path.read_text()
    assert text.count(" SFLU    .OHMM") == 2 and "SFLU:1" not in text
    assert " : 5  RXO RESISTIVITY\n" in text
    back, _, _ = read_log(path)
    assert back.column_names == table.column_names


# ----------------------------------------------------------------------- convert (CLI)


def _csv_table(path: Path) -> tuple[pa.Table, list[str | None]]:
    """A CSV written by gyropipe: ``# `` comment lines, then a ``name[unit]`` header."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    header = lines[0].split(",")
    names = [re.sub(r"\[[^\]]*\]$", "", h) for h in header]
    units = [m[1] if (m := re.search(r"\[([^\]]*)\]$", h)) else None for h in header]
    table = pacsv.read_csv(
        io.BytesIO("\n".join(lines[1:]).encode()),
        pacsv.ReadOptions(column_names=names),
        convert_options=pacsv.ConvertOptions(strings_can_be_null=True),
    )
    return table, units


@pytest.mark.parametrize("suffix", ["parquet", "csv", "las"])
def test_convert_a_log(tmp_path: Path, suffix: str) -> None:
    source = DATA / "gr.las"
    out = tmp_path / f"gr.{suffix}"
    result = gyropipe_cli("convert", str(source), "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert result.stdout == (f"wrote {out}: well log, 5 rows × 4 columns (DEPT, GR, RHOB, NPHI)\n")
    original, _, _ = read_log(source)
    expected = original.drop_columns(SOURCE_LINE)
    units = [unit(original, n) for n in expected.column_names]
    if suffix == "parquet":
        assert_same_table(pq.read_table(out), expected)
    elif suffix == "csv":
        back, csv_units = _csv_table(out)
        assert csv_units == units
        for name in expected.column_names:
            np.testing.assert_array_equal(
                back.column(name).to_numpy(), expected.column(name).to_numpy()
            )
    else:
        back, well, _ = read_log(out)
        assert_same_table(back.drop_columns(SOURCE_LINE), expected)
        assert_same_as_lasio(back, out)
        assert well.well == "GR-7"


def test_convert_reads_the_log_back_from_parquet(tmp_path: Path) -> None:
    parquet = tmp_path / "gr.parquet"
    assert gyropipe_cli("convert", str(DATA / "gr.las"), "--out", str(parquet)).returncode == 0
    table, well, kind = read_kind(load_registry(), parquet, kind="auto", reader="auto", options={})
    assert kind == "log" and well.well == "GR-7"
    assert table.column_names == ["DEPT", "GR", "RHOB", "NPHI"]


def test_convert_a_log_as_a_survey_says_what_it_is(tmp_path: Path) -> None:
    result = gyropipe_cli(
        "convert",
        "tests/data/las/gr.las",
        "--out",
        str(tmp_path / "x.parquet"),
        "--kind",
        "stations",
    )
    assert result.returncode == 1
    assert result.stderr == (
        "error: tests/data/las/gr.las: a depth-indexed LAS log with curves GR, RHOB, NPHI; "
        "not survey stations (needs MD, INC, AZI) — use --kind log\n"
    )
    assert not (tmp_path / "x.parquet").exists()


def test_convert_prints_warnings_and_located_errors(tmp_path: Path) -> None:
    runon = gyropipe_cli(
        "convert", str(LASIO / "null_policy_runon.las"), "--out", str(tmp_path / "r.parquet")
    )
    assert runon.returncode == 0, runon.stderr
    assert "warning: " in runon.stderr and ":33: '7.020101130.188' holds 2 values" in runon.stderr
    wrong = gyropipe_cli(
        "convert", str(DATA / "wrong_count.las"), "--out", str(tmp_path / "w.parquet")
    )
    assert wrong.returncode == 1
    assert wrong.stderr == (
        f"error: {DATA / 'wrong_count.las'}:26: expected 4 values (one per curve: DEPT, GR, "
        "RHOB, NPHI), got 3\n"
    )


def test_convert_positional_output_and_its_errors(tmp_path: Path) -> None:
    out = tmp_path / "gr.parquet"
    assert gyropipe_cli("convert", str(DATA / "gr.las"), str(out)).returncode == 0 and out.exists()
    none = gyropipe_cli("convert", str(DATA / "gr.las"))
    assert none.returncode == 2 and "give --out OUTPUT" in none.stderr
    both = gyropipe_cli(
        "convert", str(DATA / "gr.las"), str(out), "--out", str(tmp_path / "other.csv")
    )
    assert both.returncode == 2 and "two outputs" in both.stderr


def test_auto_keeps_surveys_and_reports_a_broken_one(tmp_path: Path) -> None:
    survey = tmp_path / "survey.las"
    survey.write_text(
        "~Version\n VERS. 2.0 : v\n WRAP. NO : w\n~Well\n NULL. -999.25 : null\n"
        " NREF. grid : north\n~Curve\n DEPT.M : depth\n INCL.DEG : inc\n AZIM.DEG : azi\n"
        "~A\n0 0 0\n100 1.5 45\n200 3 x46.5\n"
    )
    registry = load_registry()
    with pytest.raises(InputFileError) as info:
        read_kind(registry, survey, kind="auto", reader="auto", options={})
    assert info.value.line == 14 and "expected a number, got 'x46.5'" in str(info.value)
    survey.write_text(survey.read_text().replace("x46.5", "46.5"))
    table, _, kind = read_kind(registry, survey, kind="auto", reader="auto", options={})
    assert kind == "stations" and table.column_names[:3] == ["md", "inc", "azi"]


# ------------------------------------------------------------------------------ fuzz

_mutation = byte_mutations(1000, b" \t\r\n#~.:-+eE0123456789,\"'", lines=True)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(mutations=st.lists(_mutation, min_size=1, max_size=3))
def test_fuzz_mutations_raise_located_errors_or_read_a_log(
    fuzz_dir: Path, mutations: list[tuple[str, int, int]]
) -> None:
    """A broken log is an :class:`InputFileError` (never another exception); one that
    reads is a table whose columns are its curves, each float64 or text."""
    path = fuzz_dir / "log.las"
    path.write_bytes(mutate_bytes((DATA / "gr.las").read_bytes(), mutations))
    try:
        table, _, _ = read_log(path)
    except InputFileError:
        return
    assert table.column_names[-1] == SOURCE_LINE
    for f in table.schema:
        assert f.type in (pa.float64(), pa.string(), pa.int64()), f
    LogTable.validate_table(table)


def test_index_steps_past_the_float_range_warn_located_without_an_overflow(tmp_path: Path):
    """Fuzz finding: an index from -1e308 to 1e308 steps by more than the float range; NumPy
    printed 'overflow encountered in subtract' (reader and writer) beside the STEP warning.
    The step is now reported at its line and the copy is written irregular (STEP 0)."""
    src = tmp_path / "far.las"
    src.write_text(
        "~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.M -1e308 :\n STOP.M 1e308 :\n"
        " STEP.M 1e308 :\n NULL. -999.25 :\n WELL. A-12 :\n~Curve\n DEPT.M : depth\n"
        " GR.GAPI : gamma\n~A\n-1e308 45\n1e308 50\n"
    )
    out = tmp_path / "far-copy.las"
    result = gyropipe_cli("convert", str(src), str(out), "--kind", "log")
    assert result.returncode == 0, result.stderr
    assert result.stderr.splitlines() == [
        f"warning: {src}:15: STEP is 1e+308 but the index steps by more than the float range "
        "from line 14 to this line: a row may be missing or repeated (STEP 0 means irregular "
        "steps); the data are kept"
    ]
    assert re.search(r"^ STEP +\.M +0 +:", out.read_text(), re.M)
    table, _, _ = read_log(out)
    assert values(table, "DEPT") == [-1e308, 1e308]

"""Hostile uncertainty statements in a stations file, as hand edits and foreign stores make
them: a tie-on record holding NaN, an infinite MD, a negative size or a basis its fields
contradict; a statement (``# tie_on=``, ``# confidence=``, a WITSML extension value) given
twice with different values; covariances of no covariance matrix (cov_ne² > cov_nn·cov_ee),
or a station's covariance with one entry emptied (a -999.25 null, a missing element); 1σ
ellipses unlike the covariances beside them; a Parquet table's tie-on record that is no
JSON, a variance in a length unit, no rows; infinite covariances read by ``gp.read``.
Each is refused at its file and line, or warned of and not carried — never a NumPy warning,
a pydantic traceback, or a covariance no matrix has in a deliverable. Inputs are written
here; expected values are their own text."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import pipeline as gp
from pipeline.errors import InputFileError, InputFileWarning
from tests_support import ROOT, gyropipe_cli

SURVEY = ROOT / "pipelines" / "survey.yaml"
COV = ("cov_nn", "cov_ne", "cov_nv", "cov_ee", "cov_ev", "cov_vv")
TIE = '{"surveys":[{"md": 500.0, "basis": "not included"}]}'
ROWS = (
    "500,10,30,0.01,0.001,0.0005,0.02,0.0002,0.004",
    "600,12,32,0.04,0.004,0.002,0.08,0.0008,0.016",
    "700,14,34,0.09,0.009,0.0045,0.18,0.0018,0.036",
)
"""Stations of a survey tied on at 500 m MD, each with its NEV covariance (m²)."""


def listing(tmp_path: Path, tie: str = TIE, rows: tuple[str, ...] = ROWS, extra: str = "") -> Path:
    """A stations listing as gyropipe writes one, ``extra`` lines after its statements."""
    path = tmp_path / "listing.csv"
    head = f"# confidence=0.95\n# error_model=TEST-GYRO rev 2\n# tie_on={tie}\n{extra}"
    head += "north_reference: true\n"
    header = "md[m],inc[deg],azi[deg]," + ",".join(f"{c}[m2]" for c in COV)
    path.write_text(head + header + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize(
    ("tie", "said"),
    [
        ('{"surveys":[{"md": NaN, "basis": "not included"}]}', r"surveys\.0\.md: .*finite"),
        ('{"surveys":[{"md": 1e400, "basis": "not included"}]}', r"surveys\.0\.md: .*finite"),
        (
            '{"surveys":[{"md": 500.0, "basis": "given", "semi_major": NaN}]}',
            r"surveys\.0\.semi_major: .*finite",
        ),
        (
            '{"surveys":[{"md": 500.0, "basis": "given", "semi_major": -3}]}',
            r"surveys\.0\.semi_major: .*greater than or equal to 0",
        ),
        (
            '{"surveys":[{"md": 500.0, "basis": "survey"}]}',
            r"surveys\.0: .*basis 'survey' with parent None",
        ),
        (
            '{"surveys":[{"md": 500.0, "basis": "wellhead"}]}',
            r"surveys\.0: .*basis 'wellhead' at MD 500.00 m",
        ),
    ],
)
def test_a_tie_on_line_no_writer_makes_is_refused_at_its_line(
    tmp_path: Path, tie: str, said: str
) -> None:
    """Before, NaN and 1e400 failed the run in the trajectory stage with a pydantic
    traceback; a NaN or negative size reached the report as 'nan m'; a deep 'wellhead'
    tie-on hid that the tie-on's uncertainty is not included."""
    with pytest.raises(InputFileError, match=r"listing\.csv:3: tie_on " + said):
        gp.read(listing(tmp_path, tie))


@pytest.mark.parametrize(
    ("extra", "name"),
    [
        ('# tie_on={"surveys":[{"md": 500.0, "basis": "given", "semi_major": 0.5}]}\n', "tie_on"),
        ("# confidence=0.5\n", "confidence"),
        ("# error_model=OTHER rev 9\n", "error_model"),
    ],
)
def test_a_statement_given_twice_with_different_values_is_refused(
    tmp_path: Path, extra: str, name: str
) -> None:
    """Before, the first line won and the other was dropped without a word."""
    with pytest.raises(InputFileError, match=rf"listing\.csv:4: {name} is given twice") as err:
        gp.read(listing(tmp_path, extra=extra))
    assert "also on line" in str(err.value)


def test_a_statement_repeated_as_it_is_is_one(tmp_path: Path) -> None:
    frame = gp.read(listing(tmp_path, extra=f"# tie_on={TIE}\n"))
    assert [t["basis"] for t in frame.attrs["uncertainty"]["tie_on"]] == ["not included"]


@pytest.mark.parametrize(
    ("old", "new", "said"),
    [
        (  # cov_ne² = 0.25 > cov_nn·cov_ee = 0.0032
            "600,12,32,0.04,0.004,",
            "600,12,32,0.04,0.5,",
            r"at MD 600.00 m the covariances are no covariance matrix: its smallest "
            r"eigenvalue is -0.44 m²",
        ),
        (  # cov_nv² = 0.81 > cov_nn·cov_vv
            "600,12,32,0.04,0.004,0.002,",
            "600,12,32,0.04,0.004,0.9,",
            r"at MD 600.00 m the covariances are no covariance matrix",
        ),
        (
            "600,12,32,0.04,",
            "600,12,32,,",
            r"at MD 600.00 m cov_nn null where the other covariance columns are not",
        ),
        (
            "600,12,32,0.04,0.004,",
            "600,12,32,0.04,-999.25,",
            r"at MD 600.00 m cov_ne null where the other covariance columns are not",
        ),
    ],
)
def test_covariances_of_no_covariance_matrix_are_not_carried(
    tmp_path: Path, old: str, new: str, said: str
) -> None:
    """Before, each was carried into every deliverable: the summary's largest ellipse was
    the impossible matrix's (0.75 m at 600 m, where the listing's is 0.28 m)."""
    rows = tuple(r.replace(old, new) for r in ROWS)
    assert rows != ROWS
    out = tmp_path / "out"
    with pytest.warns(InputFileWarning) as caught:
        gp.run(SURVEY, listing(tmp_path, rows=rows), out=out)
    refused = [str(w.message) for w in caught if "not carried" in str(w.message)]
    assert len(refused) == 1 and "listing.csv" in refused[0], refused
    assert re.search(said, refused[0]), refused[0]
    assert json.loads((out / "summary.json").read_text()).get("uncertainty") is None
    for name in ("trajectory.csv", "trajectory.xml"):
        assert not [c for c in COV if c in gp.read(out / name).columns], name


def test_a_station_without_covariance_among_others_is_carried_as_none(tmp_path: Path) -> None:
    """A whole row null is a station with no σ (outside its error model's range), not a
    broken statement: the others are carried, it stays null."""
    rows = (ROWS[0], "600,12,32,,,,,,", ROWS[2])
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        got = gp.run(SURVEY, listing(tmp_path, rows=rows)).tables["trajectory.trajectory"]
    assert got.column("cov_nn").to_pylist()[0::2] == [0.01, 0.09]
    assert got.column("cov_nn")[1].as_py() is None


@pytest.fixture(scope="module")
def witsml(tmp_path_factory: pytest.TempPathFactory) -> str:
    """The WITSML 1.4.1.1 trajectory the survey pipeline writes of the listing."""
    root = tmp_path_factory.mktemp("hostile-witsml")
    gp.run(SURVEY, listing(root), out=root / "out")
    return (root / "out" / "trajectory.xml").read_text()


def tie_extension(text: str) -> str:
    start = text.index('<extensionNameValue uid="uncertainty_tie_on">')
    return text[start : text.index("</extensionNameValue>", start) + len("</extensionNameValue>")]


def line_of(text: str, needle: str, nth: int = 1) -> int:
    at = -1
    for _ in range(nth):
        at = text.index(needle, at + 1)
    return text.count("\n", 0, at) + 1


def test_a_tie_on_extension_given_twice_with_different_values_is_refused(
    witsml: str, tmp_path: Path
) -> None:
    """Before, two values in a trajectory left it with no tie-on record, silently (the
    deliverables then never said the tie-on's uncertainty is not included)."""
    ext = tie_extension(witsml)
    other = ext.replace('"basis":"not included"', '"basis":"given"')
    path = tmp_path / "in.xml"
    path.write_text(witsml.replace(ext, ext + "\n" + other))
    second = line_of(path.read_text(), "<value>{", 2)
    with pytest.raises(InputFileError, match=rf"in\.xml:{second}: extension "):
        gp.read(path)
    path.write_text(witsml.replace(ext, ext + "\n" + ext))  # the same twice: one statement
    assert [t["basis"] for t in gp.read(path).attrs["uncertainty"]["tie_on"]] == ["not included"]


def test_an_error_model_extension_given_twice_with_different_values_is_refused(
    witsml: str, tmp_path: Path
) -> None:
    """Before, 'OTHER rev 1, TEST-GYRO rev 2' was stated as the columns' one error model."""
    first = '<extensionNameValue uid="error_model">'
    other = (
        '<extensionNameValue uid="em"><name>gyropipe.error_model</name>'
        "<value>OTHER rev 1</value></extensionNameValue>\n"
    )
    path = tmp_path / "in.xml"
    path.write_text(witsml.replace(first, other + first))
    second = line_of(path.read_text(), "<value>TEST-GYRO rev 2</value>")
    with pytest.raises(InputFileError, match=rf"in\.xml:{second}: extension gyropipe.error_mo"):
        gp.read(path)


def test_a_tie_on_extension_of_a_nan_md_is_refused_at_its_line(witsml: str, tmp_path: Path) -> None:
    """Before, it failed the run in the trajectory stage with a pydantic traceback."""
    ext = tie_extension(witsml)
    path = tmp_path / "in.xml"
    path.write_text(witsml.replace(ext, ext.replace('"md":500.0', '"md":NaN')))
    line = line_of(path.read_text(), '"md":NaN')
    result = gyropipe_cli("run", SURVEY, "--input", path, "--out", tmp_path / "out")
    assert result.returncode != 0
    assert f"in.xml:{line}: tie_on md: Input should be a finite number" in result.stderr
    assert "Traceback" not in result.output


def test_a_witsml_matrix_cov_of_no_covariance_is_not_carried(witsml: str, tmp_path: Path) -> None:
    path = tmp_path / "in.xml"
    path.write_text(witsml.replace('<varianceNE uom="m2">0.004<', '<varianceNE uom="m2">0.5<', 1))
    with pytest.warns(InputFileWarning, match=r"in\.xml.*not carried.*no covariance matrix"):
        gp.run(SURVEY, path, out=tmp_path / "out")
    assert json.loads((tmp_path / "out" / "summary.json").read_text()).get("uncertainty") is None


def parquet_listing(
    tmp_path: Path,
    tie: bytes | None,
    nn: list[float] | None = None,
    nv_unit: bytes = b"m2",
    rows: int = len(ROWS),
) -> Path:
    """The listing's first ``rows`` stations as a Parquet table whose metadata holds ``tie``
    as its tie-on record, ``nn`` its north variances, ``nv_unit`` the unit of cov_nv."""
    table = gp.read_table(listing(tmp_path)).slice(0, rows)
    if nn is not None:
        i = table.schema.get_field_index("cov_nn")
        table = table.set_column(i, table.schema.field(i), pa.array(nn, pa.float64()))
    i = table.schema.get_field_index("cov_nv")
    field = table.schema.field(i)
    table = table.set_column(i, field.with_metadata({**field.metadata, b"unit": nv_unit}), table[i])
    meta = dict(table.schema.metadata or {})
    if tie is not None:
        meta[b"gyropipe.uncertainty_tie_on"] = tie
    path = tmp_path / "in.parquet"
    pq.write_table(table.replace_schema_metadata(meta), path)
    return path


@pytest.mark.parametrize(
    ("tie", "said"),
    [
        (b'{"surveys": [{', r"tie_on the value: Invalid JSON"),
        (b"[1, 2]", r"tie_on the value: Input should be an object"),
        (b'{"surveys":[{"md":NaN,"basis":"not included"}]}', r"tie_on surveys.0.md: .*finite"),
    ],
)
def test_a_parquet_tie_on_record_no_writer_makes_is_refused(
    tmp_path: Path, tie: bytes, said: str
) -> None:
    """Before, the survey pipeline failed in its trajectory stage with a pydantic
    ValidationError naming no file."""
    path = parquet_listing(tmp_path, tie)
    result = gyropipe_cli("run", SURVEY, "--input", path, "--out", tmp_path / "out")
    assert result.returncode != 0
    assert re.search(r"in\.parquet: " + said, result.stderr), result.stderr
    assert "ValidationError" not in result.output


def test_infinite_covariances_read_without_a_numpy_warning(tmp_path: Path) -> None:
    """Before, ``gp.read`` let NumPy's 'invalid value encountered in subtract' out."""
    path = parquet_listing(tmp_path, TIE.encode(), nn=[float("inf"), 0.04, 0.09])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frame = gp.read(path)
    assert frame.attrs["uncertainty"]["at_td"]["md"] == 700.0
    assert frame.attrs["uncertainty"]["stations_without_sigma"] == 1


def test_a_parquet_covariance_in_a_length_unit_is_refused_by_its_column(tmp_path: Path) -> None:
    """Before, the table was read, and ``gyropipe convert`` wrote a CSV column cov_nv[FT]
    that no reader reads back (a variance in a length unit)."""
    path = parquet_listing(tmp_path, TIE.encode(), nv_unit=b"FT")
    with pytest.raises(InputFileError, match=r"in\.parquet \(column 'cov_nv'\): unit 'FT': "):
        gp.read(path)


def test_stations_without_rows_with_a_tie_on_record_integrate(tmp_path: Path) -> None:
    """A table of no stations keeping its covariance columns and tie-on record (a filter
    that kept none): before, minimum curvature died of an IndexError."""
    path = parquet_listing(tmp_path, TIE.encode(), rows=0)
    got = gp.minimum_curvature(gp.read_table(path))
    assert got.num_rows == 0


def with_ellipses(
    rows: tuple[str, ...],
    edit: dict[int, tuple[float, float]] | None = None,
    turn: dict[int, float] | None = None,
) -> tuple[str, ...]:
    """``rows`` with each station's 1σ ellipse (major, minor, azimuth, σ_V) of its covariance
    (the eigen-decomposition of its horizontal block, computed here, 4 decimals as the
    writers write m), ``edit`` replacing a row's (major, minor), ``turn`` adding degrees to
    a row's azimuth."""
    out = []
    for k, row in enumerate(rows):
        nn, ne, _, ee, _, vv = (float(v) for v in row.split(",")[3:])
        values, vectors = np.linalg.eigh(np.array([[nn, ne], [ne, ee]]))
        major, minor = np.sqrt(values[1]), np.sqrt(values[0])
        azimuth = np.degrees(np.arctan2(vectors[1, 1], vectors[0, 1])) % 180.0
        major, minor = (edit or {}).get(k, (major, minor))
        azimuth = (azimuth + (turn or {}).get(k, 0.0)) % 180.0
        out.append(f"{row},{major:.4f},{minor:.4f},{azimuth:.6f},{np.sqrt(vv):.4f}")
    return tuple(out)


def ellipse_listing(tmp_path: Path, rows: tuple[str, ...]) -> Path:
    path = listing(tmp_path, rows=rows)
    names = ("ellipse_major[m]", "ellipse_minor[m]", "ellipse_azimuth[deg]", "sigma_v[m]")
    text = path.read_text().replace("cov_vv[m2]\n", "cov_vv[m2]," + ",".join(names) + "\n")
    path.write_text(text)
    return path


def test_ellipses_beside_their_covariances_are_carried(tmp_path: Path) -> None:
    """A listing stating both, as gyropipe writes them (rounded): both carried."""
    rows = with_ellipses(ROWS)
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        got = gp.run(SURVEY, ellipse_listing(tmp_path, rows)).tables["trajectory.trajectory"]
    assert [float(r.split(",")[9]) for r in rows] == got.column("ellipse_major").to_pylist()


@pytest.mark.parametrize(
    ("edit", "turn", "said"),
    [
        ({1: (0.1, 0.05)}, {}, r"at MD 600.00 m ellipse_major is 0.1000 m, the covariances' 0.28"),
        ({2: (0.3, 0.5)}, {}, r"at MD 700.00 m ellipse_minor 0.5 m exceeds ellipse_major 0.3 m"),
        ({}, {1: 1.5}, r"at MD 600.00 m ellipse_azimuth is \d+\.\d\d°, the covariances' "),
    ],
)
def test_ellipses_unlike_their_covariances_are_not_carried(
    tmp_path: Path, edit: dict[int, tuple[float, float]], turn: dict[int, float], said: str
) -> None:
    """Before, both were carried and the summary's largest ellipse was the edited
    ellipse_major's, whatever the covariances beside it said; an ellipse azimuth turned
    1.5° from its covariances' (a convergence applied to one of them) was carried too."""
    out = tmp_path / "out"
    rows = with_ellipses(ROWS, edit, turn)
    with pytest.warns(InputFileWarning) as caught:
        gp.run(SURVEY, ellipse_listing(tmp_path, rows), out=out)
    refused = [str(w.message) for w in caught if "not carried" in str(w.message)]
    assert len(refused) == 1 and re.search(said, refused[0]), refused
    assert json.loads((out / "summary.json").read_text()).get("uncertainty") is None


K2 = float(np.sqrt(-2.0 * np.log(1.0 - 0.95)))
"""the 95 % ellipse's scale of its 1σ axes: P(χ²₂ ≤ k²) = 0.95, k = √(−2 ln 0.05) ≈ 2.4477"""
K1 = 1.959963984540054
"""the two-sided 95 % normal quantile, the vertical interval's scale"""


def conf_listing(tmp_path: Path, ellipse_k: float) -> Path:
    """The ellipse listing with the axes at the stated 95 % confidence beside them: the 1σ
    semi-axes times ``ellipse_k``, σ_V times :data:`K1`, 4 decimals."""
    rows = []
    for row in with_ellipses(ROWS):
        major, minor, _, sigma_v = (float(v) for v in row.split(",")[9:])
        rows.append(f"{row},{ellipse_k * major:.4f},{ellipse_k * minor:.4f},{K1 * sigma_v:.4f}")
    path = ellipse_listing(tmp_path, tuple(rows))
    names = "ellipse_major_conf[m],ellipse_minor_conf[m],vertical_conf[m]"
    path.write_text(path.read_text().replace("sigma_v[m]\n", f"sigma_v[m],{names}\n"))
    return path


def test_axes_at_the_stated_confidence_are_carried(tmp_path: Path) -> None:
    """Axes scaled by the 2-D factor of the stated 95 %: carried with the rest."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", InputFileWarning)
        run = gp.run(SURVEY, conf_listing(tmp_path, K2))
    got = run.tables["trajectory.trajectory"]
    assert "ellipse_major_conf" in got.column_names and "vertical_conf" in got.column_names


def test_an_ellipse_scaled_by_the_1d_factor_is_not_carried(tmp_path: Path) -> None:
    """A 95 % ellipse made with 1.96 (the 1-D quantile) is a 85 % one: a file stating 95 %
    beside it states two confidences, and before it was carried as 95 %."""
    out = tmp_path / "out"
    with pytest.warns(InputFileWarning) as caught:
        gp.run(SURVEY, conf_listing(tmp_path, K1), out=out)
    refused = [str(w.message) for w in caught if "not carried" in str(w.message)]
    said = (
        r"at MD 500\.00 m ellipse_major_conf is \d\.\d{4} m, not the 1σ \d\.\d{4} m at the "
        r"95 % confidence the file states \(2\.4477 × 1σ"
    )
    assert len(refused) == 1 and re.search(said, refused[0]), refused
    assert json.loads((out / "summary.json").read_text()).get("uncertainty") is None

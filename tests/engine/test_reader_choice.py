"""Reader choice belongs to the engine (``Registry.reader_for``/``read``): the surest claim
wins, a third-party reader wins a tie with a built-in, a tie left is an error naming the
candidates, a failing third-party reader is named, and reader options are checked when a
pipeline is validated, each problem at its YAML location."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import pyarrow as pa
import pytest
from pydantic import BaseModel, ConfigDict

from pipeline.errors import ReaderChoiceError, ReaderError, ReaderOptionsError
from pipeline.plugins import load_registry
from pipeline.registry import Claim, PluginInfo, ReaderDef, Registry
from pipeline.tables import Stations
from pipeline.well import DefaultNorthReference, WellMetadata
from tests_support import gyropipe_cli

STATIONS = "MD[m],INC[deg],AZI[deg]\n0,0,0\n30,2,40\n"


class VendorOptions(BaseModel):
    model_config = ConfigDict(extra="forbid")
    default_north_reference: DefaultNorthReference = None
    skip: int = 0


def vendor_reader(name: str, claim: Claim | bool, fail: Exception | None = None) -> ReaderDef:
    """A stations reader that claims every file with ``claim`` and returns two stations
    (or raises ``fail``); the options it received are kept in the table's metadata."""

    def read(path: Path, kind: str, options: Any) -> tuple[pa.Table, WellMetadata]:
        if fail is not None:
            raise fail
        table = Stations.compiled().make_table(
            {"md": [0.0, 10.0], "inc": [0.0, 1.0], "azi": [0.0, 2.0]},
            north_reference=options.default_north_reference or "true",
        )
        return table, WellMetadata(well=name)

    return ReaderDef(
        name=name,
        description="test reader",
        kinds={"stations": Stations},
        read=read,
        sniff=lambda path: claim,
        options=VendorOptions,
    )


def with_plugin(*readers: ReaderDef, builtin: bool = False) -> Registry:
    """The real registry plus ``readers``, registered as one plugin would register them."""
    registry = load_registry()
    info = PluginInfo("vendor", "2.1", builtin=builtin)
    registry.plugins[info.name] = info
    for reader in readers:
        registry.add(reader, info, ReaderDef)
    assert not registry.problems
    return registry


@pytest.fixture
def csv_file(tmp_path: Path) -> Path:
    path = tmp_path / "s.csv"
    path.write_text(STATIONS)
    return path


def test_content_beats_name(tmp_path: Path) -> None:
    """The built-in CSV reader claims a .txt by its name only; a reader that recognises the
    content wins even when it is a built-in; a .txt with a stations header is the CSV
    reader's by content."""
    other = tmp_path / "other.txt"
    other.write_text("VENDOR FORMAT 3\n1 2 3\n")
    registry = with_plugin(vendor_reader("zeta", Claim.CONTENT), builtin=True)
    assert registry.readers["csv"][0].claim(other) is Claim.NAME
    assert registry.reader_for(other, "stations").name == "zeta"
    plain = load_registry()
    ours = tmp_path / "ours.txt"
    ours.write_text(STATIONS)
    assert plain.readers["csv"][0].claim(ours) is Claim.CONTENT
    assert plain.reader_for(ours, "stations").name == "csv"


def test_third_party_wins_a_tie_with_a_builtin(csv_file: Path) -> None:
    registry = with_plugin(vendor_reader("vendor_csv", Claim.CONTENT))
    assert registry.readers["csv"][0].claim(csv_file) is Claim.CONTENT
    assert registry.reader_for(csv_file, "stations").name == "vendor_csv"
    table, well = registry.read(csv_file, "stations")
    assert well.well == "vendor_csv" and table.num_rows == 2


def test_a_tie_left_is_an_error_naming_the_candidates(csv_file: Path) -> None:
    registry = with_plugin(vendor_reader("alpha", True), vendor_reader("beta", Claim.CONTENT))
    with pytest.raises(ReaderChoiceError) as info:
        registry.reader_for(csv_file, "stations")
    text = str(info.value)
    assert "several readers claim" in text and "by its content" in text
    assert "alpha (vendor 2.1), beta (vendor 2.1)" in text
    assert "choose one with `reader:`" in text
    assert registry.reader_for(csv_file, "stations", "beta").name == "beta"


def test_a_builtin_tie_is_an_error_too(csv_file: Path) -> None:
    registry = with_plugin(vendor_reader("zeta", Claim.CONTENT), builtin=True)
    with pytest.raises(ReaderChoiceError, match=r"csv \(builtin.csv .*\), zeta \(vendor 2.1\)"):
        registry.reader_for(csv_file, "stations")


def test_a_sniff_that_raises_claims_nothing(csv_file: Path) -> None:
    def broken(path: Path) -> bool:
        raise RuntimeError("bug")

    reader = vendor_reader("broken", True)
    registry = with_plugin(ReaderDef(**{**reader.__dict__, "sniff": broken}))
    assert registry.readers["broken"][0].claim(csv_file) is Claim.NO
    assert registry.reader_for(csv_file, "stations").name == "csv"


def test_no_reader_names_the_readers_of_the_kind(tmp_path: Path) -> None:
    path = tmp_path / "x.bin"
    path.write_bytes(bytes(range(256)))
    with pytest.raises(ReaderChoiceError) as info:
        load_registry().reader_for(path, "stations")
    assert "no installed reader recognises" in str(info.value)
    assert "csv" in str(info.value) and "las" in str(info.value)


def test_a_failing_third_party_reader_is_named(csv_file: Path) -> None:
    registry = with_plugin(vendor_reader("vendor_csv", Claim.CONTENT, fail=KeyError("DEPTH")))
    with pytest.raises(ReaderError) as info:
        registry.read(csv_file, "stations")
    assert str(info.value) == "reader 'vendor_csv' (plugin vendor 2.1) failed: KeyError: 'DEPTH'"


def test_options_marked_as_well_defaults_come_from_the_well(csv_file: Path) -> None:
    registry = with_plugin(vendor_reader("vendor_csv", Claim.CONTENT))
    grid = WellMetadata(north_reference="grid")
    table, _ = registry.read(csv_file, "stations", well=grid)
    assert table.schema.field("azi").metadata[b"north_reference"] == b"grid"
    table, _ = registry.read(
        csv_file, "stations", options={"default_north_reference": "magnetic"}, well=grid
    )
    assert table.schema.field("azi").metadata[b"north_reference"] == b"magnetic"
    with pytest.raises(ReaderOptionsError, match="options of reader 'vendor_csv': skip: "):
        registry.read(csv_file, "stations", options={"skip": "many"})


PIPELINE = """\
name: opts
version: "1"
inputs:
  stations: {{}}
stages:
  - id: read
    uses: read_stations
    with:
      input: stations
      reader: {reader}
      options:
        {options}
"""


@pytest.mark.parametrize(
    ("reader", "options", "expected"),
    [
        ("csv", "delimter: ';'", "12:9: unknown field 'options.delimter'"),
        ("las", "null_values: many", "12:22: options.null_values: Input should be a valid list"),
        ("auto", "skip_rowz: 3", "12:9: unknown field 'options.skip_rowz'"),
    ],
)
def test_validate_locates_a_wrong_reader_option(
    tmp_path: Path, reader: str, options: str, expected: str
) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(PIPELINE.format(reader=reader, options=options))
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 2, result.stdout + result.stderr
    where, message = expected.split(": ", 1)
    assert f"{path}:{where}: stage 'read' (read_stations): {message}" in result.stderr
    assert "Traceback" not in result.stderr


def test_validate_accepts_options_some_reader_of_the_kind_takes(tmp_path: Path) -> None:
    path = tmp_path / "p.yaml"
    path.write_text(PIPELINE.format(reader="auto", options="delimiter: ';'"))
    result = gyropipe_cli("validate", str(path))
    assert result.returncode == 0, result.stderr


def test_plugins_lists_what_each_reader_claims() -> None:
    result = gyropipe_cli("plugins")
    lines = result.stdout.splitlines()
    assert any(
        line.startswith("  csv (builtin.csv ") and "by name, a .csv/.txt/.tsv file" in line
        for line in lines
    ), textwrap.indent(result.stdout, "  ")

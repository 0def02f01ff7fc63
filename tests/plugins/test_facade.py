"""``pipeline.plugin``, the plugin authors' API, and what is written against it: the sample
plugin ``plugins/gyropipe-acme``, the vendor guide ``docs/vendor-adapter.md``, the README's
plugin example and the facade's own docstring example.

- every ``pipeline…`` import of these is ``pipeline`` or ``pipeline.plugin``;
- every name the facade exports is the very object of its home module;
- the guide's code blocks, read in order, are one plugin module that runs: no name in them
  is undefined, its readers and writer register, simulated samples round-trip through them,
  and the engine chooses its survey-report reader and fills its well-default option.
"""

from __future__ import annotations

import ast
import builtins
import dis
import importlib
import importlib.util
import inspect
import re
import textwrap
import types
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pytest
from pydantic import ValidationError

import pipeline.plugin
import pipeline.tables
from pipeline.contracts import TableContract
from pipeline.errors import ReaderChoiceError, ReaderError
from pipeline.plugins import load_registry
from pipeline.registry import CheckDef, PluginInfo, ReaderDef, Registry, StageDef, WriterDef
from pipeline.reporting import ReportDef
from pipeline.sim.simulate import simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.well import WellMetadata
from tests_support import ROOT

ALLOWED = {"pipeline", "pipeline.plugin"}
ACME_SRC = ROOT / "plugins" / "gyropipe-acme" / "src"
GUIDE = ROOT / "docs" / "vendor-adapter.md"

HOME = {
    "hookimpl": "pipeline.hookspecs",
    "TableStream": "pipeline.streams",
    "InputPath": "pipeline.inputfiles",
    **dict.fromkeys(
        [
            "StageDef",
            "ReaderDef",
            "WriterDef",
            "CheckDef",
            "ToolModelDef",
            "Claim",
            "NoParams",
            "pipeline_input",
            "registered",
            "StageContext",
        ],
        "pipeline.registry",
    ),
    **dict.fromkeys(["Provenance", "StageSetup"], "pipeline.provenance"),
    **dict.fromkeys(["ExecutorDef", "ExecutorSetup", "PipelineRef"], "pipeline.executing"),
    **dict.fromkeys(["WellTask", "WellOutcome", "run_well"], "pipeline.batch.worker"),
    **dict.fromkeys(
        [
            "ReportDef",
            "ReportContext",
            "ReportSection",
            "ReportTable",
            "ReportFigure",
            "ReportLine",
            "MethodNote",
        ],
        "pipeline.reporting",
    ),
    **dict.fromkeys(
        ["TableContract", "column", "SOURCE_LINE", "UNIT_KEY", "NORTH_KEY"], "pipeline.contracts"
    ),
    **dict.fromkeys(
        [
            "AnyTable",
            "Stations",
            "Trajectory",
            "CheckResults",
            "RawSamples",
            "PositionReadings",
            "FreeGyroReadings",
            "ErrorBudget",
            "CompassStations",
            "CompassRejects",
            "SimTruth",
            "LogTable",
            "AcceptanceGates",
        ],
        "pipeline.tables",
    ),
    **dict.fromkeys(
        [
            "WellMetadata",
            "Latitude",
            "NorthReference",
            "DefaultNorthReference",
            "attach",
            "well_of",
        ],
        "pipeline.well",
    ),
    **dict.fromkeys(["conversion_factor", "canonical_unit", "is_unit_of"], "pipeline.units"),
    **dict.fromkeys(["Conventions", "to_canonical"], "pipeline.io.conventions"),
    **dict.fromkeys(
        ["CURVES", "Curve", "canonical_name", "register_alias"], "pipeline.io.mnemonics"
    ),
    **dict.fromkeys(
        [
            "GyropipeError",
            "InputFileError",
            "UnitError",
            "ContractViolation",
            "MissingSiteError",
            "ReaderError",
            "ReaderChoiceError",
            "ReaderOptionsError",
        ],
        "pipeline.errors",
    ),
}
"""Every name of the facade → the module it comes from: the public surface, on purpose."""


# --- where code written against the facade is found ----------------------------------------


def python_blocks(markdown: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", markdown, flags=re.S)


def readme_plugin_section() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return text.split("## Writing a plugin", 1)[1].split("\n## ", 1)[0]


def docstring_example() -> str:
    """The reader plugin in :mod:`pipeline.plugin`'s docstring (the ``::`` block)."""
    doc = pipeline.plugin.__doc__ or ""
    block = doc.split("::\n", 1)[1].split("\nWhat is here:", 1)[0]
    return textwrap.dedent(block)


def guide_module_source() -> str:
    """The guide's python blocks, in order: one plugin module."""
    return "\n\n".join(python_blocks(GUIDE.read_text(encoding="utf-8")))


def sources() -> Iterator[tuple[str, str]]:
    """(where, source) of everything that must import gyropipe through the facade only."""
    for path in sorted(ACME_SRC.rglob("*.py")):
        yield str(path.relative_to(ROOT)), path.read_text(encoding="utf-8")
    for i, block in enumerate(python_blocks(GUIDE.read_text(encoding="utf-8")), 1):
        yield f"docs/vendor-adapter.md block {i}", block
    for i, block in enumerate(python_blocks(readme_plugin_section()), 1):
        yield f"README.md 'Writing a plugin' block {i}", block
    yield "pipeline.plugin docstring example", docstring_example()


def pipeline_imports(source: str) -> Iterator[tuple[int, str]]:
    """(line, module) of every import of the ``pipeline`` package, wherever it stands."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            # ``from pipeline import x`` imports module pipeline.x when there is one
            names = [node.module]
            if node.module == "pipeline":
                names = [
                    f"pipeline.{a.name}"
                    if importlib.util.find_spec(f"pipeline.{a.name}") is not None
                    else "pipeline"
                    for a in node.names
                ]
        else:
            continue
        for name in names:
            if name.partition(".")[0] == "pipeline":
                yield node.lineno, name


def test_sources_are_found() -> None:
    found = dict(sources())
    assert {"plugins/gyropipe-acme/src/gyropipe_acme/gyrolog.py"} <= set(found)
    assert sum(where.startswith("docs/") for where in found) >= 5
    assert sum(where.startswith("README") for where in found) == 1


@pytest.mark.parametrize(("where", "source"), list(sources()), ids=lambda v: str(v)[:60])
def test_imports_only_the_facade(where: str, source: str) -> None:
    bad = [f"line {line}: {name}" for line, name in pipeline_imports(source) if name not in ALLOWED]
    assert not bad, f"{where} imports gyropipe internals (use pipeline.plugin): {bad}"


def test_the_checker_sees_internal_imports() -> None:
    source = (
        "import pipeline\nfrom pipeline import plugin\nfrom pipeline.plugin import Claim\n"
        "def f():\n    from pipeline.registry import Claim\n    import pipeline.units\n"
        "from pipeline import tables\n"
    )
    assert {name for _, name in pipeline_imports(source) if name not in ALLOWED} == {
        "pipeline.registry",
        "pipeline.units",
        "pipeline.tables",
    }


# --- the facade itself ---------------------------------------------------------------------


def test_all_is_the_public_surface() -> None:
    exported = pipeline.plugin.__all__
    assert len(exported) == len(set(exported))
    assert set(exported) == set(HOME)


@pytest.mark.parametrize("name", sorted(HOME))
def test_each_name_is_its_home_modules_object(name: str) -> None:
    home = importlib.import_module(HOME[name])
    obj = getattr(pipeline.plugin, name)
    assert obj is getattr(home, name)
    if inspect.isclass(obj) or inspect.isfunction(obj):
        assert obj.__module__ == HOME[name]


def test_every_standard_contract_is_exported() -> None:
    standard = {
        name
        for name, obj in vars(pipeline.tables).items()
        if inspect.isclass(obj)
        and issubclass(obj, TableContract)
        and obj.__module__ == "pipeline.tables"
    }
    assert standard <= set(pipeline.plugin.__all__)


def test_star_import_gives_exactly_all() -> None:
    namespace: dict[str, Any] = {}
    exec("from pipeline.plugin import *", namespace)
    assert set(namespace) - {"__builtins__"} == set(pipeline.plugin.__all__)


# --- the examples run ----------------------------------------------------------------------


def undefined_names(source: str, namespace: dict[str, Any]) -> set[str]:
    """Global names some code of ``source`` loads that neither ``namespace`` (after running
    the module) nor the builtins define: the NameErrors waiting in function bodies."""
    known = set(namespace) | set(vars(builtins)) | {"__annotations__"}
    missing: set[str] = set()

    def visit(code: types.CodeType) -> None:
        stored = {
            i.argval
            for i in dis.get_instructions(code)
            if i.opname in ("STORE_NAME", "IMPORT_NAME")
        }
        for instruction in dis.get_instructions(code):
            if instruction.opname in ("LOAD_GLOBAL", "LOAD_NAME"):
                name = instruction.argval
                if name not in known and name not in stored:
                    missing.add(name)
        for const in code.co_consts:
            if isinstance(const, types.CodeType):
                visit(const)

    visit(compile(source, "<example>", "exec", dont_inherit=True))
    return missing


def run_module(source: str, name: str) -> types.ModuleType:
    """``source`` run as a fresh module (not added to ``sys.modules``)."""
    module = types.ModuleType(name)
    exec(compile(source, f"<{name}>", "exec", dont_inherit=True), module.__dict__)
    missing = undefined_names(source, module.__dict__)
    assert not missing, f"{name}: undefined names {sorted(missing)}"
    return module


def test_undefined_names_are_found() -> None:
    source = "import os\nX = 1\ndef f():\n    return os.sep, X, len, Y\n"
    assert undefined_names(source, {"os": None, "X": 1, "f": None}) == {"Y"}


def registrations(module: types.ModuleType) -> dict[str, list[Any]]:
    found: dict[str, list[Any]] = {}
    for hook in ("stages", "readers", "writers", "checks", "report_parts"):
        impl = getattr(module, f"gyropipe_register_{hook}", None)
        if impl is not None:
            impl(register=found.setdefault(hook, []).append)
    return found


def with_plugin(module: types.ModuleType, name: str) -> Registry:
    """The real registry plus ``module``'s registrations, as a third-party plugin's."""
    registry = load_registry()
    info = PluginInfo(name, "0.1", builtin=False)
    registry.plugins[name] = info
    kinds = {
        "stages": StageDef,
        "readers": ReaderDef,
        "writers": WriterDef,
        "checks": CheckDef,
        "report_parts": ReportDef,
    }
    for hook, items in registrations(module).items():
        for item in items:
            registry.add(item, info, kinds[hook])
    assert not registry.problems, registry.problems
    return registry


def test_readme_plugin_example_defines_every_name() -> None:
    (block,) = python_blocks(readme_plugin_section())
    module = run_module(block, "my_vendor_plugin")
    (stage,) = registrations(module)["stages"]
    assert stage.name == "my_vendor.deep_only"


def test_docstring_example_reads_through_the_engine(tmp_path: Path) -> None:
    module = run_module(docstring_example(), "foo_gyro_plugin")
    registry = with_plugin(module, "foo")
    path = tmp_path / "run.foo"
    path.write_text("FOO SURVEY\n0 0 0\n30 1.5 40\n")
    assert registry.reader_for(path, "stations").name == "foo"
    table, _ = registry.read(path, "stations")
    assert table.column("inc").to_pylist() == [0.0, 1.5]
    bad = tmp_path / "bad.foo"
    bad.write_text("FOO SURVEY\n0 0\n")
    with pytest.raises(ReaderError, match=rf"reader 'foo' \(plugin foo 0.1\).*{bad}:2: expected"):
        registry.read(bad, "stations")


@pytest.fixture(scope="module")
def guide() -> types.ModuleType:
    return run_module(guide_module_source(), "guide_acme_plugin")


def test_guide_registers_readers_and_a_writer(guide: types.ModuleType) -> None:
    found = registrations(guide)
    assert [r.name for r in found["readers"]] == ["acme", "acme_survey"]
    assert [w.name for w in found["writers"]] == ["acme"]
    assert found["readers"][0].what_it_claims().startswith("By content: the file starts")


def test_guide_report_section_counts_an_acme_runs_stations(guide: types.ModuleType) -> None:
    """The guide's report part: a section in the survey report of an Acme run only."""
    (part,) = registrations(guide)["report_parts"]
    trajectory = pa.table({"inc": [0.0, 3.0, 12.0, 45.0, 91.0]})
    acme = WellMetadata(tool_type="Acme GL-2", tool_serial="A-17")
    ctx = types.SimpleNamespace(document="survey", tables={"trajectory": trajectory}, well=acme)
    section = part.section(ctx)
    assert section.title == "Acme tool"
    assert section.paragraphs == ("Surveyed with Acme tool A-17.",)
    (table,) = section.tables
    assert table.columns == (("Inclination", "°"), ("Stations", ""))
    assert table.rows == (("0 – 5", "2"), ("5 – 30", "1"), ("30 – 180", "2"))
    assert part.section(types.SimpleNamespace(**{**vars(ctx), "document": "calibration"})) is None
    other = types.SimpleNamespace(**{**vars(ctx), "well": WellMetadata(tool_type="Other")})
    assert part.section(other) is None


SPEC = {
    "name": "guide",
    "seed": 3,
    "site": {
        "latitude": 61.25,
        "longitude": 73.4,
        "elevation": 120.0,
        "date": "2026-11-21",
        "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
    },
    "well": {"sections": [{"kind": "vertical", "length": 20}]},
    "tool": {"preset": "ideal"},
    "survey": {"mode": "point", "every": 20, "dwell": 1.0, "move_time": 1.0, "speed": 5.0},
}


def test_guide_round_trips_simulated_samples(guide: types.ModuleType, tmp_path: Path) -> None:
    samples = simulate(SimulationSpec.model_validate(SPEC)).samples
    well = WellMetadata(well="Guide-1", tool_serial="AG-7", latitude=61.25)
    registry = with_plugin(guide, "guide")
    path = tmp_path / "run.agl"
    registry.writers["acme"][0].write(samples, path, well)
    lines = path.read_text().splitlines()
    assert lines[:4] == ["ACME GYROLOG v2", "WELL=Guide-1", "SERIAL=AG-7", "LAT=61.25"]
    assert registry.reader_for(path, "samples").name == "acme"
    table, read_well = registry.read(path, "samples")
    assert read_well == well
    assert table.column("source_line").to_pylist()[0] == lines.index("DATA") + 2
    for name in samples.column_names:
        got = table.column(name).to_numpy(zero_copy_only=False)
        want = samples.column(name).to_numpy(zero_copy_only=False)
        assert table.schema.field(name).metadata == samples.schema.field(name).metadata, name
        if name in ("station", "position"):
            assert table.column(name).to_pylist() == samples.column(name).to_pylist(), name
        elif name == "frame_angle":
            np.testing.assert_allclose((got - want + 180.0) % 360.0 - 180.0, 0.0, atol=1e-12)
        else:
            np.testing.assert_allclose(got, want, rtol=1e-14, atol=0, err_msg=name)


REPORT = "ACME SURVEY REPORT\nWELL=Acme-2\n{north}MD(ft) INC(deg) AZI(deg)\n0 0 0\n100 2.5 47.5\n"


def test_guide_survey_report_wins_over_the_csv_reader_and_takes_the_wells_north(
    guide: types.ModuleType, tmp_path: Path
) -> None:
    registry = with_plugin(guide, "guide")
    path = tmp_path / "report.txt"
    path.write_text(REPORT.format(north=""))
    assert registry.readers["csv"][0].claim(path).name == "NAME"
    assert registry.reader_for(path, "stations").name == "acme_survey"
    table, well = registry.read(path, "stations", well=WellMetadata(north_reference="grid"))
    assert table.schema.field("azi").metadata[b"north_reference"] == b"grid"
    assert table.column("md").to_pylist() == [0.0, 30.48]
    assert well.well == "Acme-2"
    path.write_text(REPORT.format(north="NORTH=TRUE\n"))
    table, _ = registry.read(path, "stations", well=WellMetadata(north_reference="grid"))
    assert table.schema.field("azi").metadata[b"north_reference"] == b"true"
    path.write_text(REPORT.format(north="NORTH=TRUE\n").replace("100 2.5", "100 2.5x"))
    with pytest.raises(ReaderError, match=rf"{path}:6 \(column 'INC'\): '2.5x' is not a number"):
        registry.read(path, "stations")
    with pytest.raises(ValidationError, match="default_north"):
        registry.check_reader_options("stations", "acme_survey", {"default_north": "grid"})


def test_a_tie_left_asks_for_reader(guide: types.ModuleType, tmp_path: Path) -> None:
    """Two third-party readers equally sure: the user is told to choose with `reader:`."""
    registry = with_plugin(guide, "guide")
    twin = ReaderDef(
        name="twin",
        description="another reader of Acme files",
        kinds={"samples": pipeline.plugin.RawSamples},
        read=registry.readers["acme"][0].read,
        sniff=lambda path: pipeline.plugin.Claim.CONTENT,
    )
    registry.add(twin, registry.plugins["guide"], ReaderDef)
    path = tmp_path / "x.agl"
    path.write_text("ACME GYROLOG v2\n")
    with pytest.raises(ReaderChoiceError, match=r"choose one with `reader:`"):
        registry.reader_for(path, "samples")


def test_guide_table_is_canonical(guide: types.ModuleType, tmp_path: Path) -> None:
    """A hand-written file in Acme's units and axes reads as canonical units and axes."""
    path = tmp_path / "hand.agl"
    path.write_text(
        "ACME GYROLOG v2\nCHANNELS=T WX WY WZ AX AY AZ STN\nDATA\n"
        "0 0.001 0.002 0.003 0 0 1 -\n1 0.001 0.002 0.003 0 0 1 4\n"
    )
    table, _ = guide.read_samples(path, "samples", None)
    row = table.slice(0, 1).to_pylist()[0]
    assert row["gyro_x"] == pytest.approx(7.2)  # Acme y, deg/s → deg/h
    assert row["gyro_y"] == pytest.approx(3.6)
    assert row["gyro_z"] == pytest.approx(-10.8)  # Acme z up-hole
    assert row["acc_z"] == pytest.approx(9.80665)  # +1 g up-hole, specific force
    assert table.column("station").to_pylist() == [None, 4]
    assert isinstance(table, pa.Table)

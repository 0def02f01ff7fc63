"""Helpers importable by test modules (pytest puts tests/ on sys.path)."""

from __future__ import annotations

import contextlib
import importlib
import math
import os
import re
import shutil
import subprocess
import sys
import textwrap
import warnings
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from html.parser import HTMLParser
from pathlib import Path
from types import ModuleType, SimpleNamespace
from typing import Any

import numpy as np
import pyarrow as pa
import yaml
from click.testing import CliRunner
from hypothesis import strategies as st

from pipeline.cli import main
from pipeline.io.las.log import TEXT_NULL
from pipeline.plugins import forget_shared_registries
from pipeline.registry import ReaderDef, WriterDef
from pipeline.well import WellMetadata

ROOT = Path(__file__).resolve().parents[1]
TEXT_NULLS = re.compile(TEXT_NULL, re.IGNORECASE)


@dataclass(frozen=True)
class CliResult:
    """What a ``gyropipe`` command did: its exit status and what it wrote (the names of
    :class:`subprocess.CompletedProcess`)."""

    returncode: int
    stdout: str
    stderr: str
    output: str
    """stdout and stderr interleaved as a terminal shows them."""


def stage_context(well: WellMetadata, **attrs: Any) -> Any:
    """A stand-in StageContext of a run whose well is ``well`` (no overrides): a table's
    own header over it (``well_for``), ``attrs`` beside (``provenance``, ``update_well``;
    ``stage_id`` "stage" unless given)."""

    def well_for(header: WellMetadata | None) -> WellMetadata:
        return well if header is None else well.merged(header)

    return SimpleNamespace(well=well, well_for=well_for, **{"stage_id": "stage", **attrs})


def gyropipe_cli(
    *args: str | Path,
    env: Mapping[str, str] | None = None,
    cwd: Path = ROOT,
    site: Path | None = None,
    check: bool = False,
) -> CliResult:
    """``gyropipe ARGS`` in this process through click's ``CliRunner``, from ``cwd`` (the
    repository root: relative paths as a user types them) with ``env`` set for the command,
    stdin and stderr not terminals. ``site``: a directory of plugin modules and their
    dist-info entry points, importable for this command only (as on ``PYTHONPATH``).
    ``check``: the command must succeed (its stderr is the failure's message). A
    Python warning the command lets out is written to stderr, as a process does; an
    exception it lets out is raised here (a process would print a traceback)."""
    runner = CliRunner()
    with contextlib.chdir(cwd), _importable(site), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")  # and a plain interpreter's exceptions:
        for hidden in (
            DeprecationWarning,
            PendingDeprecationWarning,
            ImportWarning,
            ResourceWarning,
        ):
            warnings.simplefilter("ignore", hidden)
        result = runner.invoke(
            main,
            [str(a) for a in args],
            env=dict(env or {}),
            catch_exceptions=False,
            prog_name="gyropipe",
        )
    shown = "".join(
        warnings.formatwarning(w.message, w.category, w.filename, w.lineno) for w in caught
    )
    done = CliResult(result.exit_code, result.stdout, shown + result.stderr, result.output + shown)
    assert not check or done.returncode == 0, done.stderr
    return done


@contextlib.contextmanager
def _importable(site: Path | None) -> Iterator[None]:
    """``site`` first on ``sys.path`` for the block; the modules imported from it, and the
    registries the process loaded with them, are forgotten afterwards (the next command
    imports its own plugins afresh)."""
    if site is None:
        yield
        return
    sys.path.insert(0, str(site))
    importlib.invalidate_caches()
    forget_shared_registries()
    try:
        yield
    finally:
        sys.path.remove(str(site))
        for name, module in list(sys.modules.items()):
            if str(getattr(module, "__file__", None) or "").startswith(str(site)):
                del sys.modules[name]
        importlib.invalidate_caches()
        forget_shared_registries()


def gyropipe() -> list[str]:
    """Command line that runs the installed ``gyropipe`` console script."""
    exe = Path(sys.executable).parent / "gyropipe"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("gyropipe")
    assert found, "the gyropipe console script is not installed"
    return [found]


def pythonpath(*dirs: Path) -> dict[str, str]:
    """``os.environ`` with ``dirs`` first on ``PYTHONPATH`` and what was there kept after
    them (a worktree's ``src``, so a subprocess runs the gyropipe under test)."""
    kept = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return {**os.environ, "PYTHONPATH": os.pathsep.join([*map(str, dirs), *kept])}


def faults_of(script: str, *args: object, timeout: float = 120) -> int:
    """The page-fault count a ``python -c script args…`` prints (a fresh process: a fresh
    heap, the gyropipe under test on its path)."""
    found = subprocess.run(
        [sys.executable, "-c", script, *map(str, args)],
        capture_output=True,
        text=True,
        env=pythonpath(),
        timeout=timeout,
        check=True,
    )
    return int(found.stdout)


def plugin_site(root: Path, plugins: Mapping[str, tuple[str, str]]) -> Path:
    """``root`` made a directory of installed plugins: for each name → (version, module
    source), the module and a dist-info declaring it an entry point of the group
    ``gyropipe`` (put ``root`` on ``sys.path`` or ``PYTHONPATH`` to install them)."""
    for name, (version, source) in plugins.items():
        (root / f"{name}.py").write_text(textwrap.dedent(source))
        info = root / f"{name}-{version}.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {version}\n")
        (info / "entry_points.txt").write_text(f"[gyropipe]\n{name} = {name}\n")
    return root


EXAMPLE_SITE: dict[str, Any] = {
    "latitude": 61.25,
    "longitude": 73.4,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
"""The bundled simulation plans' site (West Siberia; latitude and longitude deg, the IGRF-14
field of that day: total field nT, dip and declination deg), for a test's own plan."""

TRUE_NORTH = {"north_reference": "true"}
"""A pipeline's well defaults: azimuths are to true north unless the file says otherwise."""


LISTING_HEADER = """\
Well: T-7
Latitude: 61.25
Longitude: 73.4
Survey Date: 2026-11-21

MD (m),Inc (deg),Azimuth True (deg),TVD (m),North (m),East (m)
"""
"""The head of a vendor's stations listing (CSV) that lists each station's position."""


def stage(
    id: str,
    uses: str,
    inputs: Mapping[str, str] | None = None,
    persist: list[str] | None = None,
    **with_: Any,
) -> dict[str, Any]:
    """One stage of a pipeline spec: ``id`` running ``uses`` on ``inputs`` (port → stage.port)
    with the parameters ``with_`` (its ``with:``), persisting the ports ``persist``."""
    out: dict[str, Any] = {"id": id, "uses": uses}
    if inputs:
        out["inputs"] = dict(inputs)
    if with_:
        out["with"] = with_
    if persist:
        out["persist"] = persist
    return out


def survey_stages(vs_azimuth: float = 0.0) -> list[dict[str, Any]]:
    """The head of a survey pipeline: stations ``read``, their ``trajectory`` (persisted)."""
    return [
        stage("read", "read_stations"),
        stage(
            "trajectory",
            "minimum_curvature",
            {"stations": "read.stations"},
            ["trajectory"],
            vs_azimuth=vs_azimuth,
        ),
    ]


def pipeline_yaml(
    stages: Sequence[Mapping[str, Any]],
    name: str = "test",
    inputs: Sequence[str] = ("stations",),
    well: Mapping[str, Any] | None = TRUE_NORTH,
) -> str:
    """The YAML of pipeline ``name`` 1.0 of ``stages`` (:func:`stage`) on ``inputs``, with the
    ``well`` defaults (None: none)."""
    spec: dict[str, Any] = {
        "name": name,
        "version": "1.0",
        "inputs": {n: {"description": n} for n in inputs},
        **({"well": dict(well)} if well is not None else {}),
        "stages": list(stages),
    }
    return yaml.safe_dump(spec, sort_keys=False)


def write_pipeline(directory: Path, stages: Sequence[Mapping[str, Any]], **spec: Any) -> Path:
    """:func:`pipeline_yaml` of ``stages`` written to ``directory/<name>.yaml``."""
    text = pipeline_yaml(stages, **spec)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{yaml.safe_load(text)['name']}.yaml"
    path.write_text(text)
    return path


def without_report(name: str, directory: Path) -> Path:
    """The shipped pipeline ``pipelines/NAME.yaml`` without its report stage, written to
    ``directory`` (its processing stages only)."""
    spec = yaml.safe_load((ROOT / "pipelines" / f"{name}.yaml").read_text())
    spec["stages"] = [s for s in spec["stages"] if s["uses"] != "report"]
    path = directory / f"{name}.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def read_stations(path: Path, reader: str) -> pa.Table:
    """A stations file read with the engine's reader choice, as the CLI gives it to the
    simulator (``StationsWell.load``)."""
    from pipeline.plugins import load_registry

    return load_registry().read(path, "stations", reader=reader)[0]


def plugin_io(plugin: ModuleType) -> tuple[ReaderDef, WriterDef]:
    """The one reader and the one writer an I/O plugin module registers."""
    readers: list[ReaderDef] = []
    writers: list[WriterDef] = []
    plugin.gyropipe_register_readers(register=readers.append)
    plugin.gyropipe_register_writers(register=writers.append)
    (reader,) = readers
    (writer,) = writers
    return reader, writer


def export_tolerance(unit: str, values: Any) -> Any:
    """How far an export may put ``values`` of ``unit`` (a unit in
    :data:`pipeline.io.precision.DECIMALS`): half a step of its decimals, plus the
    float's own rounding."""
    from pipeline.io.precision import DECIMALS

    with np.errstate(over="ignore"):
        return 0.5 * 10.0 ** -DECIMALS[unit] + 2 * np.spacing(np.abs(values))


def assert_exported(back: pa.Table, written: pa.Table, names: list[str] | None = None) -> None:
    """Columns ``names`` (default: all) of ``written`` as an export reads them back: a float
    column of a unit in :data:`pipeline.io.precision.DECIMALS` within half a step of that
    unit's decimals (plus the float's own rounding), nulls and NaN where they were; any
    other column exactly."""
    from pipeline.contracts import UNIT_KEY
    from pipeline.io.precision import DECIMALS

    for name in names or written.column_names:
        field = written.schema.field(name)
        got, want = back.column(name), written.column(name)
        unit = (field.metadata or {}).get(UNIT_KEY, b"").decode()
        if unit not in DECIMALS or not pa.types.is_floating(field.type):
            assert got.equals(want), name
            continue
        assert got.is_null().equals(want.is_null()), name
        a = got.to_numpy(zero_copy_only=False).astype(np.float64)
        b = want.to_numpy(zero_copy_only=False).astype(np.float64)
        assert np.array_equal(np.isnan(a), np.isnan(b)), name
        finite = np.isfinite(b)
        tolerance = export_tolerance(unit, b[finite])
        assert np.all(np.abs(a[finite] - b[finite]) <= tolerance), (name, unit)
        assert np.array_equal(a[~finite], b[~finite], equal_nan=True), name


def mutate_bytes(data: bytes, mutations: list[tuple[str, int, int]]) -> bytes:
    """Byte-level fuzz mutations at positions: flip, truncate, insert, delete (n bytes),
    delete_line, swap_columns (two whitespace-separated cells of the line)."""
    buf = bytearray(data)
    for op, at, arg in mutations:
        at = min(at, len(buf))
        start = buf.rfind(b"\n", 0, at) + 1
        end = buf.find(b"\n", at)
        end = len(buf) if end < 0 else end
        if op == "flip" and at < len(buf):
            buf[at] = arg
        elif op == "truncate":
            del buf[at:]
        elif op == "insert":
            buf[at:at] = bytes([arg])
        elif op == "delete":
            del buf[at : at + arg]
        elif op == "delete_line":
            del buf[start : end + 1]
        elif op == "swap_columns":
            cells = bytes(buf[start:end]).split()
            if len(cells) > arg + 1:
                cells[arg], cells[arg + 1] = cells[arg + 1], cells[arg]
                buf[start:end] = b" ".join(cells)
    return bytes(buf)


def byte_mutations(
    size: int, inserted: bytes, lines: bool = False
) -> st.SearchStrategy[tuple[str, int, int]]:
    """One :func:`mutate_bytes` operation at a position up to ``size``: flip, truncate, insert
    one of the bytes ``inserted``, delete; with ``lines`` also delete_line and swap_columns."""
    position = st.integers(min_value=0, max_value=size)
    ops = [
        st.tuples(st.just("flip"), position, st.integers(0, 255)),
        st.tuples(st.just("truncate"), position, st.just(0)),
        st.tuples(st.just("insert"), position, st.sampled_from(inserted)),
        st.tuples(st.just("delete"), position, st.integers(1, 8)),
    ]
    if lines:
        ops.append(st.tuples(st.just("delete_line"), position, st.just(0)))
        ops.append(st.tuples(st.just("swap_columns"), position, st.integers(0, 3)))
    return st.one_of(ops)


def mutate_lines(data: bytes, ops: list[tuple[str, int, int]], delimiter: bytes) -> bytes:
    """Line-aware fuzz mutations: truncate, flip a byte, delete a line, swap two columns (in
    every line: a valid file stays valid) or two cells of one line (``swap_row``)."""
    for op, a, b in ops:
        lines = data.split(b"\n")
        if op == "truncate":
            data = data[: a % (len(data) + 1)]
        elif op == "flip" and data:
            i = a % len(data)
            data = data[:i] + bytes([b % 256]) + data[i + 1 :]
        elif op == "delete":
            del lines[a % len(lines)]
            data = b"\n".join(lines)
        elif op in ("swap", "swap_row"):
            for n in range(len(lines)) if op == "swap" else [b % len(lines)]:
                cells = lines[n].split(delimiter)
                i, j = a % len(cells), (a // 7) % len(cells)
                cells[i], cells[j] = cells[j], cells[i]
                lines[n] = delimiter.join(cells)
            data = b"\n".join(lines)
    return data


def line_ops() -> st.SearchStrategy[tuple[str, int, int]]:
    """One :func:`mutate_lines` operation."""
    return st.tuples(
        st.sampled_from(["truncate", "flip", "delete", "swap", "swap_row"]),
        st.integers(0, 10_000),
        st.integers(0, 10_000),
    )


def comparable_cell(value: Any, null: float | None = None) -> float | str | None:
    """A LAS cell of gyropipe or lasio in comparable form: None (null), a float or stripped
    text. lasio keeps a curve holding a text null as text, with its numbers as text, the
    NULL value (``null``) among them."""
    if value is None:
        return None
    if isinstance(value, float | np.floating):
        return None if math.isnan(value) else float(value)
    text = str(value).strip()
    if not text or TEXT_NULLS.fullmatch(text):
        return None
    try:
        number = float(text)
    except ValueError:
        return text
    return None if math.isnan(number) or number == null else number


def simulate_and_run(tmp_path: Path, plan_text: str, pipeline: str = "point-gyro.yaml") -> Path:
    """``gyropipe simulate`` the plan (YAML text) into ``tmp_path/sim``, then ``gyropipe run``
    the shipped ``pipeline`` on its samples into ``tmp_path/out``; return the run's directory
    (the run must succeed)."""
    (tmp_path / "plan.yaml").write_text(plan_text)
    gyropipe_cli(
        "simulate", str(tmp_path / "plan.yaml"), "--out", str(tmp_path / "sim"), check=True
    )
    out = tmp_path / "out"
    pipeline_file, samples = ROOT / "pipelines" / pipeline, tmp_path / "sim" / "samples.parquet"
    result = gyropipe_cli("run", str(pipeline_file), "--input", str(samples), "--out", str(out))
    assert result.returncode == 0, result.stderr
    return out


class _Tables(HTMLParser):
    """Cell texts of every table in an HTML file, by table class."""

    def __init__(self) -> None:
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self._current: str | None = None
        self._cell: list[str] | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "table":
            self._current = (dict(attrs).get("class") or "").split()[0]
            self.tables[self._current] = []
        elif tag == "tr" and self._current:
            self.tables[self._current].append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag in ("td", "th") and self._cell is not None and self._current:
            self.tables[self._current][-1].append("".join(self._cell))
            self._cell = None
        elif tag == "table":
            self._current = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)


def tables_of(html: Path) -> dict[str, list[list[str]]]:
    """The cell texts of every table of an HTML report, by table class (row by row, the
    header row first)."""
    parser = _Tables()
    parser.feed(html.read_text(encoding="utf-8"))
    return parser.tables


def point_gyro_run(root: Path, plan: str = "short-j-well") -> Path:
    """``pipelines/point-gyro.yaml`` on ``examples/plans/PLAN.yaml`` simulated under
    ``root``; returns its output directory."""
    gyropipe_cli("simulate", ROOT / "examples" / "plans" / f"{plan}.yaml", "--out", root / "sim",
                 check=True)  # fmt: skip
    gyropipe_cli(
        "run", ROOT / "pipelines" / "point-gyro.yaml",
        "--input", f"samples={root / 'sim' / 'samples.parquet'}", "--out", root / "out",
        check=True,
    )  # fmt: skip
    return root / "out"

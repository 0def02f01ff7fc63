"""Seeded fuzzing of every input kind gyropipe reads, in process, through the code paths
the CLI uses. Shared by ``tests/test_fuzz_inputs.py`` (a few hundred inputs) and
``benchmarks/fuzz_inputs.py`` (the long run).

Every input starts from a valid seed file (``examples/``, ``tests/data``, ``pipelines/`` or
written by gyropipe's own writers from a small simulation, or from a listing stating its
covariances, error model and tie-on: the carried-uncertainty read paths of CSV, WITSML
and Parquet) and is mutated a few times:
bytes flipped, inserted or deleted, truncated, lines deleted, duplicated or swapped,
columns swapped, numbers replaced by NaN/inf/huge/odd spellings, units swapped, the file
emptied or replaced by binary junk, re-encoded (UTF-16, latin-1, CRLF, BOM); tables
re-written with NaN/inf cells, dropped or renamed columns, wrong unit metadata, zero rows,
garbled well metadata (Parquet, MCAP); MCAP messages cut short, flipped, emptied, dropped,
repeated or re-timed and their JSON changed, with the file's CRCs intact; YAML values
replaced, tags, anchors, aliases and merge keys injected, keys misspelt, nesting deepened,
two problems made at once (pipelines, simulation plans); manifest cells replaced; files
replaced by hostile ones of their kind (``hostile_inputs``: chunks and row counts claiming
gigabytes, metadata nested 100,000 deep, megabyte XML tokens and YAML aliases). Then it
is run the way the CLI runs it:

* table files — :func:`pipeline.convert.convert` (``gyropipe convert``), the accepted table
  checked against its contract and re-read from the file written, accepted stations also
  integrated by minimum curvature (:func:`pipeline.api.functions.minimum_curvature`);
* pipeline YAML — :func:`pipeline.spec.load_spec` + :func:`pipeline.graph.build_plan`
  (``gyropipe validate``);
* simulation plans — :func:`pipeline.sim.spec.load_simulation` and the plan's well path
  (``gyropipe simulate`` up to the simulation itself);
* batch manifests — :func:`pipeline.batch.jobs.jobs_from_manifest` (``gyropipe batch``).

Each outcome is classified (:data:`OUTCOMES`); :data:`BAD` ones break the contract every
input must meet: refused with a located one-line message, or accepted with finite,
contract-valid output; never a traceback, never a hang.
"""

from __future__ import annotations

import contextlib
import io
import json
import random
import re
import signal
import time
import traceback
import warnings
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from fuzz_faults import FAULT_KINDS, FS_FAULT, LEDGER, MANIFEST_SPECIAL, Faults, make_fault
from hostile_inputs import HOSTILE
from pipeline.contracts import UNIT_KEY, VERTICAL_TOLERANCE, TableContract
from pipeline.convert import convert, read_kind
from pipeline.errors import (
    ContractViolation,
    GyropipeError,
    InputFileError,
    InputFileWarning,
    ReaderError,
    SpecError,
    StageError,
    WrongKindError,
)
from pipeline.plugins import load_registry
from pipeline.registry import Registry
from pipeline.tables import LogTable, PositionReadings, RawSamples, Stations
from pipeline.well import WELL_KEY, WellMetadata, attach
from tests_support import mutate_bytes, mutate_lines

ROOT = Path(__file__).resolve().parents[1]

# ------------------------------------------------------------------------------ outcomes

ACCEPTED = "accepted"
REFUSED = "refused"
"""a GyropipeError naming the file and a location (or a whole-file reason)"""
UNLOCATED = "unlocated"
"""a GyropipeError without the file name or without a location where one is expected"""
MULTILINE = "multiline"
"""a file error whose message spans several lines (the CLI prints it as it is)"""
TRACEBACK = "traceback"
"""any other exception, or a reader's unexpected exception wrapped in a ReaderError"""
HANG = "hang"
NONFINITE = "nonfinite"
"""accepted, with NaN/inf where the contract promises finite numbers"""
CONTRACT = "contract"
"""accepted, with a table that breaks its contract otherwise"""
UNWRITABLE = "unwritable"
"""read, but the writer of the output format cannot hold the table (a log without a
numeric curve as LAS, an empty table as WITSML), refused naming both files (``gyropipe
convert`` exits 2); a writer's refusal that does not name both is :data:`UNLOCATED`"""
ROUNDTRIP = "roundtrip"
"""accepted, but the file gyropipe wrote from it does not read back as the same kind"""
PARTIAL = "partial"
"""a spec with two problems made on purpose, only one of them reported (``validate``
reports every problem in one pass)"""

OUTCOMES = (
    ACCEPTED,
    REFUSED,
    UNLOCATED,
    MULTILINE,
    TRACEBACK,
    HANG,
    NONFINITE,
    CONTRACT,
    UNWRITABLE,
    ROUNDTRIP,
    PARTIAL,
)
BAD = frozenset({TRACEBACK, HANG, NONFINITE, CONTRACT, ROUNDTRIP, PARTIAL})
"""Outcomes that break the contract every input must meet."""

CONTRACTS: dict[str, type[TableContract]] = {
    "stations": Stations,
    "samples": RawSamples,
    "readings": PositionReadings,
    "log": LogTable,
}
TARGETS: dict[str, tuple[str, ...]] = {
    "stations": ("csv", "parquet", "las", "xml"),
    "samples": ("csv", "parquet", "las", "mcap"),
    "readings": ("csv", "parquet"),
    "log": ("csv", "parquet", "las"),
}
"""Formats each kind is converted to, in turn (``auto``: CSV and Parquet, which hold any)."""

LOCATED = re.compile(
    r"(:\d+\b|\blines? \d+|\bbyte \d+|\bmessage \d+|\brow \d+|\brecord\b|\bcolumn '|\bfooter\b|"
    r"in the schema metadata|/gyropipe/\w+|\btopic\b)",
    re.IGNORECASE,
)
WHOLE_FILE = re.compile(
    r"(empty|no data|not an? [\w -]*file|not a readable|too short|cannot read|no such file|"
    r"UTF-?16|encod|decod|binary|magic|no installed reader recognises|no channels|"
    r"not UTF-8|NUL|no header|no ~|section is missing|several readers claim|no channel)",
    re.IGNORECASE,
)
"""Problems of the whole file, which need no line: empty, unrecognised, undecodable."""
MASKED_CRASH = re.compile(r"reader '[\w.]+' \(plugin builtin\.[^)]*\) failed: (\w+):")
"""A built-in reader's unexpected exception, as a ReaderError reports it."""


class Hang(BaseException):
    """The time budget of one input ran out (a BaseException: no reader swallows it)."""


@dataclass(frozen=True)
class Outcome:
    """What one fuzzed input did."""

    kind: str
    index: int
    label: str
    detail: str
    seconds: float
    mutations: tuple[str, ...]
    data: bytes
    suffix: str
    warnings: tuple[str, ...] = ()
    """warnings other than InputFileWarning (Python prints them over several lines)"""

    @property
    def bad(self) -> bool:
        return self.label in BAD


# --------------------------------------------------------------------------------- seeds


@dataclass(frozen=True)
class Seed:
    """A valid input file and how to read it."""

    name: str
    data: bytes
    reader: str = "auto"
    options: dict[str, Any] = field(default_factory=dict)
    table: pa.Table | None = None
    """the table behind a binary seed, for table-level mutations"""


REQUIRED = {
    "clearance": (
        b"# reference_hole_diameter: m, required (e.g. 0.3112 for a 12\xc2\xbc in hole)",
        b"reference_hole_diameter: 0.3112",
    ),
}
"""Values a shipped pipeline leaves for the user to give (the well's own): the line of the
pipeline that says so, and the line a user writes there."""


def completed(name: str, text: bytes) -> bytes:
    """A shipped pipeline as a user completes it (:data:`REQUIRED`): a valid seed."""
    if name not in REQUIRED:
        return text
    left, given = REQUIRED[name]
    assert left in text, f"pipelines/{name}.yaml no longer says {left!r}"
    return text.replace(left, given)


@dataclass(frozen=True)
class InputKind:
    """One input kind: its seeds, how its files are mutated and run."""

    name: str
    suffix: str
    family: str
    """``text``, ``binary``, ``yaml``, ``manifest``, ``fault`` (made and run by ``fuzz_faults``)"""
    expect: str | None
    """the table kind asked for (None: the seed's name is its kind, as for Parquet, or the
    file is no table: YAML, manifests)"""
    seeds: tuple[Seed, ...]


SITE = {
    "latitude": 61.25,
    "longitude": 73.4,
    "elevation": 120.0,
    "date": "2026-11-21",
    "magnetic": {"total_field": 59731.0, "dip": 78.29, "declination": 17.0},
}
SMALL_PLAN = {
    "name": "fuzz",
    "seed": 3,
    "site": SITE,
    "well": {
        "sections": [
            {"kind": "vertical", "length": 10},
            {"kind": "curve", "dls": 30.0, "inc": 35, "azi": 40},
        ]
    },
    "tool": {"preset": "mems-vrg"},
    "survey": {
        "mode": "point",
        "every": 10,
        "dwell": 0.2,
        "move_time": 0.2,
        "speed": 5.0,
        "positions": [0, 180],
    },
}
SIM_WELL = WellMetadata(
    well="FZ-1",
    latitude=61.25,
    longitude=73.4,
    elevation=120.0,
    survey_date="2026-11-21",
    tool_type="simulated mems-vrg",
    north_reference="true",
)
LOG_SEEDS = ("gr.las", "time_log.las", "lasio/1.2/sample.las", "lasio/2.0/sample_2.0.las")
JSON_MCAP_OPTIONS = {
    "columns": {"time": "t"},
    "units": {"gyro": "deg/h", "acc": "m/s2", "time": "s"},
}


def _simulated() -> dict[str, pa.Table]:
    from pipeline.sim.spec import SimulationSpec
    from pipeline.stages.simulation import simulation_tables

    tables = simulation_tables(SimulationSpec.model_validate(SMALL_PLAN))
    return {"samples": tables["samples"].slice(0, 40), "stations": tables["stations"]}


def _json_mcap(rows: int = 30) -> bytes:
    """A per-sample JSON MCAP (a foreign layout: keyed messages) of ``rows`` samples."""
    from mcap.writer import Writer

    values = np.random.default_rng(5).normal(size=(rows, 6)) * [10, 10, 10, 0.5, 0.5, 9.8]
    out = io.BytesIO()
    writer = Writer(out, chunk_size=1024)
    writer.start()
    channel = writer.register_channel("/imu", "json", 0)
    keys = ("wx", "wy", "wz", "gx", "gy", "gz")
    for i, row in enumerate(values):
        message = {"t": i * 0.01, **dict(zip(keys, row.tolist(), strict=True))}
        stamp = 1_700_000_000_000_000_000 + i * 10_000_000
        writer.add_message(channel, stamp, json.dumps(message).encode(), stamp)
    writer.finish()
    return out.getvalue()


def _written(registry: Registry, writer: str, table: pa.Table, work: Path, name: str) -> bytes:
    path = work / name
    registry.writers[writer][0].write(attach(table, SIM_WELL), path, SIM_WELL)
    return path.read_bytes()


def _head(path: Path, lines: int) -> bytes:
    return b"".join(path.read_bytes().splitlines(keepends=True)[:lines])


MANIFEST = (
    "# wells of the fuzz batch\n"
    "well_id,stations,latitude,longitude,tool_serial\n"
    "J-12,stations-j-well.csv,61.25,73.4,SN-1\n"
    "J-13,j13.csv,,,\n"
    'K_7.b,sub/k7.csv,-12.5,120.25,"SN, 7"\n'
)
MANIFEST_INPUTS = ("stations",)
SPECIAL_MANIFEST = b"well_id,stations\nA-1,a.csv\nB-2,a.csv\n"
"""The manifest whose cells ``fuzz_faults`` points at special files."""
STATIONS_PLAN = (
    "name: stations-plan\nseed: 1\n"
    "site: {latitude: 61.25, longitude: 73.4, elevation: 54.3, date: 2026-11-21}\n"
    "well:\n  stations: stations-j-well.csv\n  reader: auto\n  start_north: 1.5\n"
    "tool: {preset: ideal}\n"
    "survey: {mode: point, stations: [100, 300, 600], dwell: 5, positions: [0, 180]}\n"
)


STORE_TRAJECTORY = b"""<?xml version="1.0" encoding="UTF-8"?>
<trajectorys xmlns="http://www.witsml.org/schemas/1series" version="1.4.1.1">
  <trajectory uidWell="W-58" uidWellbore="W-58-1" uid="TRJ-7">
    <nameWell>58/1-A1</nameWell><nameWellbore>58/1-A1</nameWellbore><name>Gyro 0-360 m</name>
    <objectGrowing>true</objectGrowing>
    <parentTrajectory><trajectoryReference uidRef="TRJ-1">Main bore</trajectoryReference>
    </parentTrajectory>
    <dTimTrajStart>2026-03-02T08:00:00Z</dTimTrajStart>
    <mdMn uom="m">0</mdMn><mdMx uom="m">390</mdMx>
    <magDeclUsed uom="dega">0</magDeclUsed>
    <finalTraj>false</finalTraj><aziRef>true north</aziRef>
    <trajectoryStation uid="s0"><typeTrajStation>tie in point</typeTrajStation>
      <md uom="m">0</md><incl uom="dega">0</incl><azi uom="dega">0</azi></trajectoryStation>
    <trajectoryStation uid="s1"><typeTrajStation>gyro north seeking</typeTrajStation>
      <typeSurveyTool>gyroscopic north seeking</typeSurveyTool><md uom="m">300</md>
      <incl uom="dega">0.5</incl><azi uom="dega">45</azi>
      <statusTrajStation>position</statusTrajStation></trajectoryStation>
    <trajectoryStation uid="s2"><typeTrajStation>gyro north seeking</typeTrajStation>
      <md uom="m">330</md><incl uom="dega">1.5</incl><azi uom="dega">45</azi>
      <statusTrajStation>rejected</statusTrajStation></trajectoryStation>
    <trajectoryStation uid="s3"><typeTrajStation>casing MD</typeTrajStation>
      <md uom="m">340</md><incl uom="dega">1.8</incl><azi uom="dega">45</azi></trajectoryStation>
    <trajectoryStation uid="s4"><typeTrajStation>gyro north seeking</typeTrajStation>
      <md uom="m">360</md><incl uom="dega">3</incl><azi uom="dega">45</azi>
      <commonData><itemState>actual</itemState></commonData></trajectoryStation>
    <trajectoryStation uid="s5"><typeTrajStation>gyro north seeking</typeTrajStation>
      <md uom="m">390</md><incl uom="dega">4</incl><azi uom="dega">46</azi>
      <commonData><itemState>plan</itemState></commonData></trajectoryStation>
    <commonData><sourceName>Store A</sourceName><itemState>actual</itemState></commonData>
  </trajectory>
</trajectorys>
"""
"""A store's answer: a sidetrack's growing, preliminary trajectory (its tie-in listing no
position: warned of) whose stations the store marks validated, rejected, a marker, actual
and planned."""
LISTING = b"""Company: Example Operator
Well: 58/1-A1
Survey Date: 2026-03-02
well.survey_date_last: 2026-03-04
North Reference: grid
Grid Convergence: 0.75

MD (m),Inc (deg),Azi (deg),TVD (m),Survey Type
0.00,0.00,0.00,0.00,Tie-In
300.00,0.00,0.00,300.00,Gyro NS
330.00,1.50,45.00,329.99,Gyro NS
345.00,2.20,45.00,344.97,Interpolated
360.00,3.00,45.00,359.94,Gyro NS
380.00,4.00,45.00,379.88,Projection to TD
"""
"""A vendor's listing whose Survey Type column names its tie-in, an interpolation and the
projection to TD, its north grid, its survey two days."""
UNCERTAINTY = b"""# confidence=0.95
# error_model=TEST-GYRO rev 2
# tie_on={"surveys":[{"md":500.0,"basis":"not included"}]}
north_reference: true
md[m],inc[deg],azi[deg],cov_nn[m2],cov_ne[m2],cov_nv[m2],cov_ee[m2],cov_ev[m2],cov_vv[m2]
500,10,30,0.01,0.001,0.0005,0.02,0.0002,0.004
600,12,32,0.04,0.004,0.002,0.08,0.0008,0.016
700,14,34,,,,,,
800,16,36,0.16,0.016,0.008,0.32,0.0032,0.064
"""
"""A trajectory listing tied on at 500 m MD stating its NEV covariance (one station without),
error model, confidence and tie-on (the carried-uncertainty read paths: written again as
WITSML matrixCov with its extension values, and as Parquet with its tie-on record)."""


INPUT_KIND_NAMES = (
    "las-stations",
    "las-samples",
    "las-log",
    "csv-stations",
    "csv-samples",
    "csv-readings",
    "mcap",
    "parquet",
    "witsml",
    "pipeline",
    "plan",
    "manifest",
)
"""Every kind of input file fuzzed by mutating its bytes."""
KIND_NAMES = (*INPUT_KIND_NAMES, *FAULT_KINDS)
"""Every kind fuzzed (:func:`build_kinds` makes their seeds): the input files, then the
fault kinds of ``fuzz_faults`` (special files, a corrupted ledger, file-system faults)."""


def build_kinds(registry: Registry, work: Path) -> dict[str, InputKind]:
    """Every input kind with its seeds (written to ``work`` where a writer makes them)."""
    work.mkdir(parents=True, exist_ok=True)
    sim = _simulated()
    samples, stations = sim["samples"], sim["stations"]
    readings_csv = _head(ROOT / "examples/readings-j-well.csv", 30)
    stations_csv = (ROOT / "examples/stations-j-well.csv").read_bytes()
    (work / "stations-j-well.csv").write_bytes(stations_csv)  # read by the stations plan
    readings = registry.read(_put(work, "readings.csv", readings_csv), "readings")[0]
    carried = registry.read(_put(work, "uncertainty.csv", UNCERTAINTY), "stations")[0]
    las_data = ROOT / "tests/data/las"
    kinds = [
        InputKind(
            "las-stations",
            ".las",
            "text",
            "stations",
            (
                Seed("sim", _written(registry, "las", stations, work, "s.las")),
                Seed(
                    "hand",
                    b"~Version\n VERS. 2.0 :\n WRAP. NO :\n~Well\n STRT.FT 0.0 :\n"
                    b" STOP.FT 201.0 :\n STEP.FT 100.5 :\n NULL. -999.25 :\n WELL. A-12 :\n"
                    b"~Curve\n DEPT.FT : depth\n INCL.DEG : inclination\n"
                    b" AZIM.DEG : azimuth (true north)\n GR.GAPI : gamma\n~A\n"
                    b"0.0 0.0 0.0 45\n100.5 1.25 45.5 -999.25\n201.0 2.5 46.0 50\n",
                ),
            ),
        ),
        InputKind(
            "las-samples",
            ".las",
            "text",
            "samples",
            (Seed("sim", _written(registry, "las", samples.slice(0, 25), work, "r.las")),),
        ),
        InputKind(
            "las-log",
            ".las",
            "text",
            "log",
            tuple(Seed(name, (las_data / name).read_bytes()) for name in LOG_SEEDS),
        ),
        InputKind(
            "csv-stations",
            ".csv",
            "text",
            "stations",
            (
                Seed("example", stations_csv),
                Seed("sim", _written(registry, "csv", stations, work, "s.csv")),
                Seed("listing", LISTING),
                Seed("uncertainty", UNCERTAINTY),
            ),
        ),
        InputKind(
            "csv-samples",
            ".csv",
            "text",
            "samples",
            (Seed("sim", _written(registry, "csv", samples.slice(0, 25), work, "r.csv")),),
        ),
        InputKind("csv-readings", ".csv", "text", "readings", (Seed("example", readings_csv),)),
        InputKind(
            "mcap",
            ".mcap",
            "binary",
            "samples",
            (
                Seed(
                    "gyropipe",
                    _written(registry, "mcap", samples, work, "r.mcap"),
                    table=samples,
                ),
                Seed("json", _json_mcap(), reader="mcap", options=JSON_MCAP_OPTIONS),
            ),
        ),
        InputKind(
            "parquet",
            ".parquet",
            "binary",
            None,
            (
                *(
                    Seed(
                        name, _written(registry, "parquet", table, work, f"{name}.parquet"), table=t
                    )
                    for name, table, t in (
                        ("stations", stations, stations),
                        ("samples", samples, samples),
                        ("readings", readings, readings),
                    )
                ),
                Seed(  # named by its kind, as the others: a stations file's covariances
                    "stations",
                    _written(registry, "parquet", carried, work, "uncertainty.parquet"),
                    table=carried,
                ),
            ),
        ),
        InputKind(
            "witsml",
            ".xml",
            "text",
            "stations",
            (
                Seed("sim", _written(registry, "witsml", stations, work, "s.xml")),
                Seed("store", STORE_TRAJECTORY),
                Seed("uncertainty", _written(registry, "witsml", carried, work, "u.xml")),
            ),
        ),
        InputKind(
            "pipeline",
            ".yaml",
            "yaml",
            None,
            tuple(
                Seed(p.stem, completed(p.stem, p.read_bytes()))
                for p in sorted((ROOT / "pipelines").glob("*.yaml"))
            ),
        ),
        InputKind(
            "plan",
            ".yaml",
            "yaml",
            None,
            (
                *(
                    Seed(p.stem, p.read_bytes())
                    for p in sorted((ROOT / "examples/plans").glob("*.yaml"))
                ),
                Seed("stations-plan", STATIONS_PLAN.encode()),
            ),
        ),
        InputKind("manifest", ".csv", "manifest", None, (Seed("manifest", MANIFEST.encode()),)),
        InputKind(MANIFEST_SPECIAL, ".csv", "fault", None, (Seed("manifest", SPECIAL_MANIFEST),)),
        InputKind(LEDGER, ".json", "fault", None, (Seed("faults", b"[]"),)),
        InputKind(FS_FAULT, ".json", "fault", None, (Seed("faults", b"[]"),)),
    ]
    assert tuple(k.name for k in kinds) == KIND_NAMES
    return {k.name: k for k in kinds}


def _put(work: Path, name: str, data: bytes) -> Path:
    path = work / name
    path.write_bytes(data)
    return path


# ----------------------------------------------------------------------------- mutations

SPECIAL_NUMBERS = (
    "NaN", "nan", "-nan", "inf", "-inf", "Infinity", "-Infinity", "1e308", "-1e308", "1e309",
    "-1e999", "1e-400", "4.9e-324", "0", "-0", "99999999999999999999999999999",
    "1.7976931348623157e308", "", "-999.25", "-999", "1,5", "0x1p3", "1_0", "١٢", "+", ".",
    "e5", "--1", "1e", "1.2.3", "1e-5", "-0.0", "360", "-180", "180.0000001", "1e15",
)  # fmt: skip
UNITS = (
    "m", "M", "ft", "FT", "F", "usft", "deg", "DEG", "dega", "rad", "grad", "deg/h", "deg/s",
    "rad/s", "mrad/s", "dph", "m/s2", "m/s^2", "g", "G", "mg", "nT", "uT", "gauss", "s",
    "ms", "h", "min", "", "furlong", "%", "°", "degC", "m/s",
)  # fmt: skip
UNIT_TOKEN = re.compile(
    rb"(?<![A-Za-z0-9/^])("
    + b"|".join(re.escape(u.encode()) for u in sorted(UNITS, key=len, reverse=True) if u)
    + rb")(?![A-Za-z0-9/^])"
)
NUMBER_TOKEN = re.compile(rb"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
YAML_SCALARS = (
    "", "null", "~", ".nan", ".inf", "-.inf", "1e999", "-1e999", "[1, 2]", "{a: 1}", "yes",
    "no", "0x1F", "0o17", "2026-13-45", "2026-02-30", "'unterminated", '"unterminated',
    "x" * 300, "-1", "0", "1e308", "-0.0", "true", "[]", "{}", "|\n  block", "&", "*",
    "!", "@x", "`x`", "%x", "? x", "- x", "1:2", "é°µ", "\\u0000", "'\\x00'", "12:30:00",
    "123456789012345678901234567890",
)  # fmt: skip
YAML_TAGS = (
    "!!python/object/apply:os.system ['true']", "!!python/name:os.system", "!!binary aGk=",
    "!custom x", "!!set {a, b}", "!!omap [a: 1]", "!!timestamp 2001-12-14", "!!float nan",
    "!!int 1e3", "!!str", "!!map {}", "!!seq []", "!!null x", "!<tag:x> 1", "!!bool maybe",
)  # fmt: skip
MANIFEST_CELLS = (
    "", "nan", "inf", "-inf", "1e999", "-91", "181", "abc", "../escape", "a b", "/abs/path.csv",
    "ledger.sqlite", "summary.csv", "é", '"', '"unclosed', "x" * 200, "J-12", "J-12 ", " ",
    "\t", "-lead", ".hidden", "CON", "a/../b.csv", "0", "2026-11-21", "None", "null",
)  # fmt: skip
NON_ASCII = ("°", "µ", "é", "Ø", "±", "²", "ß", "\u00a0")

Op = Callable[[random.Random, bytes, "Context"], tuple[bytes, str]]


@dataclass
class Context:
    """What an operation may need besides the bytes: the kind and seed, a way to re-write
    a table (binary kinds)."""

    kind: InputKind
    seed: Seed
    rewrite: Callable[[pa.Table], bytes | None]
    table: pa.Table | None = None
    notes: set[str] = field(default_factory=set)


def _byte_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    op = rng.choice(["flip", "flip", "truncate", "insert", "delete", "delete_line"])
    at = rng.randrange(len(data) + 1)
    arg = {
        "flip": rng.randrange(256),
        "truncate": 0,
        "insert": rng.choice(b" \t\r\n#~.:-+eE0123456789,;\"'[]{}()\x00\xff"),
        "delete": rng.randint(1, 16),
        "delete_line": 0,
    }[op]
    return mutate_bytes(data, [(op, at, arg)]), f"{op}@{at}:{arg}"


def _flips(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    n = rng.randint(2, 12)
    ops = [("flip", rng.randrange(len(data) + 1), rng.randrange(256)) for _ in range(n)]
    return mutate_bytes(data, ops), f"flips{ops}"


def _lines(data: bytes) -> list[bytes]:
    return data.split(b"\n")


REPEATED = 32 << 20
"""Most bytes a line repeated many times adds to an input (the harness holds every input,
and its copies, in the process whose peak memory the long run bounds)."""


def _line_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    lines = _lines(data)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    op = rng.choice(["duplicate", "swap", "move", "blank", "comment", "junk", "repeat_many"])
    if op == "duplicate":
        lines.insert(i, lines[i])
    elif op == "swap":
        lines[i], lines[j] = lines[j], lines[i]
    elif op == "move":
        lines.insert(j, lines.pop(i))
    elif op == "blank":
        lines.insert(i, rng.choice([b"", b" ", b"\t", b"\r"]))
    elif op == "comment":
        lines.insert(i, rng.choice([b"#", b"# x: y", b"~", b"~Other", b"--", b"//", b";"]))
    elif op == "junk":
        lines.insert(i, bytes(rng.randrange(32, 127) for _ in range(rng.randint(1, 80))))
    else:  # at most REPEATED bytes more: a hostile 5 MB line 200 times is the harness's GiB
        times = min(rng.randint(2, 200), max(2, REPEATED // max(1, len(lines[i]))))
        lines[i:i] = [lines[i]] * times
    return b"\n".join(lines), f"line-{op}@{i},{j}"


def _column_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    counts = Counter(c for c in data[:4000] if c in b",;\t|")
    delimiter = bytes([counts.most_common(1)[0][0]]) if counts else b" "
    op = (rng.choice(["swap", "swap_row"]), rng.randrange(10_000), rng.randrange(10_000))
    if delimiter == b" ":  # whitespace-separated columns (LAS)
        at = rng.randrange(len(data) + 1)
        return mutate_bytes(data, [("swap_columns", at, op[1] % 4)]), f"swap_columns@{at}"
    return mutate_lines(data, [op], delimiter), f"columns{op}{delimiter!r}"


def _number_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    found = list(NUMBER_TOKEN.finditer(data))
    if not found:
        return _byte_op(rng, data, ctx)
    hits = rng.sample(found, k=min(len(found), rng.choice([1, 1, 1, 2, 5])))
    new = rng.choice(SPECIAL_NUMBERS).encode("utf-8")
    for m in sorted(hits, key=lambda m: m.start(), reverse=True):
        data = data[: m.start()] + new + data[m.end() :]
    return data, f"number->{new!r}x{len(hits)}"


def _unit_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    found = list(UNIT_TOKEN.finditer(data))
    if not found:
        return _number_op(rng, data, ctx)
    m = rng.choice(found)
    new = rng.choice(UNITS).encode("utf-8")
    return data[: m.start()] + new + data[m.end() :], f"unit {m.group()!r}->{new!r}@{m.start()}"


def _whole_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    op = rng.choice(["empty", "junk", "junk_tail", "spaces", "nuls", "newlines", "prefix"])
    if op == "empty":
        return b"", op
    if op == "junk":
        return rng.randbytes(rng.choice([1, 7, 64, 1000, 20_000])), op
    if op == "junk_tail":
        at = rng.randrange(len(data) + 1)
        return data[:at] + rng.randbytes(rng.randint(1, 500)), f"{op}@{at}"
    if op == "spaces":
        return b" \t\n" * rng.randint(1, 50), op
    if op == "nuls":
        return b"\x00" * rng.randint(1, 500), op
    if op == "newlines":
        return b"\n" * rng.randint(1, 50), op
    return rng.choice(
        [b"\x89PNG\r\n\x1a\n", b"PAR1", b"\x89MCAP0\r\n", b"<?xml", b"~A\n"]
    ) + data, op


def _encoding_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    text = data.decode("utf-8", errors="replace")
    op = rng.choice(["utf-16", "utf-16-le", "utf-16-be", "latin-1", "cp1252", "bom", "crlf", "cr"])
    if op in ("latin-1", "cp1252"):
        lines = text.split("\n")
        i = rng.randrange(len(lines))
        at = rng.randrange(len(lines[i]) + 1)
        lines[i] = lines[i][:at] + rng.choice(NON_ASCII) + lines[i][at:]
        return "\n".join(lines).encode(op, errors="replace"), f"{op}@{i}:{at}"
    if op == "bom":
        return b"\xef\xbb\xbf" + data, op
    if op == "crlf":
        return data.replace(b"\n", b"\r\n"), op
    if op == "cr":
        return data.replace(b"\n", b"\r"), op
    return text.encode(op), op


# ------------------------------------------------------------------ table-level (binary)

SPECIAL_FLOATS = (
    float("nan"), float("inf"), float("-inf"), 1e308, -1e308, 0.0, -0.0, 5e-324, 1e15, -1.0,
)  # fmt: skip


def _table_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    table = ctx.table
    if table is None or table.num_columns == 0:
        return _flips(rng, data, ctx)
    op = rng.choice(
        ["cell", "cell", "null", "drop", "rename", "unit", "empty", "one", "reverse", "repeat",
         "cast", "meta"]
    )  # fmt: skip
    i = rng.randrange(table.num_columns)
    name = table.column_names[i]
    col = table.column(i)
    new = table
    what = f"table-{op} {name}"
    if op in ("cell", "null") and table.num_rows:
        row = rng.randrange(table.num_rows)
        values = col.to_pylist()
        if op == "null":
            values[row] = None
        elif pa.types.is_floating(col.type):
            values[row] = rng.choice(SPECIAL_FLOATS)
        elif pa.types.is_integer(col.type):
            values[row] = rng.choice([-1, 2**62, 0, -(2**63)])
        else:
            values[row] = rng.choice(["", "x" * 100, "NaN", "é"])
        kept = table.schema.field(i).with_nullable(True)
        new = table.set_column(i, kept, pa.array(values, col.type))
        what += f"[{row}]={values[row]!r}"
    elif op == "drop":
        new = table.remove_column(i)
    elif op == "rename":
        names = list(table.column_names)
        names[i] = rng.choice(["MD", "x", "", "inc", "time", name + " ", "azi"])
        new = table.rename_columns(names)
        what += f"->{names[i]!r}"
    elif op == "unit":
        unit = rng.choice(UNITS)
        meta = dict(table.schema.field(i).metadata or {})
        meta[UNIT_KEY] = unit.encode()
        new = table.set_column(i, table.schema.field(i).with_metadata(meta), col)
        what += f"->{unit!r}"
    elif op == "empty":
        new = table.slice(0, 0)
    elif op == "one":
        new = table.slice(0, 1)
    elif op == "reverse":
        new = table.take(pa.array(range(table.num_rows - 1, -1, -1), pa.int64()))
    elif op == "repeat":
        new = pa.concat_tables([table, table])
    elif op == "cast":
        target = rng.choice([pa.string(), pa.float32(), pa.int32(), pa.float64()])
        try:
            cast = col.cast(target, safe=False)
        except (pa.ArrowException, ValueError):
            return _flips(rng, data, ctx)
        new = table.set_column(
            i, pa.field(name, target, metadata=table.schema.field(i).metadata), cast
        )
        what += f"->{target}"
    else:
        meta = dict(table.schema.metadata or {})
        key = rng.choice([*meta, WELL_KEY] if meta else [WELL_KEY])
        meta[key] = rng.choice(
            [b"", b"{", b"null", b"[]", b'{"latitude": "x"}', b'{"latitude": NaN}',
             b'{"bogus": 1}', rng.randbytes(20), b'{"north_reference": "up"}']
        )  # fmt: skip
        new = table.replace_schema_metadata(meta)
        what = f"table-meta {key!r}={meta[key]!r}"
    written = ctx.rewrite(new)
    if written is None:  # the writer refused the table: keep the bytes as they were
        return data, what + " (writer refused)"
    ctx.table = new
    return written, what


# ------------------------------------------------------------------ message-level (MCAP)

JSON_VALUES: tuple[Any, ...] = (
    None, "9.8", [1, 2], {"x": 1}, True, float("nan"), float("inf"), 10**400, -1e308, "", 0,
)  # fmt: skip


def _mcap_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    """Re-write the MCAP file with one message, message time or metadata record changed,
    its CRCs intact: the reader's checks past the CRCs (message decoding) are reached."""
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    try:
        reader = make_reader(io.BytesIO(data))
        messages = list(reader.iter_messages())
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    except Exception:  # already broken by another mutation: start from the seed
        reader = make_reader(io.BytesIO(ctx.seed.data))
        messages = list(reader.iter_messages())
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    if not messages:
        return _flips(rng, data, ctx)
    rows = [
        [schema, channel, m.log_time, m.publish_time, m.data] for schema, channel, m in messages
    ]
    i = rng.randrange(len(rows))
    op = rng.choice(["cut", "cut", "flip", "empty", "json", "drop", "repeat", "time", "meta"])
    payload = rows[i][4]
    if op == "cut":
        rows[i][4] = payload[: rng.randrange(len(payload) + 1)]
    elif op == "flip" and payload:
        at = rng.randrange(len(payload))
        rows[i][4] = payload[:at] + bytes([rng.randrange(256)]) + payload[at + 1 :]
    elif op == "empty":
        rows[i][4] = b""
    elif op == "json":
        try:
            message = json.loads(payload)
            key = rng.choice(sorted(message))
        except (ValueError, TypeError, IndexError):  # not a JSON object: a binary payload
            rows[i][4] = rng.choice([b"{", b"[1, 2]", b"null", b'{"t": "x"}'])
        else:
            if rng.random() < 0.25:
                del message[key]
            else:
                message[key if rng.random() < 0.8 else "extra"] = rng.choice(JSON_VALUES)
            rows[i][4] = json.dumps(message).encode()
    elif op == "drop":
        del rows[i]
    elif op == "repeat":
        rows.insert(i, list(rows[i]))
    elif op == "time":
        rows[i][2] = rng.choice([0, rows[0][2], rows[-1][2] + 1, 2**63 - 1, max(rows[i][2] - 1, 0)])
    elif metadata:
        j = rng.randrange(len(metadata))
        name, values = metadata[j]
        if values:
            values[rng.choice(sorted(values))] = rng.choice(["", "x", "nan", "{", "1e999", "-1"])
    out = io.BytesIO()
    writer = Writer(out, compression=CompressionType.NONE, enable_data_crcs=True)
    writer.start()
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    for schema, channel, *_ in rows:
        if schema is not None and schema.id not in schemas:
            schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
        if channel.id not in channels:
            channels[channel.id] = writer.register_channel(
                channel.topic,
                channel.message_encoding,
                schemas.get(channel.schema_id, 0),
                dict(channel.metadata),
            )
    for name, values in metadata:
        writer.add_metadata(name, values)
    for n, (_, channel, log_time, publish_time, payload) in enumerate(rows):
        writer.add_message(channels[channel.id], log_time, payload, publish_time, n)
    writer.finish()
    return out.getvalue(), f"mcap-{op}@message {i}"


# ------------------------------------------------------------------------- YAML, manifest

YAML_VALUE = re.compile(rb"^(\s*(?:-\s+)?[\w.-]+:[ \t]+)([^#\n]*?)([ \t]*(?:#.*)?)$", re.M)
YAML_KEY = re.compile(rb"^(\s*(?:-\s+)?)([\w.-]+)(:)", re.M)


def _yaml_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    values = list(YAML_VALUE.finditer(data))
    keys = list(YAML_KEY.finditer(data))
    op = rng.choice(
        ["value", "value", "value", "tag", "alias", "bomb", "key", "indent", "tab", "nest",
         "dup", "doc", "merge", "undefined"]
    )  # fmt: skip
    if op in ("value", "tag", "alias", "merge", "undefined", "nest") and values:
        m = rng.choice(values)
        if op == "value":
            new = rng.choice(YAML_SCALARS)
        elif op == "tag":
            new = rng.choice(YAML_TAGS)
        elif op == "nest":
            depth = rng.choice([20, 200, 2000])
            new = "[" * depth + "1" + "]" * depth
        elif op == "undefined":
            new = "*nowhere"
        else:  # anchor this value, alias it from another
            other = rng.choice(values)
            if other.start() == m.start():
                return data, "alias (one value)"
            a, b = sorted([m, other], key=lambda x: x.start())
            anchored = a.group(1) + b"&fz " + a.group(2) + a.group(3)
            alias = b.group(1) + (b"*fz" if op == "alias" else b"{<<: *fz}") + b.group(3)
            data = (
                data[: a.start()] + anchored + data[a.end() : b.start()] + alias + data[b.end() :]
            )
            return data, f"yaml-{op}@{a.start()}->{b.start()}"
        line = m.group(1) + new.encode("utf-8") + m.group(3)
        return data[: m.start()] + line + data[m.end() :], f"yaml-{op}@{m.start()}={new[:40]!r}"
    if op == "bomb":
        levels = rng.choice([3, 6, 9])
        bomb = ["fz0: &fz0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
        bomb += [f"fz{i}: &fz{i} [{', '.join([f'*fz{i - 1}'] * 9)}]" for i in range(1, levels)]
        return ("\n".join(bomb) + "\n").encode() + data, f"yaml-bomb{levels}"
    if op == "key" and keys:
        m = rng.choice(keys)
        key = bytearray(m.group(2))
        at = rng.randrange(len(key) + 1)
        if rng.random() < 0.5 and key:
            del key[min(at, len(key) - 1)]
        else:
            key[at:at] = bytes([rng.choice(b"abcxyz_-.0")])
        line = m.group(1) + bytes(key) + m.group(3)
        return data[: m.start()] + line + data[m.end() :], f"yaml-key@{m.start()}={bytes(key)!r}"
    lines = _lines(data)
    i = rng.randrange(len(lines))
    if op == "indent":
        lines[i] = lines[i][2:] if rng.random() < 0.5 else b"  " + lines[i]
    elif op == "tab":
        lines[i] = b"\t" + lines[i].lstrip(b" ")
    elif op == "dup":
        lines.insert(i, lines[i])
    elif op == "doc":
        lines.insert(i, rng.choice([b"---", b"...", b"%YAML 1.1", b"%TAG ! tag:x,2000:"]))
    else:
        return _line_op(rng, data, ctx)
    return b"\n".join(lines), f"yaml-{op}@line {i + 1}"


def _hostile_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    """Replace the file by a hostile one of its kind (``hostile_inputs``: claims, nesting,
    huge tokens; issue 32)."""
    made, what = rng.choice(HOSTILE[ctx.kind.name])(rng)
    return made, f"hostile: {what}"


TWO_FAULTS = "two-faults"
"""An operation that makes two independent spec problems (the count reported is checked)."""


def _two_faults(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    uses = list(re.finditer(rb"^[ \t]*(?:-[ \t]+)?uses:[ \t]*\w+", data, re.M))
    if not uses:
        return _yaml_op(rng, data, ctx)
    m = rng.choice(uses)
    data = data[: m.end()] + b"_nope" + data[m.end() :]
    first = rng.choice([b"bogus_field: 1\n", b"version: [1]\n"])
    data = first + data if not data.startswith(b"version") else data + b"\nbogus_field: 1\n"
    ctx.notes.add(TWO_FAULTS)
    return data, f"{TWO_FAULTS}@{m.start()}"


def _manifest_op(rng: random.Random, data: bytes, ctx: Context) -> tuple[bytes, str]:
    lines = _lines(data)
    i = rng.randrange(len(lines))
    cells = lines[i].split(b",")
    op = rng.choice(["cell", "cell", "cell", "add", "drop", "quote"])
    j = rng.randrange(len(cells))
    if op == "cell":
        cells[j] = rng.choice(MANIFEST_CELLS).encode("utf-8")
    elif op == "add":
        cells.insert(j, rng.choice(MANIFEST_CELLS).encode("utf-8"))
    elif op == "drop" and len(cells) > 1:
        del cells[j]
    else:
        cells[j] = b'"' + cells[j]
    lines[i] = b",".join(cells)
    return b"\n".join(lines), f"manifest-{op}@{i + 1}:{j}"


OPS: dict[str, list[tuple[Op, int]]] = {
    "text": [
        (_byte_op, 6), (_flips, 1), (_line_op, 4), (_column_op, 2), (_number_op, 5),
        (_unit_op, 3), (_whole_op, 1), (_encoding_op, 2),
    ],
    "binary": [(_byte_op, 4), (_flips, 3), (_whole_op, 1), (_table_op, 6)],
    "yaml": [
        (_yaml_op, 10), (_byte_op, 3), (_line_op, 2), (_number_op, 2), (_whole_op, 1),
        (_encoding_op, 1),
    ],
    "manifest": [
        (_manifest_op, 8), (_byte_op, 3), (_line_op, 3), (_number_op, 1), (_whole_op, 1),
        (_encoding_op, 1),
    ],
}  # fmt: skip


# ----------------------------------------------------------------------------- the fuzzer


WALL_FACTOR = 6.0
"""A hang is judged by the CPU time the process spends (a loaded machine slows every input
alike); the wall-clock limit, ``WALL_FACTOR`` times the budget, catches a process that
waits without computing."""


@contextlib.contextmanager
def time_budget(seconds: float) -> Iterator[None]:
    """Raise :class:`Hang` in the running code after ``seconds`` of CPU time, or
    ``WALL_FACTOR × seconds`` of wall-clock time (main thread, POSIX)."""

    def expire(signum: int, frame: object) -> None:
        clock = "CPU" if signum == signal.SIGPROF else "wall-clock"
        limit = seconds if signum == signal.SIGPROF else seconds * WALL_FACTOR
        raise Hang(f"no answer within {limit:g} s of {clock} time")

    try:
        previous = [signal.signal(s, expire) for s in (signal.SIGPROF, signal.SIGALRM)]
    except (ValueError, AttributeError):  # not the main thread, or no such signals
        yield
        return
    signal.setitimer(signal.ITIMER_PROF, seconds)
    signal.setitimer(signal.ITIMER_REAL, seconds * WALL_FACTOR)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.setitimer(signal.ITIMER_REAL, 0)
        for s, handler in zip((signal.SIGPROF, signal.SIGALRM), previous, strict=True):
            signal.signal(s, handler)


class Fuzzer:
    """Seeds, mutations and runs of every input kind (see the module docstring)."""

    def __init__(self, work: Path, registry: Registry | None = None, budget: float = 10.0):
        self.work = work
        self.registry = registry or load_registry()
        self.budget = budget
        self.kinds = build_kinds(self.registry, work / "seeds")
        self.inputs = work / "inputs"
        self.inputs.mkdir(parents=True, exist_ok=True)
        self.faults = Faults(work / "faults", self.registry)
        stations = "stations-j-well.csv"  # the stations file of the stations plan
        (self.inputs / stations).write_bytes((work / "seeds" / stations).read_bytes())

    # -- making inputs

    def make(self, kind: InputKind, seed: int, index: int) -> tuple[bytes, Seed, Context]:
        """The ``index``-th input of ``kind`` for ``seed``: a seed file mutated 1 to 3
        times (the same bytes each time)."""
        rng = random.Random(f"{seed}/{kind.name}/{index}")
        source = rng.choice(kind.seeds)
        ctx = Context(kind, source, self._rewriter(kind), table=source.table)
        ops, weights = zip(*OPS.get(kind.family, OPS["text"]), strict=True)
        if kind.name == "pipeline":
            ops, weights = (*ops, _two_faults), (*weights, 1)
        if kind.name == "mcap":
            ops, weights = (*ops, _mcap_op), (*weights, 8)
        if kind.family == "fault":  # made by fuzz_faults: no byte-level mutations
            data, what = make_fault(kind.name, rng, source.data)
            ctx.notes.add(what)
            return data, source, ctx
        if kind.name in HOSTILE:
            ops, weights = (*ops, _hostile_op), (*weights, 1)
        data = source.data
        done = []
        for _ in range(rng.choice([1, 1, 1, 2, 2, 3])):
            op = rng.choices(ops, weights)[0]
            try:
                data, what = op(rng, data, ctx)
            except Exception as exc:  # a harness bug must not stop a long run: noted
                what = f"{op.__name__} failed: {type(exc).__name__}: {exc}"
            done.append(what)
        ctx.notes.update(done)
        return data, source, ctx

    def _rewriter(self, kind: InputKind) -> Callable[[pa.Table], bytes | None]:
        if kind.name == "parquet":

            def parquet(table: pa.Table) -> bytes | None:
                out = pa.BufferOutputStream()
                try:
                    pq.write_table(table, out)
                except pa.ArrowException:  # e.g. a null in a non-nullable field
                    return None
                return bytes(out.getvalue().to_pybytes())

            return parquet
        writer = self.registry.writers["mcap"][0]

        def mcap(table: pa.Table) -> bytes | None:
            path = self.work / "rewrite.mcap"
            try:
                writer.write(table, path, SIM_WELL)
            except Exception:  # the writer takes only tables it can hold
                return None
            return path.read_bytes()

        return mcap

    # -- running inputs

    def fuzz(self, kind: str, seed: int, count: int, start: int = 0) -> Iterator[Outcome]:
        """Outcomes of inputs ``start`` … ``start + count - 1`` of ``kind``."""
        spec = self.kinds[kind]
        for index in range(start, start + count):
            data, source, ctx = self.make(spec, seed, index)
            yield self.run(spec, index, data, source, ctx)

    def run(self, kind: InputKind, index: int, data: bytes, source: Seed, ctx: Context) -> Outcome:
        """Run one input and classify what it did."""
        path = self.inputs / f"fuzz-{kind.name}{kind.suffix}"
        path.write_bytes(data)
        started, cpu = time.perf_counter(), time.process_time()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                with time_budget(self.budget):
                    label, detail = self._run(kind, path, source, ctx, index)
            except Hang as exc:
                label, detail = HANG, str(exc)
            except Exception as exc:
                label, detail = classify(exc, path, kind, ctx)
        seconds, cpu = time.perf_counter() - started, time.process_time() - cpu
        if cpu > self.budget and label != HANG:
            label, detail = HANG, f"took {cpu:.1f} s of CPU time ({label}: {detail})"
        stray = tuple(
            f"{w.category.__name__}: {w.message}"
            for w in caught
            if not issubclass(w.category, InputFileWarning)
        )
        return Outcome(
            kind.name,
            index,
            label,
            detail,
            seconds,
            tuple(sorted(ctx.notes)),
            data,
            kind.suffix,
            stray,
        )

    def _run(
        self, kind: InputKind, path: Path, source: Seed, ctx: Context, index: int
    ) -> tuple[str, str]:
        if kind.family in ("text", "binary"):
            return self._run_table(kind, path, source, index)
        if kind.name == "pipeline":
            return self._run_pipeline(path, ctx)
        if kind.name == "plan":
            return self._run_plan(path)
        if kind.family == "fault":
            return self.faults.run(kind.name, path.read_bytes(), index)
        return self._run_manifest(path)

    def _run_table(self, kind: InputKind, path: Path, source: Seed, index: int) -> tuple[str, str]:
        expect = kind.expect or source.name  # a Parquet seed is named by its kind
        asked = expect if index % 2 or source.reader != "auto" else "auto"
        formats = TARGETS[asked] if asked != "auto" else ("csv", "parquet")
        target = self.work / f"out-{index // 2}.{formats[index // 2 % len(formats)]}"
        registry = self.registry
        done = convert(
            registry, path, target, kind=asked, reader=source.reader, options=source.options
        )
        problem = check_table(done.table, done.kind)
        if problem is not None:
            return problem
        seeded = set(source.table.column_names) if source.table is not None else set()
        if not _reads_back(done.table, done.kind, target.suffix, seeded):
            return self._downstream(done.table, done.kind)
        # what gyropipe wrote must read back as the same kind, as valid
        try:
            back, _, read_as = read_kind(
                registry, target, kind=done.kind, reader="auto", options={}
            )
        except GyropipeError as exc:
            return ROUNDTRIP, f"wrote {target.name} as {done.kind}; reading it back: {exc}"
        problem = check_table(back, read_as)
        if problem is not None:
            return ROUNDTRIP, f"read back from {target.name}: {problem[1]}"
        return self._downstream(done.table, done.kind)

    def _downstream(self, table: pa.Table, kind: str) -> tuple[str, str]:
        """Accepted stations (empty ones too) go on through minimum curvature, as in the
        survey pipeline."""
        rows = f"{kind}: {table.num_rows} rows"
        if kind != "stations":
            return ACCEPTED, rows
        from pipeline.api import functions

        try:
            functions.minimum_curvature(table, well=SIM_WELL)
        except StageError as exc:  # the stage raised: on purpose, or a crash
            cause = exc.__cause__
            if isinstance(cause, GyropipeError) or cause is None:
                return ACCEPTED, f"{rows}; minimum curvature refused: {first_line(exc)}"
            return TRACEBACK, describe(cause, f"minimum curvature of {rows}")
        except GyropipeError as exc:
            return ACCEPTED, f"{rows}; minimum curvature refused: {first_line(exc)}"
        return ACCEPTED, f"{rows}, integrated"

    def _run_pipeline(self, path: Path, ctx: Context) -> tuple[str, str]:
        from pipeline.graph import build_plan
        from pipeline.spec import load_spec

        try:
            plan = build_plan(load_spec(path), self.registry)
        except SpecError as exc:
            injected = re.compile(r"bogus_field|'version'|_nope")
            if (
                TWO_FAULTS in ctx.notes
                and len(exc.problems) == 1
                and injected.search(exc.problems[0].message)
                and not exc.problems[0].message.startswith("malformed YAML")
            ):  # one of two problems made on purpose reported, without the other (a
                # document another mutation made unparseable has only its syntax error)
                return PARTIAL, f"1 problem reported of 2: {exc.problems[0]}"
            return spec_outcome(exc, path)
        return ACCEPTED, f"pipeline {plan.spec.name!r}: {len(plan.stages)} stages"

    def _run_plan(self, path: Path) -> tuple[str, str]:
        from pipeline.sim.spec import load_simulation

        def read_stations(stations: Path, reader: str) -> pa.Table:
            return self.registry.read(stations, "stations", reader=reader)[0]

        try:
            spec = load_simulation(path, read_stations=read_stations)
        except SpecError as exc:
            return spec_outcome(exc, path)
        try:
            well = spec.path()
        except ValueError as exc:  # `gyropipe simulate` reports it as "error: PLAN: …"
            where = bool(re.search(r"sections\[\d+\]|stations", str(exc)))
            return (REFUSED if where else UNLOCATED), f"{path.name}: {exc}"
        arrays = {"md0": well.md0, "md1": well.md1, "r0": well.r0, "t0": well.t0}
        bad = [name for name, values in arrays.items() if not np.isfinite(values).all()]
        if bad:
            return NONFINITE, f"well path {', '.join(bad)} not finite"
        return ACCEPTED, f"plan {spec.name!r}: {len(well.md0)} arcs"

    def _run_manifest(self, path: Path) -> tuple[str, str]:
        from pipeline.batch.jobs import jobs_from_manifest

        jobs = jobs_from_manifest(path, MANIFEST_INPUTS, WellMetadata())
        for job in jobs:
            values = [v for v in (job.well.latitude, job.well.longitude) if v is not None]
            if not np.isfinite(values).all():
                return NONFINITE, f"well {job.well_id}: {job.well}"
        return ACCEPTED, f"{len(jobs)} wells"


# ------------------------------------------------------------------------ classification


def _reads_back(table: pa.Table, kind: str, suffix: str, seeded: set[str]) -> bool:
    """Whether the copy of ``table`` written to a ``suffix`` file must read back as ``kind``:
    not an empty table (legal, but the text readers want data rows), not a log in CSV (no
    CSV reader reads logs), not a survey table with columns neither in its contract nor in
    its seed (a Parquet column renamed ``MD`` or ``frame_angle ``: a text reader takes its
    header for a contract column's)."""
    if table.num_rows == 0 or (kind, suffix) == ("log", ".csv"):
        return False
    known = {c.name for c in CONTRACTS[kind].compiled().columns} | seeded
    known |= {"tvd", "north", "east", "dls", "source_line"}
    return kind == "log" or set(table.column_names) <= known


def first_line(exc: BaseException) -> str:
    return str(exc).split("\n", 1)[0]


def check_table(table: pa.Table, kind: str) -> tuple[str, str] | None:
    """None if ``table`` meets the contract of ``kind``, else the bad outcome."""
    contract = CONTRACTS[kind]
    for spec in contract.compiled().columns:
        if spec.finite and spec.name in table.column_names:
            col = table.column(spec.name)
            if pa.types.is_floating(col.type):
                values = col.fill_null(0.0).to_numpy()
                finite = np.isfinite(values)
                if spec.undefined_at_vertical:  # an azimuth no inclination defines: NaN
                    inc = table.column("inc").fill_null(90.0).to_numpy()
                    vertical = np.minimum(np.abs(inc), np.abs(180.0 - inc)) <= VERTICAL_TOLERANCE
                    finite |= np.isnan(values) & vertical
                if not finite.all():
                    return NONFINITE, f"{kind}: column {spec.name!r}: {values[~finite][:5]}…"
    try:
        contract.validate_table(table)
    except ContractViolation as exc:
        rules = {f.rule for f in exc.failures}
        return (NONFINITE if "finite" in rules else CONTRACT), f"{kind}: {exc}"
    return None


def located(message: str, path: Path) -> bool:
    return bool(LOCATED.search(message.replace(str(path), "")) or WHOLE_FILE.search(message))


def classify(
    exc: BaseException, path: Path, kind: InputKind, ctx: Context | None = None
) -> tuple[str, str]:
    """The outcome of an exception raised by one input (module docstring)."""
    text = str(exc)
    chain = [exc]
    while chain[-1].__cause__ is not None:
        chain.append(chain[-1].__cause__)
    innermost = chain[-1]
    frames = [f for e in chain for f in traceback.extract_tb(e.__traceback__)]
    if isinstance(exc, ValueError | GyropipeError) and any(
        "writer.write" in (f.line or "") for f in frames
    ):  # read, then refused by the writer of the output format: both files named?
        both = text.startswith(f"{path}: ") and "cannot be written to " in text
        return (UNWRITABLE if both else UNLOCATED), describe(exc)
    if isinstance(exc, ReaderError) or MASKED_CRASH.search(text):  # a reader's bug
        return TRACEBACK, describe(innermost, f"{type(exc).__name__}: {first_line(exc)}")
    if not isinstance(exc, GyropipeError):
        return TRACEBACK, describe(exc)
    if isinstance(exc, SpecError):
        return spec_outcome(exc, path)
    whole = isinstance(exc, WrongKindError)  # the whole file is another kind
    if path.name not in text or not (whole or located(text, path)):
        return UNLOCATED, f"{type(exc).__name__}: {text}"
    if "\n" in text and isinstance(exc, InputFileError):
        return MULTILINE, f"{type(exc).__name__}: {text}"
    return REFUSED, f"{type(exc).__name__}: {first_line(exc)}"


def spec_outcome(exc: SpecError, path: Path) -> tuple[str, str]:
    """A spec or plan error: refused if every problem names the file and a line (or is
    about the whole file)."""
    for problem in exc.problems:
        named = problem.location.file == str(path)
        if not named or not (problem.location.line or WHOLE_FILE.search(problem.message)):
            return UNLOCATED, f"{problem}"
    return REFUSED, f"{exc.problems[0]}"


def describe(exc: BaseException, head: str = "") -> str:
    """Exception type, message and the top frames of its traceback (innermost last)."""
    frames = traceback.extract_tb(exc.__traceback__)[-4:]
    where = " <- ".join(f"{Path(f.filename).name}:{f.lineno} {f.name}" for f in reversed(frames))
    return f"{head + ' / ' if head else ''}{type(exc).__name__}: {exc} [{where}]"


def summary(outcomes: list[Outcome]) -> dict[str, Counter[str]]:
    """Counts of each outcome per kind."""
    table: dict[str, Counter[str]] = {}
    for o in outcomes:
        table.setdefault(o.kind, Counter())[o.label] += 1
    return table


def format_table(counts: dict[str, Counter[str]]) -> str:
    """Counts per kind (rows) and outcome (columns; outcomes that occurred only), the total
    of the outcomes, then any other count (e.g. inputs that warned)."""
    used = [o for o in OUTCOMES if any(c[o] for c in counts.values())]
    other = sorted({k for c in counts.values() for k in c if k not in OUTCOMES})
    width = max([len(k) for k in counts] + [5])
    head = (
        f"{'kind':<{width}} "
        + " ".join(f"{o:>10}" for o in used)
        + f" {'total':>7}"
        + "".join(f" {o:>8}" for o in other)
    )
    rows = [head, "-" * len(head)]
    for kind, c in counts.items():
        rows.append(
            f"{kind:<{width}} "
            + " ".join(f"{c[o]:>10}" for o in used)
            + f" {sum(c[o] for o in OUTCOMES):>7}"
            + "".join(f" {c[o]:>8}" for o in other)
        )
    return "\n".join(rows)

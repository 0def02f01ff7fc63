"""The figures of one published well for the fleet page (:mod:`pipeline.batch.fleet_page`):
QC checks passed and failed and the stations dropped (recorded but not in the trajectory:
:mod:`pipeline.qc.dropped`), the acceptance gates, the worst clearance separation factor,
the drift rate applied (with its σ; a well that corrected none: its calibration's selected
estimates), TD and the largest dogleg severity.

The worker records them as it runs the well (:func:`run_figures`, into the ``batch.json``
it publishes with the run): from the run's persisted tables as they are in memory, whatever
format they were written in, each known by the columns its contract requires (so a
plugin's trajectory counts as one) — never a sample stream. TD and the largest DLS are
those of the trajectory the run's survey report states, by its own rule
(:func:`pipeline.survey.courses.max_dls` over its ``min_course_length``); a run without a
survey report gives the last persisted trajectory's by the report's default rule. A well
published before figures were recorded has them read back from its persisted Parquet tables
(a table's footer, then only the few columns a figure needs); tables persisted as CSV keep
no table metadata (a clearance rule, a file-position check), so figures are not guessed from
them: ``problems`` says so. A figure the well has no table for is None; a file that cannot
be read is named in ``problems`` and its figure stays None.
Tables are in the canonical units of their contracts (m, deg, deg/30m, deg/h).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pipeline import jsontext
from pipeline.anticollision.rule import LEVELS
from pipeline.anticollision.tables import Clearance, rule_of
from pipeline.batch.publish import of_ledger
from pipeline.contracts import TableContract
from pipeline.drift.correction import correction_rate, drift_rate_of
from pipeline.drift.tables import CalibrationResult, CorrectedFreeGyroReadings, InOutQc
from pipeline.graph import Plan
from pipeline.hashing import open_regular, regular_bytes
from pipeline.manifest import MANIFEST
from pipeline.qc.dropped import DROPPED_BY, REJECT_COLUMNS, Dropped, dropped_stations
from pipeline.qc.tables import QcResults, QcSummary
from pipeline.qc.verdict import INOUT_COLUMNS, QcTally, inout_checks, qc_tally
from pipeline.survey.courses import MIN_COURSE, max_dls
from pipeline.survey.crosscheck import position_check_of
from pipeline.survey.stations import survey_offsets
from pipeline.tables import CheckResults, Trajectory

from .publish import MARKER, output_on_disk

REPORT_SUFFIXES = (".html", ".pdf")
UNRECORDED = "unrecorded"
"""the DLS rule of figures an earlier version made (:attr:`WellFigures.dls_rule`)"""


@dataclass(frozen=True)
class Gate:
    """An acceptance gate as ``run.json`` records it."""

    name: str
    status: str
    """pass, fail or not evaluated"""
    description: str


@dataclass(frozen=True)
class WorstClearance:
    """The least separation factor of a well against its offset wells."""

    sf: float
    """-inf where it is undefined (the wells' σ outside their models' range)"""
    offset: str
    md: float
    """reference MD of the least SF, m"""
    level: str
    """the rule's worst level over the whole scan: pass, warn or fail"""


@dataclass(frozen=True)
class DriftFigure:
    """A drift rate, °/h: a calibration's selected estimate or the rate a free-gyro
    survey was corrected with, with its σ (None: a corrected survey written before its σ
    was recorded, its rate the slope of its correction)."""

    rate_deg_h: float
    sigma_deg_h: float | None
    instrument: str | None
    caveats: tuple[str, ...] = ()
    """where the calibration applied does not cover the survey, one sentence each"""


@dataclass(frozen=True)
class WellFigures:
    """What a well's published outputs say (module docstring)."""

    pipeline: str | None = None
    """pipeline name and version"""
    qc: QcTally | None = None
    gates: tuple[Gate, ...] | None = None
    clearance: WorstClearance | None = None
    drift: tuple[DriftFigure, ...] | None = None
    td_md: float | None = None
    """MD of the deepest station, m"""
    td_tvd: float | None = None
    """its TVD below the well's depth reference, m"""
    max_dls: float | None = None
    """the largest dogleg severity over the courses at least :attr:`dls_min_course` long,
    °/30 m"""
    dls_min_course: float = 0.0
    """m: the shortest course counted in :attr:`max_dls` (0: every course)"""
    dls_rule: str = UNRECORDED
    """where :attr:`dls_min_course` comes from: ``report`` (the run's survey report, whose
    maximum this is), ``default`` (no survey report: the report's default) or
    ``unrecorded`` (figures of an earlier version: read back from the tables by the
    default, or in the ledger over every course)"""
    reports: tuple[str, ...] = ()
    """the report files (HTML first), names in the well's directory"""
    missing: str | None = None
    """why there are no figures at all (no or a damaged ``run.json``)"""
    problems: tuple[str, ...] = ()
    """published files that could not be read"""


def figures_record(figures: WellFigures) -> dict[str, Any]:
    """``figures`` as JSON values (:func:`figures_of_record`); an undefined SF is -inf."""
    qc = figures.qc
    record = dataclasses.asdict(dataclasses.replace(figures, qc=None))
    if qc is not None:  # (asdict would count a Counter's items as keys)
        record["qc"] = {
            "evaluated": qc.evaluated,
            "failed": dict(qc.failed),
            "stations": sorted(qc.stations),
            "windows": qc.windows,
            "dropped": [dataclasses.asdict(d) for d in qc.dropped],
        }
    return record


def figures_json(figures: WellFigures) -> str:
    """``figures`` as JSON text (the ledger keeps a done run's, :func:`figures_of_json`);
    an undefined SF is ``-Infinity``."""
    return json.dumps(figures_record(figures), sort_keys=True, separators=(",", ":"))


def figures_of_json(text: str) -> WellFigures | None:
    """The figures :func:`figures_json` wrote; None where the text is not such a record."""
    try:
        return figures_of_record(json.loads(text))
    except ValueError:
        return None


def figures_of_record(record: Any) -> WellFigures | None:
    """The figures :func:`figures_record` made; None where ``record`` is not such a record.
    A record of an earlier version (no DLS rule, no drift σ of a corrected survey) reads
    as what it was computed by: DLS over every course, σ None."""
    try:
        qc, gates, worst, drift = (record.get(k) for k in ("qc", "gates", "clearance", "drift"))
        figures = WellFigures(
            pipeline=record["pipeline"],
            qc=None
            if qc is None
            else QcTally(
                qc["evaluated"],
                Counter(qc["failed"]),
                set(qc["stations"]),
                qc["windows"],
                [_dropped(d) for d in qc.get("dropped", ())],
            ),
            gates=None if gates is None else tuple(Gate(**g) for g in gates),
            clearance=None if worst is None else WorstClearance(**worst),
            drift=None
            if drift is None
            else tuple(DriftFigure(**{**d, "caveats": tuple(d.get("caveats", ()))}) for d in drift),
            td_md=record["td_md"],
            td_tvd=record["td_tvd"],
            max_dls=record["max_dls"],
            dls_min_course=float(record.get("dls_min_course", 0.0)),
            dls_rule=str(record.get("dls_rule", UNRECORDED)),
            reports=tuple(record["reports"]),
            missing=record["missing"],
            problems=tuple(record["problems"]),
        )
    except (ValueError, TypeError, KeyError, AttributeError):
        return None
    return figures if _well_typed(figures) else None


def _dropped(record: Mapping[str, Any]) -> Dropped:
    """A station dropped as :func:`figures_record` wrote it (its checks a list: a text's
    letters are no check names)."""
    checks = record.get("checks", [])
    if not isinstance(checks, list):
        raise TypeError(f"checks {checks!r}: expected a list of check names")
    return Dropped(**{**record, "checks": tuple(checks)})


def _well_typed(figures: WellFigures) -> bool:
    """Whether the numbers of ``figures`` are numbers (its QC counts and station indices
    integers ≥ 0, its dropped stations' MDs finite), its texts text, what dropped a station one of
    :data:`~pipeline.qc.dropped.DROPPED_BY`, its clearance level one of the rule's and its
    reports plain file names of the well's directory (a record read from a file could hold
    anything: the page shows these, and links the reports)."""
    numbers: list[object] = [figures.td_md, figures.td_tvd, figures.max_dls]
    texts: list[object] = [*figures.reports, *figures.problems]
    optional: list[object] = [figures.pipeline, figures.missing]
    if figures.clearance is not None:
        numbers += [figures.clearance.sf, figures.clearance.md]
        texts += [figures.clearance.offset, figures.clearance.level]
    numbers += [x for d in figures.drift or () for x in (d.rate_deg_h, d.sigma_deg_h)]
    optional += [d.instrument for d in figures.drift or ()]
    texts += [t for g in figures.gates or () for t in (g.name, g.status, g.description)]
    counts: list[object] = []
    mds: list[object] = []
    if figures.qc is not None:
        qc = figures.qc
        counts += [qc.evaluated, qc.windows, *qc.failed.values()]
        counts += [d.station for d in qc.dropped]
        texts += list(qc.failed)
        numbers += list(qc.stations)
        mds += [d.md for d in qc.dropped]
        texts += [t for d in qc.dropped for t in (d.reason, *d.checks)]
        if not all(d.by in DROPPED_BY for d in qc.dropped):
            return False
    return (
        all(n is None or (isinstance(n, int | float) and not isinstance(n, bool)) for n in numbers)
        and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in counts)
        and all(_finite(m) for m in mds)
        and all(isinstance(t, str) for t in texts)
        and all(t is None or isinstance(t, str) for t in optional)
        and (figures.clearance is None or figures.clearance.level in LEVELS)
        and all(_report_name(name) for name in figures.reports)
    )


def _finite(value: object) -> bool:
    """Whether ``value`` is a finite number (not a bool)."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _report_name(name: str) -> bool:
    """Whether ``name`` is a report file's name in a well's directory (not a path)."""
    return name.endswith(REPORT_SUFFIXES) and "/" not in name and "\\" not in name


def required(contract: type[TableContract]) -> frozenset[str]:
    """The columns every table of ``contract`` has."""
    return frozenset(c.name for c in contract.compiled().columns if c.required)


TRAJECTORY = required(Trajectory)
CHECKS = (required(CheckResults), required(QcResults))
CLEARANCE = required(Clearance)
CALIBRATION = required(CalibrationResult)
CORRECTED = required(CorrectedFreeGyroReadings)
INOUT = required(InOutQc)
SUMMARY = required(QcSummary)
RATE_COLUMNS = frozenset({"drift_rate", "sigma_drift_rate"})
"""the columns of a corrected survey that record its drift rate and σ"""


def run_figures(
    plan: Plan, tables: Mapping[tuple[str, str], pa.Table], manifest: Mapping[str, Any], at: Path
) -> WellFigures:
    """The figures of a run as it ends (module docstring): ``tables``, its stage outputs by
    (stage id, port); ``manifest``, its ``run.json``; ``at``, the directory its files are
    in (the report files are looked for there)."""
    reports = [  # survey reports: a trajectory stated by a minimum course length
        (st, float(shortest))
        for st in plan.stages
        if "trajectory" in st.wiring
        and isinstance(shortest := getattr(st.params, "min_course_length", None), int | float)
    ]
    if reports:
        report, min_course = reports[-1]
        reader = _Tables([], min_course, "report")
    else:
        reader = _Tables([], MIN_COURSE, "default")
    for st in plan.stages:
        for port in st.persist:
            if port not in st.definition.streamed_outputs:
                table = tables[(st.id, port)]
                reader.take(set(table.column_names), table.select)
    if reports:  # TD and DLS as the report states them
        reader.td_dls(tables[report.wiring["trajectory"]])
    return reader.figures(manifest, at)


def well_figures(
    well_dir: Path,
    run_id: int | None = None,
    manifest: Mapping[str, Any] | None = None,
    ledger_id: str | None = None,
) -> WellFigures:
    """The figures of the run published in ``well_dir`` (module docstring): those its worker
    recorded (an output no longer on disk as the run wrote it told in ``problems``), else
    read from its persisted Parquet tables; with ``run_id``, a published run of another id
    — or, with ``ledger_id``, another ledger's run of that id (a ``batch.json`` naming no
    ledger is known by its run id alone) — is told in ``problems``. ``manifest``: the
    published run's ``run.json`` where the caller holds it, else it is read."""
    problems: list[str] = []
    if manifest is None:
        manifest, missing = _manifest(well_dir)
        if manifest is None:
            return WellFigures(missing=missing)
    marker = _marker(well_dir)
    if run_id is not None:
        marked = marker.get("run_id")
        marked = marked if isinstance(marked, int) else None
        ledger = marker.get("ledger_id")
        if marked != run_id:
            problems.append(f"the outputs published are of run {marked}, not run {run_id}")
        elif ledger_id is not None and not of_ledger(ledger, ledger_id):
            problems.append(
                f"the outputs published are of run {marked} of another ledger ({ledger}), "
                f"not this ledger's run {run_id}"
            )
    recorded = figures_of_record(marker.get("figures"))
    if recorded is not None:
        problems += _not_as_run(well_dir, manifest)
        return dataclasses.replace(recorded, problems=(*recorded.problems, *problems))
    if marker.get("figures") is not None:
        problems.append(f"{MARKER}: the figures recorded are damaged (read from the tables)")
    reader = _Tables(problems, MIN_COURSE, UNRECORDED)
    for name in _outputs(manifest):
        if name.endswith(".parquet"):
            reader.read(well_dir, name)
    if unread := _persisted_csv(manifest):
        problems.append(
            f"figures not recorded by the version that ran it, and its tables are CSV, "
            f"which keep no table metadata (a clearance rule, a file-position check): not "
            f"read ({', '.join(unread)}); run the well again to show them"
        )
    return reader.figures(manifest, well_dir)


class _Tables:
    """The persisted tables of one well, taken one by one into its figures; TD and the
    largest DLS over courses at least ``min_course`` m (``rule``: its source,
    :attr:`WellFigures.dls_rule`)."""

    def __init__(self, problems: list[str], min_course: float, rule: str) -> None:
        self.problems = problems
        self.min_course = min_course
        self.rule = rule
        self.checks: list[pa.Table] = []
        self.dropping: list[pa.Table] = []
        """validity summaries and compassing rejects: the stations the run dropped"""
        self.others: list[tuple[str, int, list[float]]] = []
        """checks recorded otherwise: a stations file's positions, in-run/out-run QC"""
        self.clearance: WorstClearance | None = None
        self.drift: list[DriftFigure] = []
        """the rates drift-corrected readings were corrected with"""
        self.calibrated: list[DriftFigure] = []
        """the selected estimates of calibration results (shown where none was applied:
        beside a rate applied, another instrument's would read as one)"""
        self.td_md: float | None = None
        self.td_tvd: float | None = None
        self.max_dls: float | None = None

    def figures(self, manifest: Mapping[str, Any], at: Path) -> WellFigures:
        """The figures of the tables taken, with what ``manifest`` says (``at``: where the
        report files are)."""
        problems = self.problems
        qc = qc_tally(self.checks, self.others, dropped_stations(self.dropping))
        return WellFigures(
            pipeline=_pipeline(manifest),
            qc=qc if qc.evaluated or qc.dropped else None,
            gates=_gates(manifest, problems),
            clearance=self.clearance,
            drift=tuple(self.drift or self.calibrated) or None,
            td_md=self.td_md,
            td_tvd=self.td_tvd,
            max_dls=self.max_dls,
            dls_min_course=self.min_course,
            dls_rule=self.rule,
            reports=_reports(at, _outputs(manifest)),
            problems=tuple(problems),
        )

    def read(self, well_dir: Path, name: str) -> None:
        """A persisted Parquet table: its footer, then the columns its figure needs."""
        try:
            # opened only if a regular file (a FIFO would block); closed here, not at GC
            with open_regular(well_dir / name) as fh, pq.ParquetFile(fh) as file:
                self.take(set(file.schema_arrow.names), lambda c: file.read(columns=c))
        except FileNotFoundError:
            self.problems.append(f"{name} is missing")
        except (OSError, pa.ArrowException, ValueError, KeyError, TypeError) as exc:
            reason = " ".join(str(exc).split())[:160]
            self.problems.append(f"{name} cannot be read ({reason})")

    def take(self, names: set[str], read: Callable[[list[str]], pa.Table]) -> None:
        """A table of columns ``names``, known by the columns its contract requires, into
        its figure; ``read(columns)`` gives those columns of it."""
        if names >= TRAJECTORY:
            self._trajectory(read(["md", "tvd", "dls", *({"survey"} & names)]))
        elif any(names >= kind for kind in CHECKS):
            self.checks.append(read(["check", "passed", "md"]))
        elif names >= CLEARANCE:
            columns = ["offset", "md", "sf", "sf_between", "md_between", "level"]
            self._clearance(read(columns))
        elif names >= CALIBRATION:
            columns = ["instrument", "drift_deg_h", "sigma_deg_h", "selected"]
            self._calibration(read(columns))
        elif names >= INOUT:
            self.others.extend(inout_checks(read(INOUT_COLUMNS)))
        elif names >= CORRECTED:
            self._corrected(read(["time", "correction", *(RATE_COLUMNS & names)]))
        elif names >= SUMMARY or names >= REJECT_COLUMNS:
            table = read(sorted(SUMMARY if names >= SUMMARY else REJECT_COLUMNS))
            dropped_stations([table])  # a row no such table holds: ValueError, a problem
            self.dropping.append(table)

    def _trajectory(self, table: pa.Table) -> None:
        """The last trajectory persisted gives TD and the largest DLS (a later stage's is
        the same survey with more columns); each file-position check is counted once."""
        self.td_dls(table)
        check = position_check_of(table)
        if check is not None:
            entry = ("file_positions", check.compared, list(check.beyond_md))
            if entry not in self.others:
                self.others.append(entry)

    def td_dls(self, table: pa.Table) -> None:
        """TD and the largest DLS of a trajectory (:func:`~pipeline.survey.courses.max_dls`
        over courses at least ``min_course`` m)."""
        md, tvd, dls = (_floats(table, c) for c in ("md", "tvd", "dls"))
        if len(md):
            deepest = int(np.nanargmax(md)) if np.isfinite(md).any() else len(md) - 1
            self.td_md, self.td_tvd = _number(md[deepest]), _number(tvd[deepest])
            offsets = tuple(int(o) for o in survey_offsets(table))
            found = max_dls(md, dls, offsets, self.min_course)
            self.max_dls = None if found is None else found.dls

    def _corrected(self, table: pa.Table) -> None:
        """A drift-corrected survey: the rate and σ it was corrected with; one written
        before they were recorded, the slope of its correction (σ None)."""
        if set(table.column_names) >= RATE_COLUMNS and table.num_rows:
            rate, sigma = (_floats(table, c)[0] for c in ("drift_rate", "sigma_drift_rate"))
            applied = drift_rate_of(table)  # (None: readings corrected before it was recorded)
            instrument, caveats = (
                (None, ()) if applied is None else (applied.instrument, applied.caveats)
            )
            self.drift.append(DriftFigure(float(rate), float(sigma), instrument, caveats))
            return
        rate = correction_rate(_floats(table, "time"), _floats(table, "correction"))
        if math.isfinite(rate):
            self.drift.append(DriftFigure(rate, None, None))

    def _clearance(self, table: pa.Table) -> None:
        """The least SF the rule decides on (``sf_between`` on courses, the default; ``sf``
        at stations), undefined counting as the least, over every clearance table."""
        if not table.num_rows:
            return
        on_course = rule_of(table).get("level_on", "course") == "course"
        sf = _floats(table, "sf_between" if on_course else "sf")
        md = _floats(table, "md_between" if on_course else "md")
        decided = np.where(np.isnan(sf), -np.inf, sf)
        k = int(np.argmin(decided))
        levels = [lv for lv in table.column("level").unique().to_pylist() if lv in LEVELS]
        level = max(levels, key=LEVELS.index) if levels else "fail"
        offset = str(table.column("offset")[k].as_py())
        found = WorstClearance(float(decided[k]), offset, float(md[k]), level)
        if self.clearance is None or found.sf < self.clearance.sf:
            self.clearance = found

    def _calibration(self, table: pa.Table) -> None:
        for row in table.to_pylist():
            if row["selected"]:
                self.calibrated.append(
                    DriftFigure(row["drift_deg_h"], row["sigma_deg_h"], row["instrument"])
                )


def _manifest(well_dir: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The well's ``run.json``, or why there is none to read."""
    path = well_dir / MANIFEST
    try:
        manifest = jsontext.loads(regular_bytes(path))
    except FileNotFoundError:
        return None, f"no published outputs ({MANIFEST} missing)"
    except OSError as exc:
        return None, f"{MANIFEST} cannot be read ({exc.strerror or exc})"
    except ValueError:
        return None, f"{MANIFEST} is damaged (not JSON)"
    if not isinstance(manifest, dict) or not isinstance(manifest.get("outputs"), list):
        return None, f"{MANIFEST} is damaged (no list of outputs)"
    return manifest, None


def _marker(well_dir: Path) -> dict[str, Any]:
    """The well's ``batch.json`` ({} where it cannot be read or is not an object)."""
    try:
        marker = jsontext.loads(regular_bytes(well_dir / MARKER))
    except (OSError, ValueError):
        return {}
    return marker if isinstance(marker, dict) else {}


def _pipeline(manifest: Mapping[str, Any]) -> str | None:
    pipeline = manifest.get("pipeline")
    if not isinstance(pipeline, Mapping) or not isinstance(pipeline.get("name"), str):
        return None
    version = pipeline.get("version")
    return f"{pipeline['name']} {version}" if isinstance(version, str) else pipeline["name"]


def _gates(manifest: Mapping[str, Any], problems: list[str]) -> tuple[Gate, ...] | None:
    acceptance = manifest.get("acceptance")
    if acceptance is None:
        return None
    try:
        return tuple(
            Gate(str(g["gate"]), str(g["status"]), str(g.get("description") or ""))
            for g in acceptance["gates"]
        )
    except (KeyError, TypeError, AttributeError):
        problems.append(f"{MANIFEST}: the acceptance gates are damaged")
        return None


def _outputs(manifest: Mapping[str, Any]) -> list[str]:
    """The names of the files ``run.json`` lists in the well's directory."""
    names = (e.get("file") if isinstance(e, Mapping) else None for e in manifest["outputs"])
    return [n for n in names if isinstance(n, str) and "/" not in n]


def _persisted_csv(manifest: Mapping[str, Any]) -> list[str]:
    """The outputs ``run.json`` lists that are stage tables persisted as CSV: named
    ``<stage>.<port>.csv`` for a port the stage's record counts rows of."""
    stages = manifest.get("stages")
    ports = set()
    for record in stages if isinstance(stages, list) else ():
        if isinstance(record, Mapping) and isinstance(record.get("rows_out"), Mapping):
            ports |= {f"{record.get('id')}.{port}.csv" for port in record["rows_out"]}
    return [name for name in _outputs(manifest) if name in ports]


def _not_as_run(well_dir: Path, manifest: Mapping[str, Any]) -> list[str]:
    """The outputs ``run.json`` lists that are no longer on disk as the run wrote them (a
    stat each: the figures recorded are the run's, these files no longer all show them)."""
    found = []
    for entry in manifest["outputs"]:
        name = entry.get("file") if isinstance(entry, Mapping) else None
        if not isinstance(name, str) or output_on_disk(well_dir, entry):
            continue
        gone = not (well_dir / name).exists()
        found.append(f"{name} is {'missing' if gone else 'not as the run wrote it (its size)'}")
    return found


def _reports(well_dir: Path, outputs: list[str]) -> tuple[str, ...]:
    """The report files among ``outputs`` that are on disk, HTML before PDF."""
    names = [n for n in outputs if n.endswith(REPORT_SUFFIXES) and (well_dir / n).is_file()]
    return tuple(sorted(names, key=lambda n: (REPORT_SUFFIXES.index(Path(n).suffix), n)))


def _floats(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=float)


def _number(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None

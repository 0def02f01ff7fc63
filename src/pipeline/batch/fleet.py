"""The figures of one published well for the fleet page (:mod:`pipeline.batch.fleet_page`):
QC checks passed and failed, the acceptance gates, the worst clearance separation factor,
the drift rate, TD and the largest dogleg severity.

They come from the well's ``run.json`` and its persisted Parquet tables, each known by the
columns its contract requires (so a plugin's trajectory counts as one): a table's footer is
read, then only the few columns a figure needs — never a sample stream. A figure the well
has no table for is None; a file that cannot be read is named in ``problems`` and its figure
stays None. Persisted tables are in the canonical units of their contracts (m, deg,
deg/30m, deg/h).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pipeline import jsontext
from pipeline.anticollision.rule import LEVELS
from pipeline.anticollision.tables import Clearance, rule_of
from pipeline.contracts import TableContract
from pipeline.drift.correction import correction_rate
from pipeline.drift.tables import CalibrationResult, CorrectedFreeGyroReadings
from pipeline.qc.tables import QcResults
from pipeline.qc.verdict import QcTally, qc_tally
from pipeline.runner import MANIFEST
from pipeline.survey.crosscheck import position_check_of
from pipeline.tables import CheckResults, Trajectory

from .publish import MARKER

REPORT_SUFFIXES = (".html", ".pdf")


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
    """A drift rate, °/h: a calibration's selected estimate (with its σ) or the rate at
    which a free-gyro survey's drift correction grows (σ None)."""

    rate_deg_h: float
    sigma_deg_h: float | None
    instrument: str | None


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
    """the largest dogleg severity over every course (short ones too), °/30 m"""
    reports: tuple[str, ...] = ()
    """the report files (HTML first), names in the well's directory"""
    missing: str | None = None
    """why there are no figures at all (no or a damaged ``run.json``)"""
    problems: tuple[str, ...] = ()
    """published files that could not be read"""


def figures_json(figures: WellFigures) -> str:
    """``figures`` as JSON text (the ledger keeps a done run's, :func:`figures_of_json`);
    an undefined SF is ``-Infinity``."""
    qc = figures.qc
    record = dataclasses.asdict(dataclasses.replace(figures, qc=None))
    if qc is not None:  # (asdict would count a Counter's items as keys)
        record["qc"] = {
            "evaluated": qc.evaluated,
            "failed": dict(qc.failed),
            "stations": sorted(qc.stations),
            "windows": qc.windows,
        }
    return json.dumps(record, sort_keys=True, separators=(",", ":"))


def figures_of_json(text: str) -> WellFigures | None:
    """The figures :func:`figures_json` wrote; None where the text is not such a record."""
    try:
        record = json.loads(text)
        qc, gates, worst, drift = (record.get(k) for k in ("qc", "gates", "clearance", "drift"))
        return WellFigures(
            pipeline=record["pipeline"],
            qc=None
            if qc is None
            else QcTally(
                qc["evaluated"], Counter(qc["failed"]), set(qc["stations"]), qc["windows"]
            ),
            gates=None if gates is None else tuple(Gate(**g) for g in gates),
            clearance=None if worst is None else WorstClearance(**worst),
            drift=None if drift is None else tuple(DriftFigure(**d) for d in drift),
            td_md=record["td_md"],
            td_tvd=record["td_tvd"],
            max_dls=record["max_dls"],
            reports=tuple(record["reports"]),
            missing=record["missing"],
            problems=tuple(record["problems"]),
        )
    except (ValueError, TypeError, KeyError, AttributeError):
        return None


def required(contract: type[TableContract]) -> frozenset[str]:
    """The columns every table of ``contract`` has."""
    return frozenset(c.name for c in contract.compiled().columns if c.required)


TRAJECTORY = required(Trajectory)
CHECKS = (required(CheckResults), required(QcResults))
CLEARANCE = required(Clearance)
CALIBRATION = required(CalibrationResult)
CORRECTED = required(CorrectedFreeGyroReadings)


def well_figures(
    well_dir: Path, run_id: int | None = None, manifest: Mapping[str, Any] | None = None
) -> WellFigures:
    """The figures of the run published in ``well_dir`` (module docstring); with
    ``run_id``, a published run of another id is told in ``problems``. ``manifest``: the
    published run's ``run.json`` where the caller holds it (the worker that published it),
    else it is read."""
    problems: list[str] = []
    if manifest is None:
        manifest, missing = _manifest(well_dir)
        if manifest is None:
            return WellFigures(missing=missing)
    if run_id is not None:
        marked = _marked_run(well_dir)
        if marked != run_id:
            problems.append(f"the outputs published are of run {marked}, not run {run_id}")
    outputs = _outputs(manifest)
    reader = _Tables(well_dir, problems)
    for name in outputs:
        if name.endswith(".parquet"):
            reader.read(name)
    qc = qc_tally(reader.checks, reader.positions)
    return WellFigures(
        pipeline=_pipeline(manifest),
        qc=qc if qc.evaluated else None,
        gates=_gates(manifest, problems),
        clearance=reader.clearance,
        drift=tuple(reader.drift) if reader.drift else None,
        td_md=reader.td_md,
        td_tvd=reader.td_tvd,
        max_dls=reader.max_dls,
        reports=_reports(well_dir, outputs),
        problems=tuple(problems),
    )


class _Tables:
    """The persisted tables of one well, read one by one into its figures."""

    def __init__(self, well_dir: Path, problems: list[str]) -> None:
        self.well_dir = well_dir
        self.problems = problems
        self.checks: list[pa.Table] = []
        self.positions: list[tuple[str, int, list[float]]] = []
        self.clearance: WorstClearance | None = None
        self.drift: list[DriftFigure] = []
        self.td_md: float | None = None
        self.td_tvd: float | None = None
        self.max_dls: float | None = None

    def read(self, name: str) -> None:
        try:
            with pq.ParquetFile(self.well_dir / name) as file:  # closed here, not at GC
                self._table(file)
        except FileNotFoundError:
            self.problems.append(f"{name} is missing")
        except (OSError, pa.ArrowException, ValueError, KeyError, TypeError) as exc:
            reason = " ".join(str(exc).split())[:160]
            self.problems.append(f"{name} cannot be read ({reason})")

    def _table(self, file: pq.ParquetFile) -> None:
        """A table, known by the columns its contract requires, read into its figure."""
        names = set(file.schema_arrow.names)
        if names >= TRAJECTORY:
            self._trajectory(file.read(columns=["md", "tvd", "dls"]))
        elif any(names >= kind for kind in CHECKS):
            self.checks.append(file.read(columns=["check", "passed", "md"]))
        elif names >= CLEARANCE:
            columns = ["offset", "md", "sf", "sf_between", "md_between", "level"]
            self._clearance(file.read(columns=columns))
        elif names >= CALIBRATION:
            columns = ["instrument", "drift_deg_h", "sigma_deg_h", "selected"]
            self._calibration(file.read(columns=columns))
        elif names >= CORRECTED:
            table = file.read(columns=["time", "correction"])
            rate = correction_rate(_floats(table, "time"), _floats(table, "correction"))
            if math.isfinite(rate):
                self.drift.append(DriftFigure(rate, None, None))

    def _trajectory(self, table: pa.Table) -> None:
        """The last trajectory persisted gives TD and the largest DLS (a later stage's is
        the same survey with more columns); each file-position check is counted once."""
        md, tvd, dls = (_floats(table, c) for c in ("md", "tvd", "dls"))
        if len(md):
            deepest = int(np.nanargmax(md)) if np.isfinite(md).any() else len(md) - 1
            self.td_md, self.td_tvd = _number(md[deepest]), _number(tvd[deepest])
            self.max_dls = _number(np.nanmax(dls)) if np.isfinite(dls).any() else None
        check = position_check_of(table)
        if check is not None:
            entry = ("file_positions", check.compared, list(check.beyond_md))
            if entry not in self.positions:
                self.positions.append(entry)

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
                self.drift.append(
                    DriftFigure(row["drift_deg_h"], row["sigma_deg_h"], row["instrument"])
                )


def _manifest(well_dir: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The well's ``run.json``, or why there is none to read."""
    path = well_dir / MANIFEST
    try:
        manifest = jsontext.loads(path.read_bytes())
    except FileNotFoundError:
        return None, f"no published outputs ({MANIFEST} missing)"
    except OSError as exc:
        return None, f"{MANIFEST} cannot be read ({exc.strerror or exc})"
    except ValueError:
        return None, f"{MANIFEST} is damaged (not JSON)"
    if not isinstance(manifest, dict) or not isinstance(manifest.get("outputs"), list):
        return None, f"{MANIFEST} is damaged (no list of outputs)"
    return manifest, None


def _marked_run(well_dir: Path) -> int | None:
    try:
        run_id = jsontext.loads((well_dir / MARKER).read_bytes()).get("run_id")
    except (OSError, ValueError, AttributeError):
        return None
    return run_id if isinstance(run_id, int) else None


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


def _reports(well_dir: Path, outputs: list[str]) -> tuple[str, ...]:
    """The report files among ``outputs`` that are on disk, HTML before PDF."""
    names = [n for n in outputs if n.endswith(REPORT_SUFFIXES) and (well_dir / n).is_file()]
    return tuple(sorted(names, key=lambda n: (REPORT_SUFFIXES.index(Path(n).suffix), n)))


def _floats(table: pa.Table, name: str) -> np.ndarray:
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=float)


def _number(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None

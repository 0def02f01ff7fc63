"""The survey listing: one row per station (MD, INC, AZI, TVD, N, E, DLS, VS, σ, ellipse,
QC), the cells a processing flag applies to marked, the rows of stations that failed a check
marked whole, DLS over short courses marked."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.reports import plots
from pipeline.reports.document import Column, Table, fmt_azimuth
from pipeline.reports.flags import AZI, SIGMA_AZI, Flag
from pipeline.reports.numbers import UNDEFINED, fmt_azimuths, fmt_each, fmt_sigmas
from pipeline.reports.sections import north_label, unit_label
from pipeline.survey.courses import course_lengths
from pipeline.uncertainty.stated import AT_CONFIDENCE, file_statements

ELLIPSE_COLUMNS = ("ellipse_major_conf", "ellipse_minor_conf", "ellipse_azimuth", "vertical_conf")
UNDEFINED_SIGMA = (
    "σ AZI undefined: near vertical the inclination does not define an azimuth (the tool "
    "axis has no horizontal direction), so the azimuth has no finite uncertainty."
)


def col(table: pa.Table, name: str) -> plots.FloatArray:
    values: plots.FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


MAX_COURSE = 100.0
"""Default maximum course length, m: a station at the end of a longer course (a first course
after the tie-in, a gap) is flagged."""


def long_courses(
    md: plots.FloatArray, offsets: tuple[int, ...], max_course: float
) -> plots.BoolArray:
    """Stations whose course from the previous station of their survey is longer than
    ``max_course`` m."""
    long: plots.BoolArray = course_lengths(md, offsets) > max_course + 1e-6
    return long


@dataclass(frozen=True)
class Course:
    """Stations at the end of a course shorter than ``min_course`` m."""

    short: plots.BoolArray
    min_course: float

    @property
    def words(self) -> str:
        return f"courses shorter than {self.min_course:g} m"


def confidence(traj: pa.Table) -> str:
    """The probability content of the *_conf ellipses: as their columns state it, else
    from their ratio to the 1σ ones."""
    stated = file_statements(pa.schema([f for f in traj.schema if f.name in AT_CONFIDENCE]))
    if "confidence" in stated:
        return f"{100 * float(stated['confidence']):.3g} %"
    if "ellipse_major" not in traj.schema.names:
        return "confidence level"
    major, conf = col(traj, "ellipse_major"), col(traj, "ellipse_major_conf")
    ok = major > 0
    if not ok.any():
        return "confidence level"
    k = float(np.median(conf[ok] / major[ok]))
    return f"{-100 * math.expm1(-k * k / 2):.3g} %"  # χ² CDF of 2 degrees of freedom at k²


def listing(
    traj: pa.Table,
    stations: pa.Table | None,
    vs_azimuth: float | None,
    flags: list[list[Flag]] | None,
    course: Course,
) -> Table:
    ref = north_label(traj, "azi").replace(" north", "")
    dls_unit = unit_label(traj, "dls")
    vs_unit = f"m @ {fmt_azimuth(vs_azimuth, 1)}°" if vs_azimuth is not None else "m"
    spec: dict[str, tuple[Column, list[str]]] = {}

    def num(name: str, decimals: int = 2) -> list[str]:
        return fmt_each(col(traj, name), decimals)

    def azimuths(name: str, decimals: int = 2) -> list[str]:
        return fmt_azimuths(col(traj, name), decimals)

    if "survey" in traj.schema.names and len(set(traj.column("survey").to_pylist())) > 1:
        surveys = [str(s) for s in traj.column("survey").to_pylist()]
        spec["survey"] = (Column("Survey", align="left"), surveys)
    if "run" in traj.schema.names and len(set(traj.column("run").to_pylist())) > 1:
        spec["run"] = (
            Column("Run", align="left"),
            [str(r) for r in traj.column("run").to_pylist()],
        )
    spec["md"] = (Column("MD", "m"), num("md"))
    spec["inc"] = (Column("INC", "°"), num("inc"))
    spec[AZI] = (Column("AZI", f"° {ref}"), azimuths("azi"))
    spec["tvd"] = (Column("TVD", "m"), num("tvd"))
    spec["north"] = (Column("North", "m"), num("north"))
    spec["east"] = (Column("East", "m"), num("east"))
    spec["dls"] = (Column("DLS", dls_unit), num("dls"))
    spec["vs"] = (Column("VS", vs_unit), num("vertical_section"))
    sigmas = _station_sigmas(traj, stations)
    for name, header, values in sigmas:
        spec[name] = (Column(header, "°"), values)
    if all(c in traj.schema.names for c in ELLIPSE_COLUMNS):
        conf = confidence(traj)
        spec["major"] = (Column("Semi-major", f"m, {conf}"), num("ellipse_major_conf"))
        spec["minor"] = (Column("Semi-minor", f"m, {conf}"), num("ellipse_minor_conf"))
        spec["major_az"] = (Column("Major az", f"° {ref}"), azimuths("ellipse_azimuth", 1))
        spec["vertical"] = (Column("Vertical", f"± m, {conf}"), num("vertical_conf"))
    if flags is not None:
        labels = ["; ".join(x.label for x in f) or "ok" for f in flags]
        spec["qc"] = (Column("QC", align="left", wrap=True), labels)
    index = {key: j for j, key in enumerate(spec)}
    cells = {(int(i), index["dls"]) for i in np.flatnonzero(course.short)}
    for i, station in enumerate(flags or []):
        for flag in station:
            if not flag.failed:
                cells.add((i, index["qc"]))
                cells.update((i, index[c]) for c in flag.columns if c in index)
    marked = frozenset(i for i, f in enumerate(flags or []) if any(x.failed for x in f))
    notes = [
        f"Azimuths and ellipse directions relative to {north_label(traj, 'azi')}; positions "
        "from the wellhead, TVD below the depth reference."
    ]
    if marked:
        notes.append("Highlighted rows: stations that failed a QC check.")
    if cells:
        notes.append(
            "Highlighted cells: values a processing flag applies to (the QC column names the "
            "flag; the QC section explains it)"
            + (
                f"; DLS over {course.words} (left out of the maximum DLS)."
                if course.short.any()
                else "."
            )
        )
    if any(v == UNDEFINED for _, _, values in sigmas for v in values):
        notes.append(UNDEFINED_SIGMA)
    rows = tuple(zip(*(values for _, values in spec.values()), strict=True))
    return Table(
        "",
        tuple(c for c, _ in spec.values()),
        rows,
        kind="listing",
        note=" ".join(notes),
        marked=marked,
        cells=frozenset(cells),
    )


def _station_sigmas(traj: pa.Table, st: pa.Table | None) -> list[tuple[str, str, list[str]]]:
    """(column, header, cells) of σ INC / σ AZI of the solved stations, matched to the
    trajectory by MD: two significant digits, "undefined" where σ is not finite."""
    if st is None:
        return []
    md = col(traj, "md")
    st_md = col(st, "md")
    index = np.clip(np.searchsorted(st_md, md), 0, max(len(st_md) - 1, 0))
    found = np.abs(st_md[index] - md) <= 1e-3 if len(st_md) else np.zeros(len(md), bool)
    out = []
    for name, header in (("sigma_inc", "σ INC"), (SIGMA_AZI, "σ AZI")):
        if name in st.schema.names:
            sigmas = fmt_sigmas(col(st, name)[index])
            cells = [text if ok else "" for text, ok in zip(sigmas, found.tolist(), strict=True)]
            out.append((name, header, cells))
    return out

"""The survey report: well and run header, method, survey listing, trajectory plots,
position uncertainty, QC, drift, sensor noise and provenance — each part present when the
run produced its tables."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial

import numpy as np
import pyarrow as pa
from scipy import stats

from pipeline.errors import GyropipeError
from pipeline.registry import Provenance
from pipeline.reports import plots
from pipeline.reports.document import (
    Block,
    Column,
    Document,
    Fields,
    Paragraph,
    Plot,
    Section,
    Table,
    Verdict,
    fmt,
    fmt_sig,
    items,
)
from pipeline.reports.qc import QcSources, all_series, station_flags, summary_rows
from pipeline.reports.sections import (
    footer,
    method_items,
    north_label,
    provenance_section,
    references,
    site_fields,
    tool_fields,
    unit_label,
)
from pipeline.survey.stations import survey_offsets
from pipeline.well import WellMetadata

ELLIPSE_COLUMNS = ("ellipse_major_conf", "ellipse_minor_conf", "ellipse_azimuth", "vertical_conf")


class ReportInputError(GyropipeError):
    """The tables given to a report cannot make one (e.g. no stations)."""


@dataclass(frozen=True)
class SurveyTables:
    """Tables a survey report is made of; only the trajectory is required."""

    trajectory: pa.Table
    stations: pa.Table | None = None
    qc: pa.Table | None = None
    qc_summary: pa.Table | None = None
    checks: pa.Table | None = None
    inout: pa.Table | None = None
    drift: pa.Table | None = None
    calibration: pa.Table | None = None
    allan: pa.Table | None = None
    noise: pa.Table | None = None

    def qc_sources(self) -> QcSources:
        return QcSources(self.qc, self.qc_summary, self.checks, self.inout, self.stations)


def _col(table: pa.Table, name: str) -> plots.FloatArray:
    values: plots.FloatArray = table.column(name).to_numpy(zero_copy_only=False).astype(float)
    return values


def section_azimuth(
    north: plots.FloatArray, east: plots.FloatArray, vs: plots.FloatArray
) -> float | None:
    """The vertical-section azimuth (deg) the table was computed with, recovered by least
    squares from VS = N cos θ + E sin θ; None when the well has no horizontal offset."""
    design = np.column_stack([north, east])
    if np.linalg.matrix_rank(design, tol=1e-6 * max(float(np.abs(design).max()), 1e-12)) < 1:
        return None
    (c, s), *_ = np.linalg.lstsq(design, vs, rcond=None)
    if np.hypot(c, s) < 0.5:
        return None
    return round(float(np.degrees(np.arctan2(s, c))), 6) % 360.0  # −1e-13° is 0°, not 360°


def survey_document(
    tables: SurveyTables, well: WellMetadata, provenance: Provenance, title: str
) -> Document:
    """The survey report of one well."""
    traj = tables.trajectory
    if traj.num_rows == 0:
        raise ReportInputError(
            "the trajectory table has no rows (the stage that produced it gave none): "
            "no stations to report"
        )
    md, tvd = _col(traj, "md"), _col(traj, "tvd")
    north, east, vs = _col(traj, "north"), _col(traj, "east"), _col(traj, "vertical_section")
    ref = north_label(traj, "azi")
    path = plots.Path3(md, north, east, tvd, tuple(int(o) for o in survey_offsets(traj)), ref)
    vs_azimuth = section_azimuth(north, east, vs)
    src = tables.qc_sources()
    flags = station_flags(md, src) if src.any() or _has(tables.stations, "flags") else None

    sections = [
        Section(
            "Well and run",
            (
                site_fields(well),
                tool_fields(
                    well,
                    provenance,
                    [("Stations", f"{traj.num_rows} ({fmt(md[0])} – {fmt(md[-1])} m MD)")],
                ),
            ),
            key="well",
        ),
        _summary(tables, path, vs_azimuth, flags),
        _method(tables, path, vs_azimuth, provenance),
        Section("Survey listing", (_listing(tables, vs_azimuth, flags),), key="listing"),
        _trajectory_plots(traj, path, vs, vs_azimuth),
    ]
    if all(c in traj.column_names for c in ELLIPSE_COLUMNS):
        sections.append(_uncertainty(traj, path))
    groups = all_series(src)
    if groups:
        sections.append(_qc(groups))
    if _rows(tables.drift) or _rows(tables.calibration):
        drift = tables.drift if _rows(tables.drift) else None
        calibration = tables.calibration if _rows(tables.calibration) else None
        sections.append(_drift(dataclasses.replace(tables, drift=drift, calibration=calibration)))
    if tables.allan is not None and _rows(tables.allan):
        sections.append(_allan(tables.allan, tables.noise))
    sections.append(provenance_section(provenance))
    subtitle = " · ".join(x for x in (well.field, well.company, well.tool_type) if x)
    return Document(
        title=title,
        subject=well.well or "unnamed well",
        subtitle=subtitle,
        issued=f"Survey date {well.survey_date or 'not stated'} · "
        f"processed {provenance.started:%Y-%m-%d}",
        footer=footer(provenance),
        sections=tuple(sections),
    )


def _has(table: pa.Table | None, column: str) -> bool:
    return table is not None and column in table.column_names


def _confidence(traj: pa.Table) -> str:
    """The probability content of the *_conf ellipses, from their ratio to the 1σ ones."""
    if "ellipse_major" not in traj.column_names:
        return "confidence level"
    major, conf = _col(traj, "ellipse_major"), _col(traj, "ellipse_major_conf")
    ok = major > 0
    if not ok.any():
        return "confidence level"
    k = float(np.median(conf[ok] / major[ok]))
    return f"{100 * stats.chi2.cdf(k * k, 2):.3g} %"


def _summary(
    tables: SurveyTables, path: plots.Path3, vs_azimuth: float | None, flags: list[str] | None
) -> Section:
    traj = tables.trajectory
    inc, dls = _col(traj, "inc"), _col(traj, "dls")
    i_inc, i_dls = int(np.argmax(inc)), int(np.argmax(dls))
    distance = float(np.hypot(path.north[-1], path.east[-1]))
    direction = float(np.degrees(np.arctan2(path.east[-1], path.north[-1])) % 360.0)
    results = [
        ("Total depth (MD)", f"{fmt(path.md[-1])} m"),
        ("TVD at TD", f"{fmt(path.tvd[-1])} m"),
        ("North / East at TD", f"{fmt(path.north[-1])} m / {fmt(path.east[-1])} m"),
        ("Closure at TD", f"{fmt(distance)} m @ {fmt(direction)}° {path.north_label}"),
        ("Maximum inclination", f"{fmt(inc[i_inc])}° at {fmt(path.md[i_inc])} m MD"),
        (
            "Maximum DLS",
            f"{fmt(dls[i_dls])} {unit_label(traj, 'dls')} at {fmt(path.md[i_dls])} m MD",
        ),
    ]
    if vs_azimuth is not None:
        results.append(("Vertical section at TD", f"{fmt(_col(traj, 'vertical_section')[-1])} m"))
    if all(c in traj.column_names for c in ELLIPSE_COLUMNS):
        results.append(
            (
                f"Ellipse at TD ({_confidence(traj)})",
                f"{fmt(_col(traj, 'ellipse_major_conf')[-1])} × "
                f"{fmt(_col(traj, 'ellipse_minor_conf')[-1])} m, vertical ± "
                f"{fmt(_col(traj, 'vertical_conf')[-1])} m",
            )
        )
    blocks: list[Block] = [Fields("Results", tuple(results))]
    if flags is not None:
        bad = [(m, f) for m, f in zip(path.md, flags, strict=True) if f != "ok"]
        if not bad:
            blocks.append(Verdict("ok", f"QC: all {len(flags)} stations passed."))
        else:
            listed = ", ".join(f"{fmt(m)} m" for m, _ in bad[:8]) + (" …" if len(bad) > 8 else "")
            blocks.append(
                Verdict(
                    "warn",
                    f"QC: {len(bad)} of {len(flags)} stations flagged (MD {listed}); "
                    "see the listing's QC column and the QC section.",
                )
            )
    return Section("Summary", tuple(blocks), key="summary")


def _method(
    tables: SurveyTables, path: plots.Path3, vs_azimuth: float | None, provenance: Provenance
) -> Section:
    traj = tables.trajectory
    plane = (
        f"{fmt(vs_azimuth)}° {path.north_label}" if vs_azimuth is not None else "n/a (no offset)"
    )
    survey = [
        ("Azimuth reference", path.north_label),
        ("Vertical section azimuth", plane),
        (
            "Tie-in (first station)",
            f"MD {fmt(path.md[0])} m, TVD {fmt(path.tvd[0])} m, N {fmt(path.north[0])} m, "
            f"E {fmt(path.east[0])} m",
        ),
        ("Dogleg severity unit", unit_label(traj, "dls")),
        *method_items(provenance),
    ]
    blocks: list[Block] = [Fields("Method", items(survey))]
    refs = references(tables.qc)
    if refs:
        blocks.append(Fields("Reference models", tuple(refs)))
    return Section("Method and reference models", tuple(blocks), key="method")


def _listing(tables: SurveyTables, vs_azimuth: float | None, flags: list[str] | None) -> Table:
    traj = tables.trajectory
    ref = north_label(traj, "azi").replace(" north", "")
    dls_unit = unit_label(traj, "dls")
    vs_unit = f"m @ {vs_azimuth:.1f}°" if vs_azimuth is not None else "m"
    spec: list[tuple[Column, list[str]]] = []

    def add(column: Column, values: list[str]) -> None:
        spec.append((column, values))

    def num(name: str, decimals: int = 2) -> list[str]:
        return [fmt(v, decimals) for v in _col(traj, name)]

    if "survey" in traj.column_names and len(set(traj.column("survey").to_pylist())) > 1:
        add(Column("Survey", align="left"), [str(s) for s in traj.column("survey").to_pylist()])
    add(Column("MD", "m"), num("md"))
    add(Column("INC", "°"), num("inc"))
    add(Column("AZI", f"° {ref}"), num("azi"))
    add(Column("TVD", "m"), num("tvd"))
    add(Column("North", "m"), num("north"))
    add(Column("East", "m"), num("east"))
    add(Column("DLS", dls_unit), num("dls"))
    add(Column("VS", vs_unit), num("vertical_section"))
    sigmas = _station_sigmas(tables)
    for header, values in sigmas:
        add(Column(header, "°"), values)
    if all(c in traj.column_names for c in ELLIPSE_COLUMNS):
        conf = _confidence(traj)
        add(Column("Semi-major", f"m, {conf}"), num("ellipse_major_conf"))
        add(Column("Semi-minor", f"m, {conf}"), num("ellipse_minor_conf"))
        add(Column("Major az", f"° {ref}"), num("ellipse_azimuth", 1))
        add(Column("Vertical", f"± m, {conf}"), num("vertical_conf"))
    if flags is not None:
        add(Column("QC", align="left", wrap=True), flags)
    marked = frozenset(i for i, f in enumerate(flags or []) if f != "ok")
    rows = tuple(zip(*(values for _, values in spec), strict=True))
    return Table(
        "",
        tuple(c for c, _ in spec),
        rows,
        kind="listing",
        note=f"Azimuths and ellipse directions relative to {north_label(traj, 'azi')}; positions "
        "from the wellhead, TVD below the depth reference. Highlighted rows carry a QC flag.",
        marked=marked,
    )


def _station_sigmas(tables: SurveyTables) -> list[tuple[str, list[str]]]:
    """σ INC / σ AZI of the solved stations, matched to the trajectory by MD."""
    st = tables.stations
    if st is None:
        return []
    md = _col(tables.trajectory, "md")
    st_md = _col(st, "md")
    index = np.clip(np.searchsorted(st_md, md), 0, max(len(st_md) - 1, 0))
    found = np.abs(st_md[index] - md) <= 1e-3 if len(st_md) else np.zeros(len(md), bool)
    out = []
    for name, header in (("sigma_inc", "σ INC"), ("sigma_azi", "σ AZI")):
        if name in st.column_names:
            values = _col(st, name)[index]
            out.append(
                (header, [fmt(v, 3) if ok else "" for v, ok in zip(values, found, strict=True)])
            )
    return out


def _trajectory_plots(
    traj: pa.Table, path: plots.Path3, vs: plots.FloatArray, vs_azimuth: float | None
) -> Section:
    inc, azi, dls = _col(traj, "inc"), _col(traj, "azi"), _col(traj, "dls")
    return Section(
        "Trajectory",
        (
            Plot(
                "plan",
                "Plan view",
                f"Horizontal projection of the stations relative to "
                f"the wellhead ({path.north_label}); dashed: closure to TD.",
                partial(plots.plan_view, path=path),
                (6.9, 4.0),
            ),
            Plot(
                "section",
                "Vertical section",
                "Displacement along the vertical-section "
                "azimuth against true vertical depth (equal scales).",
                partial(plots.vertical_section, vs=vs, path=path, azimuth=vs_azimuth),
                (6.9, 4.0),
            ),
            Plot(
                "view3d",
                "3-D view",
                "Well path (solid) and its projection on the plane "
                "through the deepest station (dashed); square: wellhead, triangle: TD. East "
                "and north at one scale, the vertical scaled to fit.",
                partial(plots.view_3d, path=path),
                (6.9, 4.2),
            ),
            Plot(
                "profiles",
                "Inclination, azimuth and dogleg severity against MD",
                "Azimuths drawn hollow where the inclination is too small to define them.",
                partial(
                    plots.profiles,
                    path=path,
                    inc=inc,
                    azi=azi,
                    dls=dls,
                    dls_unit=unit_label(traj, "dls"),
                ),
                (6.9, 4.5),
            ),
        ),
        key="trajectory",
    )


def _uncertainty(traj: pa.Table, path: plots.Path3) -> Section:
    conf = _confidence(traj)
    ell = plots.Ellipses(
        md=path.md,
        major=_col(traj, "ellipse_major_conf"),
        minor=_col(traj, "ellipse_minor_conf"),
        azimuth=_col(traj, "ellipse_azimuth"),
        vertical=_col(traj, "vertical_conf"),
        confidence=conf,
    )
    return Section(
        "Position uncertainty",
        (
            Plot(
                "ellipses",
                f"Error ellipses at {conf}",
                "Left: horizontal semi-axes and vertical half-interval against MD. Right: "
                "horizontal ellipses at stations spread over the survey, about a common centre.",
                partial(plots.error_ellipses, ell=ell, north_label=path.north_label),
                (6.9, 3.6),
            ),
        ),
        key="uncertainty",
    )


def _qc(groups: list[tuple[str, list[plots.QcSeries]]]) -> Section:
    blocks: list[Block] = []
    columns = (
        Column("Check", align="left"),
        Column("Unit", align="left"),
        Column("Evaluated"),
        Column("Passed"),
        Column("Failed"),
        Column("Not evaluated"),
        Column("Worst |value| / limit"),
    )
    for k, (title, series) in enumerate(groups):
        rows = summary_rows(series)
        blocks.append(
            Table(
                title,
                columns,
                tuple(rows),
                kind="qc",
                marked=frozenset(i for i, r in enumerate(rows) if r[4] != "0"),
            )
        )
        height = 1.0 + 2.0 * -(-len(series) // (1 if len(series) == 1 else 2))
        blocks.append(
            Plot(
                f"qc-{k}",
                title,
                "Shaded: tolerance band; crosses: failed rows. Values "
                "against MD (rows without MD are not drawn).",
                partial(plots.qc_charts, series=series),
                (6.9, min(height, 8.5)),
            )
        )
    return Section("Quality control", tuple(blocks), key="qc")


def _rows(table: pa.Table | None) -> int:
    """Rows of an optional table (0 when absent): an empty one makes no section."""
    return 0 if table is None else table.num_rows


def _drift(tables: SurveyTables) -> Section:
    blocks: list[Block] = []
    cal = tables.calibration
    if cal is not None:
        chosen = cal.filter(cal.column("selected"))
        rows = [
            (
                r["instrument"],
                r["method"],
                fmt(r["drift_deg_h"], 3),
                fmt(r["sigma_deg_h"], 3),
                r["verdict"],
            )
            for r in chosen.to_pylist()
        ]
        blocks.append(
            Table(
                "Drift calibration used",
                (
                    Column("Instrument", align="left"),
                    Column("Estimate", align="left"),
                    Column("Drift", "°/h"),
                    Column("σ", "°/h"),
                    Column("Linearity", align="left", wrap=True),
                ),
                tuple(rows),
                kind="calibration",
            )
        )
    drift = tables.drift
    if drift is not None:
        time_h = _col(drift, "time") / 3600.0
        correction = _col(drift, "correction")
        outbound = np.array([r == "out" for r in drift.column("run").to_pylist()])
        span = float(np.ptp(time_h))
        rate = (
            float(np.polyfit(time_h, correction, 1)[0])
            if span > 0 and len(time_h) > 1
            else float("nan")
        )
        blocks.append(
            Paragraph(
                f"{drift.num_rows} readings corrected over {fmt(span, 2)} h; the correction "
                f"grows at {fmt_sig(rate)} °/h (slope of the correction against time)."
            )
        )
        blocks.append(
            Plot(
                "drift",
                "Drift correction",
                "Left: correction subtracted from each reading against time. Right: azimuth as "
                "read (grey) and corrected against MD.",
                partial(
                    plots.drift_correction,
                    time_h=time_h,
                    correction=correction,
                    md=_col(drift, "md"),
                    azi_raw=_col(drift, "azi_raw"),
                    azi=_col(drift, "azi"),
                    outbound=outbound,
                    north_label=north_label(drift, "azi"),
                ),
                (6.9, 3.4),
            )
        )
    return Section("Gyro drift", tuple(blocks), key="drift")


def _allan(allan: pa.Table, noise: pa.Table | None) -> Section:
    axes = [
        a
        for a in ("gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z")
        if a in allan.column_names and allan.column(a).null_count < allan.num_rows
    ]
    curves = {a: _col(allan, a) for a in axes}
    units = {a: unit_label(allan, a) for a in axes}
    blocks: list[Block] = [
        Plot(
            "allan",
            "Allan deviation",
            "Overlapping Allan deviation of the static record at octave averaging times.",
            partial(plots.allan_deviation, tau=_col(allan, "tau"), curves=curves, units=units),
            (6.9, 3.4),
        )
    ]
    if noise is not None:
        rows = tuple(
            (
                r["axis"],
                f"{fmt_sig(r['arw'])} {r['arw_unit']}",
                f"{fmt_sig(r['bias_instability'])} {r['bias_instability_unit']}",
                f"{fmt_sig(r['rrw'])} {r['rrw_unit']}",
                r["bias_model"],
            )
            for r in noise.to_pylist()
        )
        blocks.append(
            Table(
                "Noise terms (IEEE Std 952)",
                (
                    Column("Axis", align="left"),
                    Column("Random walk"),
                    Column("Bias instability"),
                    Column("Rate random walk"),
                    Column("Bias model", align="left"),
                ),
                rows,
                kind="noise",
            )
        )
    return Section("Sensor noise", tuple(blocks), key="allan")

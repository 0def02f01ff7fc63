"""The survey report: well and run header, method, survey listing, trajectory plots,
position uncertainty, QC (the stations dropped by a check too), drift, sensor noise and
provenance — each part present when the run produced its tables."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial

import numpy as np
import pyarrow as pa

from pipeline.errors import GyropipeError
from pipeline.qc.dropped import Dropped, dropped_stations
from pipeline.registry import Provenance
from pipeline.reports import plots
from pipeline.reports.clearance import clearance_section
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
    fmt_azimuth,
    fmt_sig,
    items,
)
from pipeline.reports.drift import caveat_verdicts, drift_section
from pipeline.reports.envelope import FullRate
from pipeline.reports.flags import POSITION_MISMATCH, Flag, long_course
from pipeline.reports.listing import (
    ELLIPSE_COLUMNS,
    MAX_COURSE,
    Course,
    col,
    confidence,
    listing,
    long_courses,
)
from pipeline.reports.literature import Citations
from pipeline.reports.parts import Parts, Registered
from pipeline.reports.program import program_section
from pipeline.reports.qc import (
    QcSources,
    all_series,
    diagnosis_table,
    dropped_table,
    flag_table,
    gates_table,
    gates_verdict,
    qc_verdict,
    recording_table,
    recording_verdicts,
    station_flags,
    summary_rows,
)
from pipeline.reports.sections import (
    bearing,
    footer,
    north_label,
    provenance_section,
    references,
    signoff_section,
    site_fields,
    survey_tool,
    tool_fields,
    unit_label,
)
from pipeline.reports.view3d import view_3d
from pipeline.survey.calculation import calculation_of
from pipeline.survey.courses import MIN_COURSE, max_dls, short_courses
from pipeline.survey.crosscheck import position_check_of
from pipeline.survey.stations import survey_offsets
from pipeline.uncertainty.stated import Extent, Statement, statement_of
from pipeline.well import WellMetadata


class ReportInputError(GyropipeError):
    """The tables given to a report cannot make one (e.g. no stations)."""


@dataclass(frozen=True)
class SurveyTables:
    """Tables a survey report is made of; only the trajectory is required."""

    trajectory: pa.Table
    stations: pa.Table | None = None
    qc: pa.Table | None = None
    qc_summary: pa.Table | None = None
    rejects: pa.Table | None = None
    """stations compassing could not solve (:class:`~pipeline.tables.CompassRejects`)"""
    checks: pa.Table | None = None
    inout: pa.Table | None = None
    drift: pa.Table | None = None
    calibration: pa.Table | None = None
    allan: pa.Table | None = None
    noise: pa.Table | None = None
    comparison: pa.Table | None = None
    gates: pa.Table | None = None
    clearance: pa.Table | None = None
    series: FullRate | None = None
    """a full-rate series already reduced to its envelope (bounded, whatever its length)"""

    def dropped(self) -> list[Dropped]:
        """The stations recorded but dropped by the validity checks or compassing."""
        return dropped_stations([self.qc_summary, self.rejects, self.qc])

    def qc_sources(self) -> QcSources:
        return QcSources(
            self.qc,
            self.qc_summary,
            self.checks,
            self.inout,
            self.stations,
            self.comparison,
            self.gates,
        )


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
    tables: SurveyTables,
    well: WellMetadata,
    provenance: Provenance,
    title: str,
    registered: Registered,
    min_course: float = MIN_COURSE,
    max_course: float = MAX_COURSE,
) -> Document:
    """The survey report of one well, with what the ``registered`` report parts state and
    add; DLS over courses shorter than ``min_course`` m is left out of the summary's maximum
    and marked in the listing; a course longer than ``max_course`` m is a station flag, as is
    a station whose position the stations file states otherwise."""
    traj = tables.trajectory
    if traj.num_rows == 0:
        raise ReportInputError(
            "the trajectory table has no rows (the stage that produced it gave none): "
            "no stations to report"
        )
    md, tvd = col(traj, "md"), col(traj, "tvd")
    north, east, vs = col(traj, "north"), col(traj, "east"), col(traj, "vertical_section")
    ref = north_label(traj, "azi")
    path = plots.Path3(md, north, east, tvd, tuple(int(o) for o in survey_offsets(traj)), ref)
    vs_azimuth = section_azimuth(north, east, vs)
    src = tables.qc_sources()
    flags = station_flags(md, src) if src.any() or _has(tables.stations, "flags") else None
    flags = _own_flags(flags, traj, long_courses(md, path.offsets, max_course), max_course)
    short = short_courses(md, path.offsets, min_course)
    course = Course(short, min_course)
    citations = Citations()
    given = {f.name: getattr(tables, f.name) for f in dataclasses.fields(tables)}
    wired = {port: table for port, table in given.items() if isinstance(table, pa.Table)}
    parts = Parts(registered, "survey", wired, well, provenance, citations)
    clearance = (
        clearance_section(tables.clearance, citations, parts.error_model)
        if _rows(tables.clearance)
        else None
    )
    added = parts.sections()  # before the method section's reference list: they may cite
    tool = survey_tool(traj, well)
    verdicts = [b for b in clearance.blocks if isinstance(b, Verdict)] if clearance else []
    dropped = tables.dropped()
    verdicts += caveat_verdicts(tables.drift) + recording_verdicts(src.qc, dropped)
    recorded = f"; {len(dropped)} more recorded and dropped (see the QC section)" if dropped else ""

    sections = [
        Section(
            "Well and run",
            (
                site_fields(well),
                tool_fields(
                    well.model_copy(update={"tool_type": tool}),
                    provenance,
                    [
                        (
                            "Stations",
                            f"{traj.num_rows} ({fmt(md[0])} – {fmt(md[-1])} m MD){recorded}",
                        )
                    ],
                ),
            ),
            key="well",
        ),
        _summary(tables, path, vs_azimuth, flags, course, verdicts, dropped),
        _method(tables, path, vs_azimuth, parts),
        Section(
            "Survey listing",
            (
                listing(traj, tables.stations, vs_azimuth, flags, course),
                *_ellipse_note(traj, provenance, parts),
            ),
            key="listing",
        ),
    ]
    drawn = plots.drawn_rows(md, path.offsets, col(traj, "dls"))  # charts of a very long
    shown, shown_path = traj.take(drawn), path.taken(drawn)  # survey: thinned for drawing
    shown_course = Course(course.short[drawn], course.min_course)  # (not for the listing)
    sections.append(
        _trajectory_plots(shown, shown_path, vs[drawn], vs_azimuth, shown_course, tables.series, md)
    )
    program = program_section(traj)
    if program is not None:
        sections.insert(3, program)
    if all(c in traj.schema.names for c in ELLIPSE_COLUMNS):
        sections.append(_uncertainty(shown, shown_path, statement_of(traj)))
    elif (stated := statement_of(traj)) is not None:  # covariances alone: no sizes to chart
        words = Paragraph(_statement_words(stated, None))
        sections.append(Section("Position uncertainty", (words,), key="uncertainty"))
    groups = all_series(src)
    explained = flag_table(flags or [])
    notes = [
        t
        for t in (
            dropped_table(dropped, src.qc),
            diagnosis_table(src.summary),
            recording_table(src.qc),
        )
        if t
    ]
    if groups or explained is not None or notes or src.gates is not None:
        sections.append(_qc(groups, explained, notes, src.gates))
    if _rows(tables.drift) or _rows(tables.calibration):
        drift = tables.drift if _rows(tables.drift) else None
        sections.append(
            drift_section(drift, tables.calibration if _rows(tables.calibration) else None)
        )
    if tables.allan is not None and _rows(tables.allan):
        sections.append(_allan(tables.allan, tables.noise))
    if clearance is not None:
        sections.append(clearance)
    sections += [*added, signoff_section(), provenance_section(provenance)]
    # the tool in the subtitle only when one tool surveyed it (several: the header says)
    one_tool = well.tool_type if tool == well.tool_type else None
    subtitle = " · ".join(x for x in (well.field, well.company, one_tool) if x)
    return Document(
        title=title,
        subject=well.well or "unnamed well",
        subtitle=subtitle,
        issued=f"Survey date {well.survey_dates() or 'not stated'} · "
        f"processed {provenance.started:%Y-%m-%d}",
        footer=footer(provenance),
        sections=tuple(sections),
    )


def _ellipse_note(traj: pa.Table, provenance: Provenance, parts: Parts) -> list[Paragraph]:
    """What the listing's ellipse columns are: their axes, confidence level and the error
    model (by its title) of the run's position-uncertainty stage; none without ellipses."""
    if not all(c in traj.schema.names for c in ELLIPSE_COLUMNS):
        return []
    names = [str(s.params["model"]) for s in provenance.stages if s.uses == "position_uncertainty"]
    stated = statement_of(traj)
    titles = " and ".join(dict.fromkeys(parts.error_model(n)[0] for n in names)) or (
        stated.error_model if stated is not None else None
    )  # the models' titles, else the columns' statement (a definitive survey's runs)
    model = f"; error model {titles}" if titles else ""
    level = confidence(traj)
    level = f"confidence level {level}" if level[0].isdigit() else "confidence level not stated"
    return [
        Paragraph(
            "Ellipse columns: semi-major and semi-minor axes of the horizontal error ellipse, "
            f"azimuth of its major axis and vertical half-interval; {level}{model}."
        )
    ]


def _own_flags(
    flags: list[list[Flag]] | None, traj: pa.Table, long: plots.BoolArray, max_course: float
) -> list[list[Flag]] | None:
    """``flags`` with the trajectory's own: long courses, and stations whose position the
    stations file states otherwise (:mod:`pipeline.survey.crosscheck`)."""
    check = position_check_of(traj)
    mismatched = np.isin(col(traj, "md"), check.beyond_md) if check else np.zeros_like(long)
    if not (long.any() or mismatched.any()):
        return flags
    out = [list(f) for f in flags] if flags is not None else [[] for _ in range(len(long))]
    for i in np.flatnonzero(mismatched):
        out[i].append(POSITION_MISMATCH)
    for i in np.flatnonzero(long):
        out[i].append(long_course(max_course))
    return out


def _has(table: pa.Table | None, column: str) -> bool:
    return table is not None and column in table.schema.names


def _max_dls(traj: pa.Table, path: plots.Path3, course: Course) -> str:
    """Largest DLS over the courses at least ``min_course`` long
    (:func:`~pipeline.survey.courses.max_dls`), saying how many were left out."""
    found = max_dls(path.md, col(traj, "dls"), path.offsets, course.min_course)
    if found is None:
        return "not defined (no course between stations)"
    if found.all_short:
        note = f" (every course shorter than {course.min_course:g} m)"
    elif found.left_out:
        note = f" ({course.words} not counted: {found.left_out})"
    else:
        note = ""
    return f"{fmt(found.dls)} {unit_label(traj, 'dls')} at {fmt(path.md[found.row])} m MD{note}"


def _summary(
    tables: SurveyTables,
    path: plots.Path3,
    vs_azimuth: float | None,
    flags: list[list[Flag]] | None,
    course: Course,
    verdicts: list[Verdict],
    dropped: list[Dropped],
) -> Section:
    """Results at TD (of each survey, named, when the trajectory holds several) and the
    verdicts of the QC (the stations ``dropped`` included), the acceptance gates and
    ``verdicts`` (the clearance's and the drift calibration's caveats, repeated from their
    sections)."""
    traj = tables.trajectory
    names = _survey_names(traj, path.offsets)
    blocks: list[Block] = []
    for name, (lo, one) in zip(names, path.surveys(), strict=True):
        shorter = Course(course.short[lo : lo + len(one.md)], course.min_course)
        results = _results(traj.slice(lo, len(one.md)), one, vs_azimuth, shorter)
        blocks.append(Fields(f"Results, survey {name}" if name else "Results", results))
    if flags is not None or dropped:
        listed = flags if flags is not None else [[] for _ in range(len(path.md))]
        blocks.append(qc_verdict(listed, path.md, dropped))
    if tables.gates is not None:
        blocks.append(gates_verdict(tables.gates))
    return Section("Summary", (*blocks, *verdicts), key="summary")


def _survey_names(traj: pa.Table, offsets: tuple[int, ...]) -> list[str | None]:
    """Each survey's id where the trajectory holds several, else [None]."""
    if len(offsets) < 3:
        return [None]
    surveys = traj.column("survey")
    return [str(surveys[lo].as_py()) for lo in offsets[:-1]]


def _tie_sources(traj: pa.Table) -> list[str]:
    """Where each survey's tie came from, as the trajectory records its ties
    (:mod:`pipeline.survey.tiein`): ``" (from the stations file)"``, ``" (from the
    pipeline)"`` or ``" (on survey 'MAIN' at that MD)"``; ``""`` each where it records none."""
    calculation = calculation_of(traj)
    ties = calculation.ties if calculation is not None else ()
    words = [
        f" (on survey {tie.parent!r} at that MD)"
        if tie.source == "survey"
        else f" (from the {tie.source})"
        for tie in ties
    ]
    return words or [""] * len(survey_offsets(traj))


def _results(
    traj: pa.Table, path: plots.Path3, vs_azimuth: float | None, course: Course
) -> tuple[tuple[str, str], ...]:
    """TD, its position and closure, maximum inclination and DLS, vertical section and
    ellipse at TD of one survey."""
    inc = col(traj, "inc")
    i_inc = int(np.argmax(inc))
    distance = float(np.hypot(path.north[-1], path.east[-1]))
    direction = float(np.degrees(np.arctan2(path.east[-1], path.north[-1])))
    results = [
        ("Total depth (MD)", f"{fmt(path.md[-1])} m"),
        ("TVD at TD", f"{fmt(path.tvd[-1])} m"),
        ("North / East at TD", f"{fmt(path.north[-1])} m / {fmt(path.east[-1])} m"),
        ("Closure at TD", f"{fmt(distance)} m @ {fmt_azimuth(direction)}° {path.north_label}"),
        ("Maximum inclination", f"{fmt(inc[i_inc])}° at {fmt(path.md[i_inc])} m MD"),
        ("Maximum DLS", _max_dls(traj, path, course)),
    ]
    if vs_azimuth is not None:
        results.append(("Vertical section at TD", f"{fmt(col(traj, 'vertical_section')[-1])} m"))
    if all(c in traj.schema.names for c in ELLIPSE_COLUMNS):
        results.append(
            (
                f"Ellipse semi-axes at TD ({confidence(traj)})",
                f"{fmt(col(traj, 'ellipse_major_conf')[-1])} × "
                f"{fmt(col(traj, 'ellipse_minor_conf')[-1])} m, vertical ± "
                f"{fmt(col(traj, 'vertical_conf')[-1])} m",
            )
        )
    return tuple(results)


def _method(
    tables: SurveyTables,
    path: plots.Path3,
    vs_azimuth: float | None,
    parts: Parts,
) -> Section:
    traj = tables.trajectory
    plane = (
        f"{fmt_azimuth(vs_azimuth)}° {path.north_label}"
        if vs_azimuth is not None
        else "n/a (no offset)"
    )
    survey = [
        ("Azimuth reference", path.north_label),
        ("Declination applied to azimuths", bearing(parts.well.declination_applied)),
        ("Convergence applied to azimuths", bearing(parts.well.grid_convergence_applied)),
        ("Vertical section azimuth", plane),
        *(
            (
                f"Tie-in (first station of survey {name})" if name else "Tie-in (first station)",
                f"MD {fmt(path.md[lo])} m, TVD {fmt(path.tvd[lo])} m, "
                f"N {fmt(path.north[lo])} m, E {fmt(path.east[lo])} m{source}",
            )
            for name, lo, source in zip(
                _survey_names(traj, path.offsets), path.offsets, _tie_sources(traj), strict=False
            )
        ),
        ("Dogleg severity unit", unit_label(traj, "dls")),
        *parts.methods(),
    ]
    blocks: list[Block] = [Fields("Method", items(survey))]
    refs = references(tables.qc)
    if refs:
        blocks.append(Fields("Reference models", tuple(refs)))
    cited = parts.citations.fields()
    if cited is not None:
        blocks.append(cited)
    return Section("Method and reference models", tuple(blocks), key="method")


def _trajectory_plots(
    traj: pa.Table,
    path: plots.Path3,
    vs: plots.FloatArray,
    vs_azimuth: float | None,
    course: Course,
    series: FullRate | None,
    every_md: plots.FloatArray,
) -> Section:
    """The trajectory charts, of the stations in ``traj`` (thinned from ``every_md`` when
    the survey is very long: the captions say so)."""
    inc, azi, dls = col(traj, "inc"), col(traj, "azi"), col(traj, "dls")
    drawn = (
        f" Drawn at {traj.num_rows:,} of the {len(every_md):,} stations (evenly spaced, "
        "each survey's ends and the highest DLS between two drawn stations); the listing "
        "has them all."
        if traj.num_rows < len(every_md)
        else ""
    )
    full: tuple[Plot, ...] = ()
    if series is not None and series.samples:
        full = (
            Plot(
                "fullrate",
                "Inclination and azimuth of every sample against MD",
                f"Grey: the {series.samples:,} samples of the run (each pixel column drawn "
                "from its lowest to its highest value); dots: the stations.",
                partial(plots.full_rate, series=series, path=path, inc=inc, azi=azi),
                (6.9, 4.0),
            ),
        )
    return Section(
        "Trajectory",
        (
            Plot(
                "plan",
                "Plan view",
                f"Horizontal projection of the stations relative to "
                f"the wellhead ({path.north_label}); dashed: closure to TD.{drawn}",
                partial(plots.plan_view, path=path),
                (6.9, 4.0),
            ),
            Plot(
                "section",
                "Vertical section",
                "Displacement along the vertical-section "
                "azimuth against true vertical depth (equal scales)." + drawn,
                partial(plots.vertical_section, vs=vs, path=path, azimuth=vs_azimuth),
                (6.9, 4.0),
            ),
            Plot(
                "view3d",
                "3-D view",
                "Well path (solid) and its projection on the plane "
                "through the deepest station (dashed); square: wellhead, triangle: TD. East "
                "and north at one scale, the vertical scaled to fit." + drawn,
                partial(view_3d, path=path),
                (6.9, 4.2),
            ),
            Plot(
                "profiles",
                "Inclination, azimuth and dogleg severity against MD",
                "Azimuths drawn hollow where the inclination is too small to define them"
                + (f"; DLS over {course.words} as grey rings." if course.short.any() else ".")
                + drawn,
                partial(
                    plots.profiles,
                    path=path,
                    inc=inc,
                    azi=azi,
                    dls=dls,
                    dls_unit=unit_label(traj, "dls"),
                    short=course.short,
                    short_label=course.words,
                ),
                (6.9, 4.5),
            ),
            *full,
        ),
        key="trajectory",
    )


def _uncertainty(traj: pa.Table, path: plots.Path3, stated: Statement | None) -> Section:
    """Ellipses against MD (``traj``, ``path``: the stations drawn) and what the whole
    trajectory's columns state of them (``stated``)."""
    conf = confidence(traj)
    ell = plots.Ellipses(
        md=path.md,
        major=col(traj, "ellipse_major_conf"),
        minor=col(traj, "ellipse_minor_conf"),
        azimuth=col(traj, "ellipse_azimuth"),
        vertical=col(traj, "vertical_conf"),
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
            *([Paragraph(_statement_words(stated, conf))] if stated is not None else []),
        ),
        key="uncertainty",
    )


def _statement_words(stated: Statement, conf: str | None) -> str:
    """The error model, the σ convention of the uncertainty columns and the largest
    horizontal semi-major axis and TD's, in words (lengths m); ``conf``: the charted sizes'
    confidence level (None: the trajectory has covariances alone, none charted)."""
    model = stated.error_model or "not stated"
    level = (
        ""
        if conf is None
        else f"{conf} confidence"
        if conf[0].isdigit()
        else "a confidence level not stated"
    )
    convention = (
        "Covariances are 1σ² (m²); the semi-major axes stated here are those of their 1σ "
        "horizontal ellipse."
        if conf is None
        else "Covariances are 1σ² (m²), semi-axes and vertical σ at 1σ, the charted and listed "
        f"sizes at {level} (horizontal ellipse: 2-D, χ² of 2 degrees of freedom; vertical: "
        "1-D, two-sided normal)."
    )

    def where(extent: Extent) -> str:
        if extent.semi_major is None:
            return f"none at {fmt(extent.md)} m MD (no σ: outside the error model's range)"
        survey = f" of survey {extent.survey}" if extent.survey is not None else ""
        conf_m = extent.semi_major_conf
        at_conf = f"{fmt(conf_m)} m at {level}, " if conf_m is not None else ""
        return f"{at_conf}{fmt(extent.semi_major)} m at 1σ, at {fmt(extent.md)} m MD{survey}"

    words = [
        *([said] if (said := stated.source_words()) else []),
        f"Error model {model}. {convention}",
        "Largest horizontal semi-major axis: "
        + (where(stated.largest) if stated.largest is not None else "none (no station has a σ)")
        + f"; at TD: {where(stated.at_td)}.",
    ]
    words += [said for tie in stated.tie_on if (said := tie.words())]
    if stated.without_sigma:
        words.append(
            f"{stated.without_sigma} station(s) have no σ (outside the error model's range, "
            "or below such a station)."
        )
    if stated.interpolated_points:
        words.append(
            f"{stated.interpolated_points} row(s) are points interpolated between survey "
            "stations: no σ, and not counted as stations."
        )
    return " ".join(words)


def _qc(
    groups: list[tuple[str, list[plots.QcSeries]]],
    explained: Table | None,
    notes: list[Table],
    gates: pa.Table | None = None,
) -> Section:
    blocks: list[Block] = []
    if gates is not None:
        blocks += [gates_verdict(gates), gates_table(gates)]
    blocks += [t for t in (explained, *notes) if t is not None]
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
                "Shaded: tolerance band; crosses: failed rows. Values against MD (rows without "
                "MD are not drawn). Where the band is far wider than the values, the axis "
                "shows the values and the legend gives the band.",
                partial(plots.qc_charts, series=series),
                (6.9, min(height, 8.5)),
            )
        )
    return Section("Quality control", tuple(blocks), key="qc")


def _rows(table: pa.Table | None) -> int:
    """Rows of an optional table (0 when absent): an empty one makes no section."""
    return 0 if table is None else table.num_rows


def _allan(allan: pa.Table, noise: pa.Table | None) -> Section:
    axes = [
        a
        for a in ("gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z")
        if a in allan.schema.names and allan.column(a).null_count < allan.num_rows
    ]
    curves = {a: col(allan, a) for a in axes}
    units = {a: unit_label(allan, a) for a in axes}
    blocks: list[Block] = [
        Plot(
            "allan",
            "Allan deviation",
            "Overlapping Allan deviation of the static record at octave averaging times.",
            partial(plots.allan_deviation, tau=col(allan, "tau"), curves=curves, units=units),
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

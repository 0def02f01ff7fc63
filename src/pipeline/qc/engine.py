"""Validity checks of a point survey's stations (DOMAIN.md §3): every check over every
reading, fault isolation, the result tables and what the policies do.

The gyro checks (earth_rate, latitude, horizontal_rate, rate_along_gravity) need a
three-axis gyro; single-axis and XY tools get rows saying so and the ``earth_rate_fit``
check instead: their frame positions are fitted (compassing's least squares, bias and
trend removed) after removing the vertical Earth rate from each reading (``ω + Ω sin φ·g/|g|``
leaves ``Ω cos φ·n_b``, n the north direction in the body), giving
``(u', v') = Ω cos φ (cos A cos I, −sin A)`` in the high-side frame, hence k. Near vertical
(I below ``vertical_below``) the fit is referenced to the frame-angle sensor and
k ≈ √(u'² + v'²), low by at most 1 − cos I (0.14 % at 3°). Near horizontal σ_k grows as
1/cos I: the check weakens there, and where σ_k exceeds Ω cos φ / :data:`RESOLVED` the fit
cannot tell k at all (at 90° its estimate is thousands of °/h, passing or failing by chance):
the station is not evaluated, its row saying why. A fit cannot see a constant gyro bias (it
removes it).

Checks are made per reading (station × frame position), so a fault that changes sign as the
frame turns is not averaged away; a station of N positions has N rows per check and fails
when any does (false-alarm rate per station ≈ N × the rate per row). The rest limits
(``rest_gyro``, ``rest_acc``) take the largest per-axis sample std of each reading.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from numpy.typing import NDArray

from pipeline.earth.frames import FloatArray
from pipeline.earth.site import Site
from pipeline.gyrocompass.earth_rate import StationReject
from pipeline.gyrocompass.fit import Design, design, fit_all
from pipeline.qc.faults import Equation, Finding, isolate
from pipeline.qc.magnetic import diagnose_magnetic
from pipeline.qc.options import CHECKS, DEFAULTS, QcOptions, QcStop
from pipeline.qc.recording import recording_checks
from pipeline.qc.reference import EarthReference, earth_reference
from pipeline.qc.sensors import Sensors, float_column, readings_sensors
from pipeline.qc.tables import STATUSES, QcResults, QcSummary
from pipeline.qc.vector_checks import (
    VECTOR_CHECKS,
    IntArray,
    Keys,
    Rows,
    VectorCheck,
    judge,
    limit_rows,
    norm,
    propagate,
    vector_checks,
)
from pipeline.streams import TableStream
from pipeline.tables import PositionReadings

FIT_UNDETERMINED = (
    "the fit removes gyro biases and one or two gyro axes cannot be told apart: a scale "
    "error, motion or a frame fault"
)
"""Diagnosis of a failed earth_rate_fit (single-axis and XY tools are not isolated)."""
RESOLVED = 3.0
"""earth_rate_fit is evaluated where its k is known to a third of Ω cos φ (σ_k ≤ Ω cos φ / 3)"""
ISOLATED = ("earth_rate", "gravity", "latitude", "horizontal_rate", "rate_along_gravity")
"""Checks whose failure starts fault isolation (:mod:`pipeline.qc.faults`)."""


def rest_checks(readings: pa.Table, options: QcOptions, keys: Keys) -> list[Rows]:
    """The tool must be still while a reading is averaged: the largest per-axis sample std
    of the gyros (°/h) and accelerometers (m/s²) against the rest limits."""
    out = []
    for name, prefix, unit in (("rest_gyro", "gyro", "deg/h"), ("rest_acc", "acc", "m/s2")):
        std = np.stack([float_column(readings, f"{prefix}_{a}_std") for a in "xyz"], axis=-1)
        largest = np.full(len(std), np.nan)
        known = ~np.isnan(std).all(axis=1)
        largest[known] = np.nanmax(std[known], axis=1)
        rows = limit_rows(name, unit, f"{prefix} sample std", largest, getattr(options, name), keys)
        rows.detail[~known] = "skipped: the readings carry no std columns"
        out.append(rows)
    return out


def fit_checks(
    readings: pa.Table, sensors: Sensors, earth: EarthReference, options: QcOptions
) -> Rows:
    """``earth_rate_fit`` per station of a single-axis or XY tool (module docstring)."""
    m = 2 if "y" in sensors.gyro_axes else 1  # transverse gyros: x, or x and y
    station = readings.column("station").to_numpy()
    starts = np.flatnonzero(np.r_[True, station[1:] != station[:-1]])
    ends = np.r_[starts[1:], len(station)]
    t = float_column(readings, "t")
    frame = float_column(readings, "frame_angle")
    md = float_column(readings, "md")
    lat = np.radians(earth.latitude)
    reference = earth.rate * np.cos(lat)
    inc_k, sigma_inc_k = propagate(
        lambda g: np.arctan2(np.hypot(g[:, 0], g[:, 1]), g[:, 2]),
        [sensors.acc],
        [sensors.acc_sigma],
    )
    down = sensors.acc / norm(sensors.acc)[:, None]
    gyro = sensors.gyro[:, :m] + earth.rate * np.sin(lat) * down[:, :m]  # Ω cos φ · n_b
    sigma = sensors.gyro_sigma[:, :m]
    s = len(starts)
    measured, sig = np.full(s, np.nan), np.full(s, np.nan)
    detail = np.full(s, "", dtype=object)
    fitted: list[tuple[int, float, bool]] = []  # station index, I, near vertical
    designs: list[Design] = []
    for i, (a, b) in enumerate(zip(starts, ends, strict=True)):
        inc = float(inc_k[a:b].mean())
        near = min(inc, np.pi - inc) < np.radians(options.vertical_below)
        if not np.isfinite(sigma[a:b]).all():
            detail[i] = "skipped: the readings carry no gyro std/n (the fit needs σ)"
            continue
        if near and np.isnan(frame[a:b]).any():
            detail[i] = "skipped: near vertical and no frame angle to reference the fit"
            continue
        alpha = (
            np.radians(frame[a:b])
            if near
            else np.arctan2(sensors.acc[a:b, 1], -sensors.acc[a:b, 0])
        )
        n_obs = (b - a) * m
        terms = 2 if options.fit_trend and n_obs >= 2 + 2 * m else 1
        try:
            designs.append(design(alpha, t[a:b], gyro[a:b], sigma[a:b], terms))
        except StationReject as exc:
            detail[i] = f"skipped: {exc}"
            continue
        fitted.append((i, inc, near))
    for (i, inc, near), fit in zip(fitted, fit_all(designs), strict=True):
        if isinstance(fit, StationReject):
            detail[i] = f"skipped: {fit}"
            continue
        a, b = starts[i], ends[i]
        u, v = fit.uv
        c = 1.0 if near else np.cos(inc)
        k = np.hypot(u / c, v)
        jac = np.array([u / (c * c * k), v / k])
        var = jac @ fit.cov[:2, :2] @ jac
        if not near:  # through I: ∂k/∂I = u² sin I / (k cos³ I)
            sigma_inc = np.sqrt((sigma_inc_k[a:b] ** 2).sum()) / (b - a)
            var += (u * u * np.sin(inc) / (k * c**3) * sigma_inc) ** 2
        measured[i], sig[i] = k, np.sqrt(var)
        if sig[i] > reference / RESOLVED:
            detail[i] = (
                f"skipped: at I = {np.degrees(inc):.2f}° the fit cannot tell k (σ "
                f"{sig[i]:.3g} deg/h against Ω cos φ = {reference:.3f} deg/h): the high-side "
                "gyro sees the Earth rate times cos I"
            )
            measured[i] = np.nan
    keys = Keys(station[starts], np.full(s, -1), md[starts], np.full(s, np.nan), np.full(s, np.nan))
    rows = judge(
        "earth_rate_fit",
        "deg/h",
        "k",
        measured,
        np.nan_to_num(sig),
        np.zeros(s, bool),
        np.full(s, reference),
        options.earth_rate_fit,
        keys,
    )
    skipped = np.isnan(measured)
    rows.evaluated &= ~skipped
    rows.detail[skipped] = detail[skipped]
    rows.tolerance[skipped] = np.nan
    failed = rows.failed
    rows.suspect[failed] = "undetermined"
    rows.detail[failed] = [f"{text}; {FIT_UNDETERMINED}" for text in rows.detail[failed]]
    return rows


def _reader(spec: VectorCheck) -> Callable[[FloatArray, FloatArray], FloatArray]:
    """A check's function as a function of (ω, g)."""

    def func(w: FloatArray, g: FloatArray) -> FloatArray:
        return spec.func(*[w if s == "gyro" else g for s in spec.sensors])

    return func


def isolate_rows(
    rows: list[Rows],
    group: IntArray,
    sensors: Sensors,
    earth: EarthReference,
    options: QcOptions,
) -> dict[int, Finding]:
    """Fault isolation for every group (station, or window) with a failed gyro or
    accelerometer check: the readings of each group are stacked as frame positions and
    handed to :func:`pipeline.qc.faults.isolate`. Fills ``suspect`` and appends the
    diagnosis to the detail of those failed rows; returns the finding of each group."""
    by_name = {r.check: r for r in rows}
    failing = np.zeros(len(group), bool)
    for name in ISOLATED:
        if name in by_name:
            failing |= by_name[name].failed
    groups = np.unique(group[failing])
    if groups.size == 0:
        return {}
    members = [np.flatnonzero(group == g) for g in groups]
    width = max(len(m) for m in members)
    index = np.zeros((len(groups), width), dtype=np.int64)
    valid = np.zeros((len(groups), width), dtype=bool)
    for i, m in enumerate(members):
        index[i, : len(m)], valid[i, : len(m)] = m, True
    equations = []
    for name in ISOLATED:
        if name in by_name and by_name[name].evaluated.any():
            spec = VECTOR_CHECKS[name]
            tol = np.where(by_name[name].evaluated, by_name[name].tolerance, np.inf)
            equations.append(
                Equation(
                    "gyro" in spec.sensors,
                    _reader(spec),
                    float(by_name[name].reference[0]),
                    tol[index],
                )
            )
    three_axis = sensors.gyro_axes == "xyz"
    findings = isolate(
        sensors.gyro[index] if three_axis else None,
        sensors.acc[index],
        valid,
        equations,
        options.isolation_margin,
    )
    result = {int(g): f for g, f in zip(groups, findings, strict=True)}
    for name in ISOLATED:
        if name not in by_name:
            continue
        r = by_name[name]
        for row in np.flatnonzero(r.failed):
            finding = result[int(group[row])]
            r.suspect[row] = finding.suspect
            r.detail[row] = f"{r.detail[row]}; {finding.diagnosis}"
    return result


def results_table(rows: list[Rows]) -> pa.Table:
    """QcResults from evaluated rows, sorted by station, window start, position (station-
    level rows after the positions) and check."""

    def join(get: Callable[[Rows], NDArray[Any]]) -> NDArray[Any]:
        return np.concatenate([get(r) for r in rows])

    station, position = join(lambda r: r.keys.station), join(lambda r: r.keys.position)
    md, start, end = (
        join(lambda r: r.keys.md),
        join(lambda r: r.keys.start),
        join(lambda r: r.keys.end),
    )
    check = join(lambda r: np.full(len(r.measured), r.check, dtype=object))
    rank = join(lambda r: np.full(len(r.measured), CHECKS.index(r.check)))
    last = np.iinfo(np.int64).max
    order = np.lexsort(
        (rank, np.where(position < 0, last, position), np.nan_to_num(start), station)
    )
    station, position, md, start, end = (a[order] for a in (station, position, md, start, end))
    evaluated = join(lambda r: r.evaluated)[order]
    return QcResults.compiled().make_table(
        {
            "station": pa.array(station, pa.int64(), mask=station < 0),
            "position": pa.array(position, pa.int64(), mask=position < 0),
            "window_start": pa.array(start, pa.float64(), mask=np.isnan(start)),
            "window_end": pa.array(end, pa.float64(), mask=np.isnan(end)),
            "md": pa.array(md, pa.float64(), mask=np.isnan(md)),
            "check": pa.array(check[order], pa.string()),
            "measured": join(lambda r: r.measured)[order],
            "reference": join(lambda r: r.reference)[order],
            "tolerance": join(lambda r: r.tolerance)[order],
            "unit": pa.array(
                join(lambda r: np.full(len(r.measured), r.unit, dtype=object))[order], pa.string()
            ),
            "passed": pa.array(~join(lambda r: r.failed)[order], pa.bool_(), mask=~evaluated),
            "suspect": pa.array(join(lambda r: r.suspect)[order], pa.string()),
            "detail": pa.array(join(lambda r: r.detail)[order], pa.string()),
        }
    )


def station_checks(
    readings: pa.Table,
    site: Site,
    options: QcOptions = DEFAULTS,
    *,
    samples: pa.Table | TableStream | None = None,
) -> tuple[pa.Table, pa.Table]:
    """Check every reading of a point survey (PositionReadings) at ``site``. With the raw
    ``samples`` the readings came from, magnetometers are averaged from them and checked.
    Returns the QcResults rows and the QcSummary per station; raises :class:`QcStop` when a
    check whose policy is ``stop`` fails (the exception carries both tables)."""
    PositionReadings.validate_table(readings)
    sensors = readings_sensors(readings, samples)
    earth = earth_reference(site, magnetic=sensors.mag is not None, model=options.magnetic_model)
    n = readings.num_rows
    station = readings.column("station").to_numpy().astype(np.int64)
    md = float_column(readings, "md")
    keys = Keys(
        station,
        readings.column("position").to_numpy().astype(np.int64),
        md,
        np.full(n, np.nan),
        np.full(n, np.nan),
    )
    recorded, listed, at = recording_checks(readings, options, station, md)
    rows = vector_checks(sensors, earth, options, keys) + rest_checks(readings, options, keys)
    rows += recorded
    if sensors.gyro_axes != "xyz" and n:
        rows.append(fit_checks(readings, sensors, earth, options))
    findings = isolate_rows(rows, station, sensors, earth, options)
    for r in rows:
        if r.check == "earth_rate_fit":
            for s in r.keys.station[r.failed]:
                findings.setdefault(int(s), Finding("undetermined", FIT_UNDETERMINED))
    magnetic = diagnose_magnetic(
        rows, station, sensors, earth, options.isolation_margin, options.tool_errors()
    )
    for s, found in magnetic.items():
        other = findings.get(s)
        findings[s] = (
            Finding(f"{other.suspect}, {found.suspect}", f"{other.diagnosis}; {found.diagnosis}")
            if other is not None
            else found
        )
    qc = results_table(rows)
    summary = _summary(rows, listed, at, findings, options)
    raise_on_stop(qc, options, summary)
    return qc, summary


def _summary(
    rows: list[Rows],
    station: IntArray,
    md: FloatArray,
    findings: dict[int, Finding],
    options: QcOptions,
) -> pa.Table:
    """QcSummary: per station the most severe policy among its failed checks."""
    ids, first = np.unique(station, return_index=True)
    failed: dict[int, set[str]] = {int(s): set() for s in ids}
    for r in rows:
        for s in np.unique(r.keys.station[r.failed]):
            failed[int(s)].add(r.check)
    severity = {s: i for i, s in enumerate(STATUSES)}
    status = []
    for s in ids.tolist():
        policies = [getattr(options, c).policy for c in failed[s]]
        status.append(max(["ok", *policies], key=severity.__getitem__))
    order = {name: i for i, name in enumerate(CHECKS)}
    empty = Finding("", "")
    return QcSummary.compiled().make_table(
        {
            "station": ids,
            "md": md[first],
            "status": status,
            "failed_checks": [
                ",".join(sorted(failed[s], key=order.__getitem__)) for s in ids.tolist()
            ],
            "suspect": [findings.get(s, empty).suspect for s in ids.tolist()],
            "diagnosis": [findings.get(s, empty).diagnosis for s in ids.tolist()],
        }
    )


def raise_on_stop(qc: pa.Table, options: QcOptions, summary: pa.Table | None = None) -> None:
    """Raise :class:`QcStop` for the first failed row (in table order) of a check whose
    policy is ``stop``."""
    stopping = [c for c in CHECKS if getattr(options, c).policy == "stop"]
    if not stopping or qc.num_rows == 0:
        return
    failed = pc.and_(
        pc.is_in(qc.column("check"), pa.array(stopping)),
        pc.equal(pc.fill_null(qc.column("passed"), True), False),
    )
    hits = np.flatnonzero(failed.to_numpy(zero_copy_only=False))
    if hits.size == 0:
        return
    row = qc.slice(int(hits[0]), 1).to_pylist()[0]
    where = (
        f"station {row['station']}"
        if row["station"] is not None
        else f"window {row['window_start']:g}–{row['window_end']:g} s"
    ) + (f" (md {row['md']:g} m)" if row["md"] is not None else "")
    raise QcStop(where, row["check"], row["detail"], qc, summary)


def drop_stations(table: pa.Table, summary: pa.Table) -> pa.Table:
    """``table`` (any table with a ``station`` column) without the stations whose summary
    status is ``drop``."""
    status = summary.column("status").to_numpy(zero_copy_only=False)
    dropped = summary.column("station").to_numpy()[status == "drop"]
    keep = ~np.isin(table.column("station").to_numpy(zero_copy_only=False), dropped)
    return table.filter(pa.array(keep))

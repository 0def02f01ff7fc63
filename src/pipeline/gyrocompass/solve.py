"""Station solver: position readings → inclination, azimuth, toolfaces and their σ.

Per station (DOMAIN.md §5), from the frame positions k:

1. Accelerometers give the inclination I_k and the gravity toolface ψ_k of the frame x axis
   (I = atan2(√(gx²+gy²), gz), ψ = atan2(gy, −gx)); I is their weighted mean.
2. The gyros are fitted by weighted linear least squares against the frame's angle α_k —
   the accelerometer toolface ψ_k in an inclined hole, the frame-angle sensor θ_k near
   vertical (where ψ is ill-defined) — with a bias and a linear trend per gyro axis:
   ``x_k = u cos α_k + v sin α_k + b_x + d_x·(t_k − t̄)``,
   ``y_k = −u sin α_k + v cos α_k + b_y + d_y·(t_k − t̄)``
   (:mod:`pipeline.gyrocompass.fit`: every station's fit at once). Inclined: (u, v) =
   (h, r), the high-side and right-side Earth rate; the azimuth follows
   (:mod:`pipeline.gyrocompass.azimuth`). Near vertical the vertical Earth rate that leaks into
   the transverse gyros through the tilt is removed first (x_k + Ω sin φ·g_x,k/|g|, likewise
   y), leaving (u, v) = Ω cos φ·(n_x, n_y) of the north direction in the reference frame:
   the north-referenced (gyro) toolface Φ = atan2(−n_y, n_x).
3. Residuals against each position's σ give a χ² consistency test (tool moved, frame
   slipped); the frame-angle sensor is checked against the accelerometer toolfaces.
4. The Earth rate the fit found must be the Earth's (:mod:`pipeline.gyrocompass.earth_rate`);
   a station outside is rejected, never solved, and when most stations fail, or any fails by
   a ratio only a rate unit explains, the record's units are wrong and every station is.
   Toward horizontal h carries cos A only through cos I: a station whose mirror azimuth
   180° − A fits about as well (:func:`~pipeline.gyrocompass.azimuth.mirror_probability`
   above ``ambiguity``) is rejected too.
5. σ holds the measured noise and the tool errors the frame positions cannot remove
   (:mod:`pipeline.gyrocompass.systematic`): the gyro's g-dependent bias, the accelerometers'
   bias, misalignment and scale factor.
6. Near vertical the azimuth is the gyro toolface less the gravity toolface, A = Φ − ψ. Where
   the measured horizontal gravity is not ``tilt_detection`` times its σ (noise, the
   accelerometer resolution ``acc_resolution`` and errors) above zero, ψ — and so the
   azimuth — is undefined: NaN, flagged ``azimuth_undefined``, σ NaN; the gyro toolface
   stands.
Rates in °/h, accelerations in m/s², angles in radians internally, degrees in outputs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.earth.frames import FloatArray
from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.gyrocompass.azimuth import mirror_probability, solve_azimuth, tail_sigma
from pipeline.gyrocompass.consistency import chi2_sf
from pipeline.gyrocompass.earth_rate import (
    EarthRate,
    EarthRateReject,
    StationReject,
    earth_rate_check,
    earth_rate_reason,
    failure_hint,
)
from pipeline.gyrocompass.fit import Design, Fit, design, fit_all
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.positions import IntArray, stacks, usual_positions
from pipeline.gyrocompass.precision import OMEGA_DEG_H
from pipeline.gyrocompass.systematic import (
    ToolErrors,
    accelerometer_sigma,
    g_dependent_variance,
)
from pipeline.tables import CompassRejects, CompassStations

MICRO_G = STANDARD_GRAVITY * 1e-6
"""1 µg in m/s²."""


@dataclass
class _Station:
    """One station's readings as arrays (positions in time order) and what its
    accelerometers give (:func:`_tilts`)."""

    station: int
    md: float
    t: FloatArray
    frame: FloatArray | None
    gyro: FloatArray  # (n, axes)
    gyro_sigma: FloatArray  # (n, axes)
    acc: FloatArray  # (n, 3)
    tilt: _Tilt | StationReject


@dataclass(frozen=True)
class _Gravity:
    """What each position's accelerometer reading (m/s²) gives alone, for every position
    (:func:`_gravity`; angles rad)."""

    g: FloatArray
    """|a|, m/s²"""
    transverse: FloatArray
    """|a_xy|, m/s²"""
    inc: FloatArray
    """I_k"""
    psi: FloatArray
    """gravity toolface ψ_k"""
    weight: FloatArray
    """1 / σ²(I_k) of the accelerometer noise and resolution"""
    grad_inc: FloatArray
    """(n, 3): ∂I_k/∂a"""
    across: FloatArray
    """σ(ψ_k) of the noise and resolution"""
    grad_psi: FloatArray
    """(n, 3): ∂ψ_k/∂a"""


@dataclass
class _Row:
    """One solved station; angles in radians until :func:`_table`."""

    station: int
    md: float
    inc: float
    highside_toolface: float
    sigma_inc: float
    bias: float
    trend: float
    residual_rms: float
    chi2: float
    positions: int
    time: float
    flags: list[str]
    azi: float = float("nan")
    gyro_toolface: float = float("nan")
    sigma_azi: float = float("nan")
    sigma_toolface: float = float("nan")
    solver: str = ""
    mode: str = ""


@dataclass
class _Pending:
    """An inclined station waiting for the (vectorised) azimuth solve."""

    row: _Row
    obs: FloatArray
    cov: FloatArray
    psi0: float
    sigma_psi: float


_Solved = tuple[_Row | _Pending, list[EarthRate]]
"""A station solved (or pending the azimuth solve) and its Earth-rate checks."""


def compass(
    readings: pa.Table, latitude: float, options: CompassOptions
) -> tuple[pa.Table, pa.Table]:
    """Solve every station of a PositionReadings table at ``latitude`` (deg). Returns the
    solved stations (CompassStations) and the stations that could not be solved, with why
    (CompassRejects) — never a silently wrong azimuth."""
    axes = _axes(readings, options.gyro_axes)
    tool = options.tool_errors()
    lat = np.radians(latitude)
    rows: list[_Row] = []
    pending: list[_Pending] = []
    rejected: list[tuple[int, float, str]] = []
    implausible: dict[int, list[EarthRate]] = {}  # index in rejected → the failed checks
    good: list[tuple[_Station, _Row | _Pending, list[EarthRate]]] = []
    stations = _stations(readings, axes, options, tool)
    for st, outcome in zip(stations, _solve_all(stations, lat, options, tool), strict=True):
        if isinstance(outcome, StationReject):
            if isinstance(outcome, EarthRateReject):
                implausible[len(rejected)] = outcome.checks
            rejected.append((st.station, st.md, str(outcome)))
        else:
            good.append((st, *outcome))
    checked = len(implausible) + sum(1 for *_, checks in good if checks)
    failed = [c for checks in implausible.values() for c in checks if not c.ok]
    if implausible and (2 * len(implausible) > checked or any(c.looks_like() for c in failed)):
        # the record's gyro rates are implausible (most stations, or a ratio that only a rate
        # unit explains): the stations that seem right are luck — a transverse gyro near
        # I ≈ 90° − φ cannot tell — and the unit the ratios point to is every station's
        hint = failure_hint([c for checks in implausible.values() for c in checks])
        for i, checks in implausible.items():
            station, md, _ = rejected[i]
            rejected[i] = (station, md, earth_rate_reason(checks, latitude, hint))
        most = f"the Earth rate is implausible at {len(implausible)} of {checked} stations"
        for st, _, checks in good:
            here = f"{checks[0].describe(latitude)}, but " if checks else ""
            rejected.append((st.station, st.md, f"{here}{most}: {hint}"))
        good = []
    for _, solved, _ in good:
        if isinstance(solved, _Pending):
            pending.append(solved)
        else:
            rows.append(solved)
    for m in (2, 3):  # one vectorised azimuth solve per observation size
        group = [p for p in pending if len(p.obs) == m]
        if group:
            obs, cov = np.stack([p.obs for p in group]), np.stack([p.cov for p in group])
            inc = np.array([p.row.inc for p in group])
            solution = solve_azimuth(obs, cov, inc, lat, options.azimuth_method)
            mirrored = mirror_probability(
                obs, cov, solution.azimuth, solution.sigma, inc, lat, options.ambiguity
            )
            sigmas = solution.sigma
            if options.azimuth_method == "ml":  # the bound understates a non-linear tail
                sigmas = tail_sigma(obs, cov, solution.azimuth, sigmas, inc, lat)
            for p, azi, sigma, method, odds in zip(
                group, solution.azimuth, sigmas, solution.method, mirrored, strict=True
            ):
                if odds > options.ambiguity:
                    rejected.append((p.row.station, p.row.md, _ambiguous(azi, p.row.inc, odds)))
                else:
                    rows.append(_finish(p, float(azi), float(sigma), str(method), lat))
    rows.sort(key=lambda row: row.station)
    rejected.sort(key=lambda reject: reject[0])
    rejects = {
        "station": [r[0] for r in rejected],
        "md": [r[1] for r in rejected],
        "reason": [r[2] for r in rejected],
    }
    usual = usual_positions(readings.column("station").to_numpy())
    return _table(rows, options, usual), CompassRejects.compiled().make_table(rejects)


def _ambiguous(azimuth: float, inclination: float, probability: float) -> str:
    """Why a station whose azimuth (rad) cannot be told from its mirror is rejected."""
    a = np.degrees(azimuth) % 360.0
    return (
        f"azimuth {a:.1f}° cannot be told from its mirror {(180.0 - a) % 360.0:.1f}° "
        f"(180° − A) at inclination {np.degrees(inclination):.2f}°: the high-side gyro sees "
        f"too little of cos A so near horizontal (mirror probability {probability:.2g}); a "
        "third gyro axis in the fit (z_bias_sigma) or a lower inclination resolves it"
    )


def _table(rows: list[_Row], options: CompassOptions, usual: int) -> pa.Table:
    """CompassStations from solved rows: angles in degrees, the poor-azimuth flag added, and
    the fewer-positions flag where a station has fewer than the survey's ``usual``."""
    for row in rows:
        if row.positions < usual:
            row.flags.append("fewer_positions")
        if "azimuth_undefined" in row.flags:
            continue
        if not np.isfinite(row.sigma_azi) or np.degrees(row.sigma_azi) > options.max_sigma_azi:
            row.flags.append("poor_azimuth")
    columns: dict[str, object] = {
        name: np.array([getattr(r, name) for r in rows])
        for name in _Row.__dataclass_fields__
        if name != "flags"
    }
    for name in ("inc", "sigma_inc", "sigma_azi", "sigma_toolface"):
        columns[name] = np.degrees(np.asarray(columns[name], dtype=float))
    for name in ("azi", "gyro_toolface", "highside_toolface"):
        wrapped = np.degrees(np.asarray(columns[name], dtype=float)) % 360.0
        columns[name] = np.where(wrapped >= 360.0, 0.0, wrapped)
    columns["flags"] = [",".join(r.flags) for r in rows]
    if not rows:  # empty columns need their contract types
        columns = {name: [] for name in columns}
    return CompassStations.compiled().make_table(columns, north_reference="true")


def _axes(readings: pa.Table, wanted: str) -> str:
    present = "".join(a for a in "xyz" if f"gyro_{a}" in readings.column_names)
    axes = present if wanted == "auto" else wanted
    if any(a not in present for a in axes):
        raise ValueError(f"gyro_axes {wanted!r}: the readings have gyro axes {present!r}")
    return axes


def _column(readings: pa.Table, name: str) -> FloatArray | None:
    if name not in readings.column_names:
        return None
    col = readings.column(name)
    return None if col.null_count == len(col) else col.to_numpy(zero_copy_only=False)


def _sigmas(readings: pa.Table, names: list[str], fallback: float | None, what: str) -> FloatArray:
    """σ of each position's mean: std/√n from the readings, else the declared fallback."""
    n = _column(readings, "n")
    stds = [_column(readings, f"{name}_std") for name in names]
    if n is not None and all(s is not None for s in stds):
        return np.stack([s / np.sqrt(n) for s in stds if s is not None], axis=-1)
    if fallback is None:
        raise ValueError(
            f"the readings carry no {what} std/n columns: declare {what}_sigma "
            "(σ of one position's mean reading)"
        )
    return np.full((readings.num_rows, len(names)), fallback)


def _stations(
    readings: pa.Table, axes: str, options: CompassOptions, tool: ToolErrors
) -> list[_Station]:
    gyro_names = [f"gyro_{a}" for a in axes]
    acc_names = ["acc_x", "acc_y", "acc_z"]
    gyro = np.stack([readings.column(n).to_numpy() for n in gyro_names], axis=-1)
    gyro_sigma = np.hypot(
        _sigmas(readings, gyro_names, options.gyro_sigma, "gyro"), options.noise_floor
    )
    acc = np.stack([readings.column(n).to_numpy() for n in acc_names], axis=-1)
    acc_sigma = np.hypot(
        _sigmas(readings, acc_names, options.acc_sigma, "acc"), options.acc_resolution * MICRO_G
    )
    station = readings.column("station").to_numpy()
    frame = _column(readings, "frame_angle")
    t = readings.column("t").to_numpy()
    md = readings.column("md").to_numpy()
    frame = None if frame is None else np.radians(frame)
    starts = np.flatnonzero(np.r_[True, station[1:] != station[:-1]])
    ends = np.r_[starts[1:], len(station)]
    tilts = _tilts(_gravity(acc, acc_sigma), acc, frame, starts, ends - starts, tool, options)
    return [
        _Station(
            int(station[a]),
            float(md[a]),
            t[a:b],
            None if frame is None else frame[a:b],
            gyro[a:b],
            gyro_sigma[a:b],
            acc[a:b],
            tilt,
        )
        for a, b, tilt in zip(starts, ends, tilts, strict=True)
    ]


def _gravity(acc: FloatArray, acc_sigma: FloatArray) -> _Gravity:
    """:class:`_Gravity` of every position at once from its accelerometer readings and their
    σ (n, 3; m/s²): each an elementwise function of its own position's, the same numbers as
    position by position (a reading that is no gravity, or vertical, gives inf or NaN
    here, which :func:`_inclination` never uses)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.linalg.norm(acc, axis=1)
        transverse = np.hypot(acc[:, 0], acc[:, 1])
        inc_k = np.arctan2(transverse, acc[:, 2])
        psi = np.arctan2(acc[:, 1], -acc[:, 0])
        cos_p, sin_p, cos_i, sin_i = np.cos(psi), np.sin(psi), np.cos(inc_k), np.sin(inc_k)
        # σ of I_k: in-plane transverse part (cos I) and axial part (sin I) of the accel noise
        sx, sy, sz = acc_sigma.T
        in_plane = np.hypot(cos_p * sx, sin_p * sy)
        var_k = (cos_i * in_plane) ** 2 + (sin_i * sz) ** 2
        var_k = np.maximum(var_k / g**2, 1e-30)
        grad_inc = np.stack([-cos_p * cos_i, sin_p * cos_i, -sin_i], axis=-1) / g[:, None]
        across = np.hypot(sin_p * sx, cos_p * sy) / transverse
        grad_psi = np.stack([sin_p, cos_p, np.zeros_like(psi)], axis=-1) / transverse[:, None]
    return _Gravity(g, transverse, inc_k, psi, 1.0 / var_k, grad_inc, across, grad_psi)


def _solve_all(
    stations: list[_Station], lat: float, options: CompassOptions, tool: ToolErrors
) -> list[_Solved | StationReject]:
    """Each station solved (or pending the azimuth solve) with its Earth-rate checks, or the
    :class:`StationReject` saying why it cannot be: each station's gyro fit set up alone,
    the fits made together (:func:`pipeline.gyrocompass.fit.fit_all`)."""
    prepared: list[_Prepared | StationReject] = []
    for st in stations:
        if isinstance(st.tilt, StationReject):
            prepared.append(st.tilt)
            continue
        try:
            prepared.append(_prepare(st, st.tilt, lat, options))
        except StationReject as exc:
            prepared.append(exc)
    fits = iter(fit_all([p.design for p in prepared if isinstance(p, _Prepared)]))
    outcomes: list[_Solved | StationReject] = []
    for p in prepared:
        if isinstance(p, StationReject):
            outcomes.append(p)
            continue
        fit = next(fits)
        if isinstance(fit, StationReject):
            outcomes.append(fit)
            continue
        try:
            outcomes.append(_solve(p, fit, lat, options, tool))
        except StationReject as exc:
            outcomes.append(exc)
    return outcomes


@dataclass(frozen=True)
class _Prepared:
    """A station up to its gyro fit: what the accelerometers give, the frame angles the fit
    is referenced to, and the fit's problem."""

    st: _Station
    tilt: _Tilt
    alpha: FloatArray
    design: Design
    flags: list[str]


def _prepare(st: _Station, tilt: _Tilt, lat: float, options: CompassOptions) -> _Prepared:
    """A station's problem of its gyro fit from its ``tilt``; a :class:`StationReject` when
    it cannot be solved."""
    flags = ["frame_mismatch"] if tilt.frame_mismatch else []
    psi, near_vertical = tilt.psi, tilt.near_vertical
    use_frame = near_vertical and st.frame is not None
    alpha = st.frame if use_frame and st.frame is not None else psi
    if use_frame and np.isnan(alpha).any():  # a null frame angle (the sensor's dropout)
        raise StationReject(
            "near vertical and a position without a frame angle to reference the fit"
        )
    gyro = st.gyro
    if near_vertical:  # remove the vertical Earth rate leaking in through the tilt
        down = st.acc / np.linalg.norm(st.acc, axis=1, keepdims=True)
        gyro = gyro + OMEGA_DEG_H * np.sin(lat) * down[:, : gyro.shape[1]]
    if len(st.t) == 1 and gyro.shape[1] >= 2:
        terms = 0  # one position of a multi-axis tool: the general formula, biases stay
        flags.append("bias_not_removed")
    else:
        terms = 2 if options.trend else 1
    problem = design(alpha, st.t, gyro, st.gyro_sigma, terms)
    return _Prepared(st, tilt, alpha, problem, flags)


def _solve(
    p: _Prepared, fit: Fit, lat: float, options: CompassOptions, tool: ToolErrors
) -> _Solved:
    """A prepared station from its gyro fit, solved (or pending the azimuth solve), and its
    Earth-rate checks; a :class:`StationReject` when it cannot be solved."""
    st, tilt, alpha, flags = p.st, p.tilt, p.alpha, p.flags
    near_vertical = tilt.near_vertical
    inc, psi = tilt.inc, tilt.psi
    if fit.dof > 0 and chi2_sf(fit.chi2, fit.dof) < options.consistency:
        flags.append("inconsistent")
    row = _Row(
        station=st.station,
        md=st.md,
        inc=inc,
        highside_toolface=float(psi[0]),
        sigma_inc=tilt.sigma_inc,
        bias=fit.bias,
        trend=fit.trend * 3600.0,
        residual_rms=fit.rms,
        chi2=fit.chi2,
        positions=len(st.t),
        time=float(st.t.mean()),
        flags=flags,
    )
    # the g-dependent gyro bias turns with the frame like the Earth rate: not removed
    uv_cov = fit.cov[:2, :2] + g_dependent_variance(tool, inc) * np.eye(2)
    if not near_vertical:
        obs, cov = fit.uv, uv_cov
        if options.z_bias_sigma is not None and st.gyro.shape[1] == 3:
            var_z = 1.0 / np.sum(1.0 / st.gyro_sigma[:, 2] ** 2) + options.z_bias_sigma**2
            obs = np.append(obs, np.average(st.gyro[:, 2], weights=st.gyro_sigma[:, 2] ** -2))
            cov = np.pad(cov, (0, 1))
            cov[2, 2] = var_z
        checks = _plausible(obs, cov, inc, lat, options)
        return _Pending(row, obs, cov, float(psi[0]), tilt.sigma_psi), checks
    checks = _plausible(fit.uv, uv_cov, inc, lat, options, near_vertical=True)
    # (u, v) = k (n_x, n_y) of north in the reference (frame angle 0, or the high side)
    jac = np.array([fit.uv[1], -fit.uv[0]]) / (fit.uv @ fit.uv)
    row.sigma_toolface = float(np.sqrt(jac @ uv_cov @ jac))
    row.gyro_toolface = float(np.arctan2(-fit.uv[1], fit.uv[0]) + alpha[0])
    row.solver, row.mode = "toolface", "near-vertical"
    if not tilt.defined:  # no horizontal gravity to tell the high side: no azimuth
        row.highside_toolface = float("nan")
        flags.append("azimuth_undefined")
        return row, checks
    # A = Φ − ψ at the first position, ψ − α (frame to high side) averaged over the positions
    d = row.gyro_toolface - alpha[0] - _circmean(psi - alpha)
    row.azi = float(np.arctan2(np.sin(d), np.cos(d) / np.cos(inc)))  # (cos I cos A, −sin A)
    row.sigma_azi = float(np.hypot(row.sigma_toolface, tilt.sigma_psi))
    flags.append("azimuth_from_toolface")  # A = Φ − ψ: as good as the accelerometer ψ
    return row, checks


def _plausible(
    obs: FloatArray,
    cov: FloatArray,
    inc: float,
    lat: float,
    options: CompassOptions,
    *,
    near_vertical: bool = False,
) -> list[EarthRate]:
    """:func:`earth_rate_check`, raising :class:`EarthRateReject` when a component fails."""
    tol = options.earth_rate_tolerance
    checks = earth_rate_check(obs, cov, inc, lat, tol, near_vertical=near_vertical)
    if not all(c.ok for c in checks):
        raise EarthRateReject(earth_rate_reason(checks, float(np.degrees(lat))), checks)
    return checks


def _finish(p: _Pending, azimuth: float, sigma_gyro: float, method: str, lat: float) -> _Row:
    """Complete an inclined station from its azimuth solution (rad)."""
    row = p.row
    row.azi = azimuth
    row.sigma_azi = float(np.hypot(sigma_gyro, _leak(azimuth, row.inc, lat) * row.sigma_inc))
    row.gyro_toolface = gyro_toolface(azimuth, row.inc, p.psi0)
    row.sigma_toolface = float(np.hypot(row.sigma_azi, p.sigma_psi))
    row.solver, row.mode = method, "inclined"
    return row


@dataclass(frozen=True)
class _Tilt:
    """What the accelerometers give at one station (angles rad)."""

    inc: float
    sigma_inc: float
    psi: FloatArray
    """gravity toolface ψ_k of each position"""
    sigma_psi: float
    """σ of the mean frame-to-high-side offset: noise, resolution and accelerometer errors"""
    defined: bool
    """whether the measured horizontal gravity exceeds ``tilt_detection`` times its σ"""
    near_vertical: bool
    """whether I (or 180° − I) is below ``vertical_below``"""
    frame_mismatch: bool
    """whether, inclined, a frame angle departs from its ψ_k by more than ``frame_tolerance``
    beyond their mean offset"""


def _tilts(
    gravity: _Gravity,
    acc: FloatArray,
    frame: FloatArray | None,
    starts: IntArray,
    sizes: IntArray,
    tool: ToolErrors,
    options: CompassOptions,
) -> list[_Tilt | StationReject]:
    """Each station's :class:`_Tilt` (or why it has none), from its positions (``sizes``
    from ``starts``) of every position's ``gravity``, accelerations (m/s²) and frame angles
    (rad): the stations of a size together (:func:`~pipeline.gyrocompass.positions.stacks`,
    :func:`_inclination`)."""
    tilts: dict[int, _Tilt | StationReject] = {}
    for members, rows in stacks(starts, sizes):
        solved = _inclination(gravity, acc, frame, rows, tool, options)
        tilts.update(zip(members.tolist(), solved, strict=True))
    return [tilts[i] for i in range(len(starts))]


def _inclination(
    gravity: _Gravity,
    acc: FloatArray,
    frame: FloatArray | None,
    rows: IntArray,
    tool: ToolErrors,
    options: CompassOptions,
) -> list[_Tilt | StationReject]:
    """Inclination and gravity toolfaces with their σ (noise and the tool's accelerometer
    errors, :mod:`pipeline.gyrocompass.systematic`) of the stations whose positions are
    ``rows`` (stations, n): each station's numbers as alone."""
    g, psi, weight = gravity.g[rows], gravity.psi[rows], gravity.weight[rows]
    wrong = np.any(np.abs(g - STANDARD_GRAVITY) > 0.5 * STANDARD_GRAVITY, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):  # a rejected or vertical station's
        inc = (weight * gravity.inc[rows]).sum(axis=1) / weight.sum(axis=1)
        acc_k = acc[rows]
        sigma_inc = np.hypot(
            np.sqrt(1.0 / weight.sum(axis=1)),
            accelerometer_sigma(gravity.grad_inc[rows], acc_k, weight, tool),
        )
        # exactly vertical: no horizontal gravity at all
        vertical = (gravity.transverse[rows] <= 0).any(axis=1)
        noise = np.sqrt((gravity.across[rows] ** 2).sum(axis=1)) / rows.shape[1]
        sigma_psi = np.hypot(
            noise, accelerometer_sigma(gravity.grad_psi[rows], acc_k, np.ones_like(psi), tool)
        )
    sigma_psi[vertical] = np.inf
    near_vertical = np.minimum(inc, np.pi - inc) < np.radians(options.vertical_below)
    mismatch = np.zeros(len(rows), dtype=bool)
    if frame is not None:
        offset = _wrap(psi - frame[rows])
        spread = np.abs(_wrap(offset - _circmean(offset)[:, None])).max(axis=1)
        mismatch = ~near_vertical & (np.degrees(spread) > options.frame_tolerance)
    tilts: list[_Tilt | StationReject] = []
    for j in range(len(rows)):
        if wrong[j]:
            tilts.append(
                StationReject(
                    f"accelerometers read |g| = {g[j].min():.3g}…{g[j].max():.3g} m/s², not "
                    "gravity: check units and the sign convention"
                )
            )
        elif not np.isfinite(inc[j]):
            tilts.append(StationReject("accelerometer readings give no inclination"))
        else:
            tilts.append(
                _Tilt(
                    float(inc[j]),
                    float(sigma_inc[j]),
                    psi[j],
                    float(sigma_psi[j]),
                    bool(sigma_psi[j] * options.tilt_detection < 1.0),
                    bool(near_vertical[j]),
                    bool(mismatch[j]),
                )
            )
    return tilts


def general_azimuth(rate: FloatArray, accel: FloatArray) -> float:
    """Azimuth (rad) of the tool axis from one three-axis gyro and accelerometer reading
    (DOMAIN.md §5): d = g/|g|, e = d × ω/|d × ω|, n = e × d, A = atan2(e_z, n_z)."""
    down = accel / np.linalg.norm(accel)
    east = np.cross(down, rate)
    east /= np.linalg.norm(east)
    north = np.cross(east, down)
    return float(np.mod(np.arctan2(east[2], north[2]), 2 * np.pi))


def gyro_toolface(azimuth: float, inclination: float, toolface: float) -> float:
    """North-referenced toolface Φ = atan2(−n_y, n_x) of the body x axis (rad), from the
    body's north direction n = C_n^b (1, 0, 0) (equals A + ψ at I = 0)."""
    n_x = np.cos(toolface) * np.cos(inclination) * np.cos(azimuth) - np.sin(toolface) * np.sin(
        azimuth
    )
    n_y = -np.sin(toolface) * np.cos(inclination) * np.cos(azimuth) - np.cos(toolface) * np.sin(
        azimuth
    )
    return float(np.arctan2(-n_y, n_x))


def _leak(azimuth: float, inc: float, lat: float) -> float:
    """|∂A/∂I| at fixed h and r: sin A (cos A tan I − tan φ) (seed 004 Eqs. 8–9)."""
    return float(abs(np.sin(azimuth) * (np.cos(azimuth) * np.tan(inc) - np.tan(lat))))


def _wrap(angle: FloatArray | float) -> FloatArray:
    return np.mod(np.asarray(angle) + np.pi, 2 * np.pi) - np.pi


def _circmean(angle: FloatArray) -> FloatArray:
    """Circular mean (rad) along the last axis."""
    mean: FloatArray = np.arctan2(np.sin(angle).mean(axis=-1), np.cos(angle).mean(axis=-1))
    return mean


def five_position_closed_form(y: FloatArray) -> tuple[float, float]:
    """Seed 004's closed form for readings at ψ0, ψ0+90°, ψ0+180°, ψ0+270°, ψ0 taken at
    equal time steps (corrected, DOMAIN.md §5): the Earth rate along frame x at ψ0 and at
    ψ0 + 90°, free of a constant bias and a linear trend."""
    y0a, y90, y180, y270, y0b = y
    w1 = ((y0a + y0b) / 2 - y180) / 2
    w2 = (y90 - y270) / 2 + (y0b - y0a) / 4
    return float(w1), float(w2)

"""Station solver: position readings → inclination, azimuth, toolfaces and their σ.

Per station (DOMAIN.md §5), from the frame positions k:

1. Accelerometers give the inclination I_k and the gravity toolface ψ_k of the frame x axis
   (I = atan2(√(gx²+gy²), gz), ψ = atan2(gy, −gx)); I is their weighted mean.
2. The gyros are fitted by weighted linear least squares against the frame's angle α_k —
   the accelerometer toolface ψ_k in an inclined hole, the frame-angle sensor θ_k near
   vertical (where ψ is ill-defined) — with a bias and a linear trend per gyro axis:
   ``x_k = u cos α_k + v sin α_k + b_x + d_x·(t_k − t̄)``,
   ``y_k = −u sin α_k + v cos α_k + b_y + d_y·(t_k − t̄)``.
   Inclined: (u, v) = (h, r), the high-side and right-side Earth rate; the azimuth follows
   (:mod:`pipeline.gyrocompass.azimuth`). Near vertical the vertical Earth rate that leaks into
   the transverse gyros through the tilt is removed first (x_k + Ω sin φ·g_x,k/|g|, likewise
   y), leaving (u, v) = Ω cos φ·(n_x, n_y) of the north direction in the reference frame:
   the north-referenced (gyro) toolface Φ = atan2(−n_y, n_x).
3. Residuals against each position's σ give a χ² consistency test (tool moved, frame
   slipped); the frame-angle sensor is checked against the accelerometer toolfaces.
4. The Earth rate the fit found must be the Earth's (DOMAIN.md §3, :func:`earth_rate_check`):
   the horizontal component Ω cos φ and, when the axial gyro joins the fit, the vertical
   Ω sin φ, within ``earth_rate_tolerance`` (relative) and 4 σ of the fitted value. A
   station outside is rejected, never solved: gyro rates in the wrong unit (rad/s or deg/s
   read as °/h), a dead or mis-scaled gyro or a wrong latitude would otherwise give a
   confident, wrong azimuth (a rad/s record compasses to ≈ 180°, σ 1e-5°). A units mistake
   is the whole record's: a transverse gyro pointing near the Earth's axis (I ≈ 90° − φ,
   A ≈ 180°) truly sees almost no Earth rate and cannot tell, so when most stations fail
   the check, or any fails by a ratio only a rate unit explains (:data:`RATE_UNITS`), the
   rest are rejected with them.
Rates in °/h, accelerations in m/s², angles in radians internally, degrees in outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.earth.frames import FloatArray
from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.gyrocompass.azimuth import Method, solve_azimuth
from pipeline.gyrocompass.consistency import chi2_sf
from pipeline.gyrocompass.precision import OMEGA_DEG_H
from pipeline.tables import CompassRejects, CompassStations


class CompassOptions(BaseModel):
    """Compassing parameters (angles deg, rates °/h)."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    latitude: float | None = Field(
        None, ge=-89.9, le=89.9, description="site latitude, deg (default: the well metadata's)"
    )
    gyro_axes: Literal["auto", "x", "xy", "xyz"] = Field(
        "auto", description="gyro axes to use (auto: every gyro column present)"
    )
    azimuth_method: Method = Field("ml", description="ml, auto (sine/atan2), sine or atan2")
    vertical_below: float = Field(
        3.0, gt=0, lt=45, description="inclination below which the near-vertical mode is used"
    )
    trend: bool = Field(True, description="fit a linear gyro trend (needs enough positions)")
    gyro_sigma: float | None = Field(
        None,
        gt=0,
        description="σ of one position's mean gyro reading when the readings "
        "carry no std/n columns",
    )
    acc_sigma: float | None = Field(
        None, gt=0, description="σ of one position's mean acceleration, m/s², likewise"
    )
    noise_floor: float = Field(
        0.0, ge=0, description="added in quadrature to each position's gyro σ (bias instability)"
    )
    consistency: float = Field(
        1e-3, gt=0, lt=1, description="χ² tail probability below which a station is flagged"
    )
    frame_tolerance: float = Field(
        2.0, gt=0, description="largest disagreement of frame angle and accelerometer toolface"
    )
    max_sigma_azi: float = Field(5.0, gt=0, description="σ_azi above which a station is flagged")
    z_bias_sigma: float | None = Field(
        None,
        gt=0,
        description="σ of the axial gyro's bias, °/h: when given, a three-axis "
        "tool's z gyro joins the azimuth fit (its bias is not removed by turning the frame)",
    )
    earth_rate_tolerance: float = Field(
        0.2,
        gt=0,
        lt=1,
        description="largest relative departure of the fitted horizontal Earth rate from "
        "Ω cos φ (and, when the z gyro joins the fit, of the vertical one from Ω sin φ), "
        "beyond 4 σ of the fit, before a station is rejected (rates in the wrong unit, a "
        "dead or mis-scaled gyro, a wrong latitude)",
    )


@dataclass
class _Station:
    """One station's readings as arrays (positions in time order)."""

    station: int
    md: float
    t: FloatArray
    frame: FloatArray | None
    gyro: FloatArray  # (n, axes)
    gyro_sigma: FloatArray  # (n, axes)
    acc: FloatArray  # (n, 3)
    acc_sigma: FloatArray  # (n, 3)


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


EARTH_RATE_SIGMAS = 4.0
"""Multiples of the fitted Earth rate's σ added (in quadrature) to the relative tolerance."""
RATE_UNITS = {
    "rad/s": np.radians(1.0) / 3600.0,
    "deg/s": 1.0 / 3600.0,
    "mrad/s": np.radians(1.0) / 3.6,
}
"""What 1 °/h reads as in other rate units: the ratio of fitted to expected Earth rate that a
record in that unit, taken for °/h, shows (a factor 17 or more apart from each other)."""
LOOKS_LIKE = 2.0
"""A ratio within this factor of a unit's (:data:`RATE_UNITS`) names the unit in the hint."""


@dataclass(frozen=True)
class EarthRate:
    """One component of the Earth rate a station's gyro fit found, against the Earth's."""

    component: str
    """``horizontal`` or ``vertical``"""
    fitted: float
    """°/h"""
    expected: float
    """°/h (the vertical is positive up: Ω sin φ)"""
    limit: float
    """largest allowed |fitted − expected|, °/h"""

    @property
    def ok(self) -> bool:
        return bool(abs(self.fitted - self.expected) <= self.limit)

    @property
    def ratio(self) -> float:
        return self.fitted / self.expected if self.expected else float("nan")

    def describe(self, latitude: float) -> str:
        """``fitted horizontal Earth rate 0.000035 °/h is 0.0000048× the expected 7.24 °/h
        at 61.25° N``."""
        where = f"{abs(latitude):.2f}° {'N' if latitude >= 0 else 'S'}"
        times = f" is {_figures(self.ratio)}×" if self.expected else ","
        return (
            f"fitted {self.component} Earth rate {_figures(self.fitted)} °/h{times} the "
            f"expected {self.expected:.2f} °/h at {where}"
        )

    def looks_like(self) -> str:
        """The rate unit whose factor the ratio matches within :data:`LOOKS_LIKE`
        (``they look like rad/s``; the inverse for °/h converted as if in that unit), or ''."""
        if not self.expected or not self.ratio > 0:
            return ""
        for unit, factor in RATE_UNITS.items():
            if abs(np.log(self.ratio / factor)) <= np.log(LOOKS_LIKE):
                return f"they look like {unit}"
            if abs(np.log(self.ratio * factor)) <= np.log(LOOKS_LIKE):
                return f"they look like °/h converted as if they were {unit}"
        return ""


HINT = "are the gyro rates in °/h?"


def _figures(value: float) -> str:
    """Two significant figures without an exponent (``0.000035``, ``7.2``, ``1800``)."""
    if not np.isfinite(value) or value == 0:
        return f"{value:g}"
    return str(np.format_float_positional(value, precision=2, fractional=False, trim="-"))


def _hint(checks: list[EarthRate]) -> str:
    """The question to ask, and the unit the failed checks' ratios point to if any."""
    looks = next((c.looks_like() for c in checks if not c.ok and c.looks_like()), "")
    return f"{HINT} ({looks})" if looks else HINT


def _earth_rate_reason(checks: list[EarthRate], latitude: float, hint: str = "") -> str:
    """Why a station's Earth rate is implausible: each failed component, then the hint
    (default: the question, with the unit its own ratios point to)."""
    text = "; ".join(c.describe(latitude) for c in checks if not c.ok)
    return f"{text}: {hint or _hint(checks)}"


@dataclass
class _Pending:
    """An inclined station waiting for the (vectorised) azimuth solve."""

    row: _Row
    obs: FloatArray
    cov: FloatArray
    psi0: float
    sigma_psi: float


def compass(
    readings: pa.Table, latitude: float, options: CompassOptions
) -> tuple[pa.Table, pa.Table]:
    """Solve every station of a PositionReadings table at ``latitude`` (deg). Returns the
    solved stations (CompassStations) and the stations that could not be solved, with why
    (CompassRejects) — never a silently wrong azimuth."""
    axes = _axes(readings, options.gyro_axes)
    lat = np.radians(latitude)
    rows: list[_Row] = []
    pending: list[_Pending] = []
    rejected: list[tuple[int, float, str]] = []
    implausible: dict[int, list[EarthRate]] = {}  # index in rejected → the failed checks
    good: list[tuple[_Station, _Row | _Pending, list[EarthRate]]] = []
    for st in _stations(readings, axes, options):
        try:
            solved, checks = _solve(st, lat, options)
        except StationReject as exc:
            if isinstance(exc, EarthRateReject):
                implausible[len(rejected)] = exc.checks
            rejected.append((st.station, st.md, str(exc)))
            continue
        good.append((st, solved, checks))
    checked = len(implausible) + sum(1 for *_, checks in good if checks)
    failed = [c for checks in implausible.values() for c in checks if not c.ok]
    if implausible and (2 * len(implausible) > checked or any(c.looks_like() for c in failed)):
        # the record's gyro rates are implausible (most stations, or a ratio that only a rate
        # unit explains): the stations that seem right are luck — a transverse gyro near
        # I ≈ 90° − φ cannot tell — and the unit the ratios point to is every station's
        hint = _hint([c for checks in implausible.values() for c in checks])
        for i, checks in implausible.items():
            station, md, _ = rejected[i]
            rejected[i] = (station, md, _earth_rate_reason(checks, latitude, hint))
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
            solution = solve_azimuth(
                np.stack([p.obs for p in group]),
                np.stack([p.cov for p in group]),
                np.array([p.row.inc for p in group]),
                lat,
                options.azimuth_method,
            )
            for p, azi, sigma, method in zip(
                group, solution.azimuth, solution.sigma, solution.method, strict=True
            ):
                rows.append(_finish(p, float(azi), float(sigma), str(method), lat))
    rows.sort(key=lambda row: row.station)
    rejected.sort(key=lambda reject: reject[0])
    rejects = {
        "station": [r[0] for r in rejected],
        "md": [r[1] for r in rejected],
        "reason": [r[2] for r in rejected],
    }
    return _table(rows, options), CompassRejects.compiled().make_table(rejects)


class StationReject(Exception):
    """A station that cannot be solved, and why."""


class EarthRateReject(StationReject):
    """A station whose fitted Earth rate is not the Earth's (:func:`earth_rate_check`)."""

    def __init__(self, message: str, checks: list[EarthRate]) -> None:
        self.checks = checks
        super().__init__(message)


def earth_rate_check(
    obs: FloatArray,
    cov: FloatArray,
    inclination: float,
    latitude: float,
    tolerance: float,
    *,
    near_vertical: bool = False,
) -> list[EarthRate]:
    """The Earth rate a station's fit found, against the Earth's (DOMAIN.md §3), per
    component; latitude and inclination in radians, rates in °/h.

    ``obs`` with covariance ``cov``: inclined, the high-side and right-side components
    (h, r) or, when the axial gyro joins the fit, (h, r, z); near vertical, the transverse
    components (u, v) of the tilt-corrected fit, Ω cos φ times north's. The horizontal
    component, against k = Ω cos φ, is

    - near vertical: √(u² + v²) (low by at most 1 − cos I);
    - from (h, r, z), free of any assumption: √((h cos I + z sin I)² + r²), and the
      vertical h sin I − z cos I against Ω sin φ;
    - from (h, r) alone: √(((h − Ω sin φ sin I)/cos I)² + r²), the vertical share taken
      from the latitude (the azimuth solver does the same); nothing near horizontal, where
      cos I → 0 leaves it undetermined.

    Each component may depart from its expected value by
    ``√((tolerance·expected)² + (4σ)²)``, σ propagated from ``cov`` (first order).
    """
    k = OMEGA_DEG_H * np.cos(latitude)
    up = OMEGA_DEG_H * np.sin(latitude)
    ci, si = np.cos(inclination), np.sin(inclination)
    parts: list[tuple[str, float, FloatArray, float]] = []
    if near_vertical:
        value = float(np.hypot(obs[0], obs[1]))
        parts.append(("horizontal", value, obs[:2] / (value or 1.0), k))
    elif len(obs) == 3:
        h, r, z = obs
        along = h * ci + z * si
        value = float(np.hypot(along, r))
        grad = np.array([along * ci, r, along * si]) / (value or 1.0)
        parts.append(("horizontal", value, grad, k))
        parts.append(("vertical", float(h * si - z * ci), np.array([si, 0.0, -ci]), up))
    elif abs(ci) > 1e-6:
        h, r = obs[:2]
        along = (h - up * si) / ci
        value = float(np.hypot(along, r))
        parts.append(("horizontal", value, np.array([along / ci, r]) / (value or 1.0), k))
    checks = []
    for component, value, grad, expected in parts:
        sigma = float(np.sqrt(grad @ cov[: len(grad), : len(grad)] @ grad))
        limit = float(np.hypot(tolerance * abs(expected), EARTH_RATE_SIGMAS * sigma))
        checks.append(EarthRate(component, value, float(expected), limit))
    return checks


def _table(rows: list[_Row], options: CompassOptions) -> pa.Table:
    """CompassStations from solved rows: angles in degrees, the poor-azimuth flag added."""
    for row in rows:
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


def _stations(readings: pa.Table, axes: str, options: CompassOptions) -> list[_Station]:
    gyro_names = [f"gyro_{a}" for a in axes]
    acc_names = ["acc_x", "acc_y", "acc_z"]
    gyro = np.stack([readings.column(n).to_numpy() for n in gyro_names], axis=-1)
    gyro_sigma = np.hypot(
        _sigmas(readings, gyro_names, options.gyro_sigma, "gyro"), options.noise_floor
    )
    acc = np.stack([readings.column(n).to_numpy() for n in acc_names], axis=-1)
    acc_sigma = _sigmas(readings, acc_names, options.acc_sigma, "acc")
    station = readings.column("station").to_numpy()
    frame = _column(readings, "frame_angle")
    t = readings.column("t").to_numpy()
    md = readings.column("md").to_numpy()
    starts = np.flatnonzero(np.r_[True, station[1:] != station[:-1]])
    ends = np.r_[starts[1:], len(station)]
    return [
        _Station(
            int(station[a]),
            float(md[a]),
            t[a:b],
            None if frame is None else np.radians(frame[a:b]),
            gyro[a:b],
            gyro_sigma[a:b],
            acc[a:b],
            acc_sigma[a:b],
        )
        for a, b in zip(starts, ends, strict=True)
    ]


def _solve(
    st: _Station, lat: float, options: CompassOptions
) -> tuple[_Row | _Pending, list[EarthRate]]:
    """One station, solved (or pending the azimuth solve), and its Earth-rate checks; a
    :class:`StationReject` when it cannot be solved."""
    flags: list[str] = []
    inc, sigma_inc, psi, sigma_psi = _inclination(st)
    near_vertical = min(inc, np.pi - inc) < np.radians(options.vertical_below)
    if st.frame is not None:
        offset = _wrap(psi - st.frame)
        spread = np.abs(_wrap(offset - _circmean(offset)))
        if not near_vertical and np.degrees(spread.max()) > options.frame_tolerance:
            flags.append("frame_mismatch")
    use_frame = near_vertical and st.frame is not None
    alpha = st.frame if use_frame and st.frame is not None else psi
    gyro = st.gyro.copy()
    if near_vertical:  # remove the vertical Earth rate leaking in through the tilt
        down = st.acc / np.linalg.norm(st.acc, axis=1, keepdims=True)
        gyro += OMEGA_DEG_H * np.sin(lat) * down[:, : gyro.shape[1]]
    if len(st.t) == 1 and gyro.shape[1] >= 2:
        terms = 0  # one position of a multi-axis tool: the general formula, biases stay
        flags.append("bias_not_removed")
    else:
        terms = 2 if options.trend else 1
    fit = fit_positions(alpha, st.t, gyro, st.gyro_sigma, terms)
    if fit.dof > 0 and chi2_sf(fit.chi2, fit.dof) < options.consistency:
        flags.append("inconsistent")
    row = _Row(
        station=st.station,
        md=st.md,
        inc=inc,
        highside_toolface=float(psi[0]),
        sigma_inc=sigma_inc,
        bias=fit.bias,
        trend=fit.trend * 3600.0,
        residual_rms=fit.rms,
        chi2=fit.chi2,
        positions=len(st.t),
        time=float(st.t.mean()),
        flags=flags,
    )
    if not near_vertical:
        obs, cov = fit.uv, fit.cov[:2, :2]
        if options.z_bias_sigma is not None and st.gyro.shape[1] == 3:
            var_z = 1.0 / np.sum(1.0 / st.gyro_sigma[:, 2] ** 2) + options.z_bias_sigma**2
            obs = np.append(obs, np.average(st.gyro[:, 2], weights=st.gyro_sigma[:, 2] ** -2))
            cov = np.pad(cov, (0, 1))
            cov[2, 2] = var_z
        checks = _plausible(obs, cov, inc, lat, options)
        return _Pending(row, obs, cov, float(psi[0]), sigma_psi), checks
    checks = _plausible(fit.uv, fit.cov[:2, :2], inc, lat, options, near_vertical=True)
    # (u, v) = k (n_x, n_y) of north in the reference (frame angle 0, or the high side)
    jac = np.array([fit.uv[1], -fit.uv[0]]) / (fit.uv @ fit.uv)
    row.sigma_toolface = float(np.sqrt(jac @ fit.cov[:2, :2] @ jac))
    row.gyro_toolface = float(np.arctan2(-fit.uv[1], fit.uv[0]) + alpha[0])
    d = row.gyro_toolface - psi[0]  # (cos I cos A, −sin A) ∝ (cos d, −sin d)
    row.azi = float(np.arctan2(np.sin(d), np.cos(d) / np.cos(inc)))
    row.sigma_azi = float(np.hypot(row.sigma_toolface, sigma_psi))
    row.solver, row.mode = "toolface", "near-vertical"
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
        raise EarthRateReject(_earth_rate_reason(checks, float(np.degrees(lat))), checks)
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


def _inclination(st: _Station) -> tuple[float, float, FloatArray, float]:
    """Inclination (rad) and its σ; per-position toolface ψ_k (rad) and σ of ψ."""
    g = np.linalg.norm(st.acc, axis=1)
    transverse = np.hypot(st.acc[:, 0], st.acc[:, 1])
    if np.any(np.abs(g - STANDARD_GRAVITY) > 0.5 * STANDARD_GRAVITY):
        raise StationReject(
            f"accelerometers read |g| = {g.min():.3g}…{g.max():.3g} m/s², not gravity: "
            "check units and the sign convention"
        )
    inc_k = np.arctan2(transverse, st.acc[:, 2])
    psi = np.arctan2(st.acc[:, 1], -st.acc[:, 0])
    # σ of I_k: in-plane transverse part (cos I) and axial part (sin I) of the accel noise
    sx, sy, sz = st.acc_sigma.T
    in_plane = np.hypot(np.cos(psi) * sx, np.sin(psi) * sy)
    var_k = (np.cos(inc_k) * in_plane) ** 2 + (np.sin(inc_k) * sz) ** 2
    var_k = np.maximum(var_k / g**2, 1e-30)
    weight = 1.0 / var_k
    inc = float(np.sum(weight * inc_k) / weight.sum())
    sigma_inc = float(np.sqrt(1.0 / weight.sum()))
    across = np.hypot(np.sin(psi) * sx, np.cos(psi) * sy)
    sigma_psi = float(np.sqrt(np.mean((across / np.maximum(transverse, 1e-12)) ** 2) / len(psi)))
    if not np.isfinite(inc) or len(inc_k) == 0:
        raise StationReject("accelerometer readings give no inclination")
    return inc, sigma_inc, psi, sigma_psi


@dataclass(frozen=True)
class _Fit:
    uv: FloatArray
    cov: FloatArray
    bias: float
    trend: float
    rms: float
    chi2: float
    dof: int


def fit_positions(
    alpha: FloatArray, t: FloatArray, gyro: FloatArray, sigma: FloatArray, terms: int
) -> _Fit:
    """Weighted least squares of the gyro readings (see the module docstring) with
    ``terms`` extra unknowns per transverse axis: 0 none, 1 a bias, 2 a bias and a trend."""
    n, m = gyro.shape
    if not np.all(sigma > 0):
        raise StationReject("a position's gyro σ is zero (noise-free data?): set noise_floor")
    tau = t - t.mean()
    c, s = np.cos(alpha), np.sin(alpha)
    axes = min(m, 2)
    columns = 2 + terms * axes
    a = np.zeros((n * axes, columns))
    for axis in range(axes):
        block = a[axis * n : (axis + 1) * n]
        block[:, 0], block[:, 1] = (c, s) if axis == 0 else (-s, c)
        if terms:
            block[:, 2 + terms * axis] = 1.0
        if terms == 2:
            block[:, 3 + terms * axis] = tau
    y = gyro[:, :axes].T.ravel()
    w = 1.0 / sigma[:, :axes].T.ravel() ** 2
    if len(y) < columns:
        what = ("Earth rate", "bias", "trend")[: 1 + terms]
        raise StationReject(
            f"{n} position(s) cannot resolve {columns} unknowns ({', '.join(what)}); "
            "use more positions or trend: false"
        )
    normal = a.T @ (a * w[:, None])
    if np.linalg.cond(normal) > 1e10:
        raise StationReject("the frame positions do not span the circle (ill-conditioned fit)")
    cov = np.asarray(np.linalg.inv(normal), dtype=np.float64)
    params = cov @ (a.T @ (w * y))
    res = y - a @ params
    return _Fit(
        uv=params[:2],
        cov=cov,
        bias=float(params[2]) if terms else 0.0,
        trend=float(params[3]) if terms == 2 else 0.0,
        rms=float(np.sqrt(np.mean(res**2))),
        chi2=float(np.sum(w * res**2)),
        dof=len(y) - columns,
    )


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


def _circmean(angle: FloatArray) -> float:
    return float(np.arctan2(np.sin(angle).mean(), np.cos(angle).mean()))


def five_position_closed_form(y: FloatArray) -> tuple[float, float]:
    """Seed 004's closed form for readings at ψ0, ψ0+90°, ψ0+180°, ψ0+270°, ψ0 taken at
    equal time steps (corrected, DOMAIN.md §5): the Earth rate along frame x at ψ0 and at
    ψ0 + 90°, free of a constant bias and a linear trend."""
    y0a, y90, y180, y270, y0b = y
    w1 = ((y0a + y0b) / 2 - y180) / 2
    w2 = (y90 - y270) / 2 + (y0b - y0a) / 4
    return float(w1), float(w2)

"""Azimuth from the Earth-rate components seen by the gyros (DOMAIN.md §5).

With k = Ω cos φ and s = Ω sin φ, the high-side, right-side and axial components are
``h = k cos A cos I + s sin I``, ``r = −k sin A``, ``z = k cos A sin I − s cos I``.
Estimators, vectorised over stations (angles in radians, rates in °/h):

- ``sine``: sin A = −r/k, the A ↔ 180° − A ambiguity resolved by the sign of cos A from h;
- ``atan2``: A = atan2(−r, (h − s sin I)/cos I);
- ``auto``: whichever of those two has the smaller predicted error at (A, I, φ);
- ``ml``: the maximum-likelihood A fitting all observed components with their covariance
  (h, r, and z when a three-axis tool gives it) — a 1-D search (5° grid, then Newton); its
  σ is the Cramér–Rao bound, never worse than either closed form. At I = 90° a transverse
  pair cannot tell A from 180° − A (h carries no cos A), and toward it the σ at either
  answer stays small: :func:`mirror_probability` says how likely the other one is. Toward
  east–west at high inclination the misfit is far from its parabola and the bound
  understates the tail: :func:`tail_sigma` gives the σ the compass stage states.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.precision import OMEGA_DEG_H

Method = Literal["ml", "auto", "sine", "atan2"]
GRID = np.radians(np.arange(0.0, 360.0, 5.0))
TINY = 1e-12
MIRROR_STEP = np.radians(1.0)
MIRROR_GRID = np.arange(360) * MIRROR_STEP
"""Azimuths (rad) searched for the misfit's minima on the other side of east–west (each
refined by the parabola through its grid neighbours)."""
MIRROR_SIGMAS = 3.0
"""A mirror azimuth nearer than this many σ of the solution is within its stated error."""
TAIL_LEVEL = 9.0
"""Δχ² bounding the region whose reach is 3σ (:func:`tail_sigma`)."""
TAIL_SLACK = 0.1
"""How far (fraction) that reach may exceed 3·σ_CR before σ_CR gives way: observed
curvature alone spreads it ±7 % (99.9 %) about 3·σ_CR at well-conditioned stations."""
TAIL_SLACK_REACH = MIRROR_SIGMAS * (1 + TAIL_SLACK)
TAIL_BOUNDS = 129
"""Edges of the geometric intervals, slack reach to 180°, of :func:`tail_sigma`'s floor."""
TAIL_STEP = np.radians(0.1)
TAIL_HALF = 1800
TAIL_OFFSETS = np.arange(-TAIL_HALF, TAIL_HALF + 1) * TAIL_STEP
"""Offsets (rad) from the solution searched for the reach, −180° to 180°."""


@dataclass(frozen=True)
class AzimuthSolution:
    """Azimuth (rad, [0, 2π)), its predicted σ (rad) and the estimator used, per station."""

    azimuth: FloatArray
    sigma: FloatArray
    method: np.ndarray


def model(azimuth: FloatArray, inclination: FloatArray, latitude: float, m: int) -> FloatArray:
    """Expected (h, r[, z]) in °/h, shape (..., m), for azimuths (rad) and inclinations."""
    k, s = OMEGA_DEG_H * np.cos(latitude), OMEGA_DEG_H * np.sin(latitude)
    cos_a, sin_a = np.cos(azimuth), np.sin(azimuth)
    parts = [k * cos_a * np.cos(inclination) + s * np.sin(inclination), -k * sin_a]
    if m == 3:
        parts.append(k * cos_a * np.sin(inclination) - s * np.cos(inclination))
    return np.stack(np.broadcast_arrays(*parts), axis=-1)


def jacobian(azimuth: FloatArray, inclination: FloatArray, latitude: float, m: int) -> FloatArray:
    """∂(h, r[, z])/∂A, shape (..., m)."""
    k = OMEGA_DEG_H * np.cos(latitude)
    parts = [-k * np.sin(azimuth) * np.cos(inclination), -k * np.cos(azimuth)]
    if m == 3:
        parts.append(-k * np.sin(azimuth) * np.sin(inclination))
    return np.stack(np.broadcast_arrays(*parts), axis=-1)


def solve_azimuth(
    obs: FloatArray,
    cov: FloatArray,
    inclination: FloatArray,
    latitude: float,
    method: Method = "ml",
) -> AzimuthSolution:
    """Azimuth of each station from observations (n, m) = (h, r[, z]) in °/h with
    covariance (n, m, m), inclination (rad) and latitude (rad)."""
    n = obs.shape[0]
    k, s = OMEGA_DEG_H * np.cos(latitude), OMEGA_DEG_H * np.sin(latitude)
    cos_i = np.cos(inclination)
    safe_cos_i = np.where(np.abs(cos_i) < TINY, TINY, cos_i)
    horizontal = obs[:, 0] - s * np.sin(inclination)  # k cos A cos I
    a_atan2 = np.arctan2(-obs[:, 1], horizontal / safe_cos_i)
    if method == "ml":
        azimuth = _maximum_likelihood(obs, cov, inclination, latitude, a_atan2)
        used = np.full(n, "ml", dtype=object)
        sigma = cramer_rao(azimuth, inclination, latitude, cov)
    else:
        sin_a = np.clip(-obs[:, 1] / k, -1.0, 1.0)
        a_sine = np.where(
            horizontal * np.sign(safe_cos_i) >= 0, np.arcsin(sin_a), np.pi - np.arcsin(sin_a)
        )
        cos_a = np.cos(a_atan2)
        grad_atan2 = np.stack([-np.sin(a_atan2) / (k * safe_cos_i), -cos_a / k], axis=-1)
        grad_sine = np.stack(
            [np.zeros(n), -1.0 / (k * np.where(np.abs(cos_a) < TINY, TINY, cos_a))], axis=-1
        )
        hr = cov[:, :2, :2]
        var_atan2 = np.einsum("ni,nij,nj->n", grad_atan2, hr, grad_atan2)
        var_sine = np.einsum("ni,nij,nj->n", grad_sine, hr, grad_sine)
        use_sine = var_sine < var_atan2 if method == "auto" else np.full(n, method == "sine")
        azimuth = np.where(use_sine, a_sine, a_atan2)
        sigma = np.sqrt(np.where(use_sine, var_sine, var_atan2))
        used = np.where(use_sine, "sine", "atan2").astype(object)
    return AzimuthSolution(np.mod(azimuth, 2 * np.pi), sigma, used)


def cramer_rao(
    azimuth: FloatArray, inclination: FloatArray, latitude: float, cov: FloatArray
) -> FloatArray:
    """σ (rad) of the maximum-likelihood azimuth from observations with covariance
    ``cov`` (..., m, m) in (°/h)²: 1/√(Jᵀ Σ⁻¹ J), J = ∂(h, r[, z])/∂A (∞ if unobservable)."""
    jac = jacobian(azimuth, inclination, latitude, cov.shape[-1])
    info = np.einsum("...i,...ij,...j->...", jac, np.linalg.inv(cov), jac)
    sigma: FloatArray = 1.0 / np.sqrt(np.maximum(info, 1e-300))
    return sigma


def tail_sigma(
    obs: FloatArray,
    cov: FloatArray,
    azimuth: FloatArray,
    sigma: FloatArray,
    inclination: FloatArray,
    latitude: float,
) -> FloatArray:
    """σ (rad) of each maximum-likelihood ``azimuth`` (rad) that its likelihood bears out:
    ``sigma`` (the Cramér–Rao bound, rad), or r/3 where the region of Δχ² ≤ 9 about the
    solution reaches r > 3·(1 + :data:`TAIL_SLACK`)·``sigma`` — toward east–west at high
    inclination the misfit is far from its parabola and the bound understates the tail.
    Observations (n, m) in °/h with covariance (n, m, m).

    At an offset δ the excess misfit is exactly 4 sin²(δ/2)·(uᵀ·quad·u − μ), u the unit
    tangent at A + δ/2 and μ the misfit's gradient along (cos A, sin A) at the solution; a
    floor of it over :data:`TAIL_BOUNDS` intervals past the slack reach spares the search
    (:data:`TAIL_STEP`, the crossing interpolated) to stations whose floor drops to 9."""
    quad, linear, _ = _misfit_form(obs, cov, inclination, latitude)
    cos_a, sin_a = np.cos(azimuth), np.sin(azimuth)
    mu = _quadratic(quad, linear, cos_a, sin_a) + linear[:, 0] * cos_a + linear[:, 1] * sin_a
    # uᵀ·quad·u − μ at A + δ/2 is mean − a·cos δ + b·sin δ, a sinusoid of amplitude `spread`:
    # ≥ max(mean − spread, its value at A − spread·|δ|)
    half, cross = 0.5 * (quad[:, 0, 0] - quad[:, 1, 1]), quad[:, 0, 1]
    mean = 0.5 * (quad[:, 0, 0] + quad[:, 1, 1]) - mu
    cos_2a, sin_2a = np.cos(2 * azimuth), np.sin(2 * azimuth)
    a, b = half * cos_2a + cross * sin_2a, half * sin_2a - cross * cos_2a
    spread = np.hypot(half, cross)
    edges = np.geomspace(np.minimum(TAIL_SLACK_REACH * sigma, np.pi), np.pi, TAIL_BOUNDS).T
    lowest = np.maximum(
        (mean - spread)[:, None], (mean - a)[:, None] - spread[:, None] * edges[:, 1:]
    )
    floor = 2 * (1 - np.cos(edges[:, :-1])) * lowest
    # the excess clears Δχ² = 9 everywhere past the slack reach unless some interval's
    # floor does not: only those stations are searched
    near = np.flatnonzero(np.any(floor <= TAIL_LEVEL, axis=1))
    out: FloatArray = sigma.copy()
    if near.size == 0:
        return out
    cos_d, sin_d = np.cos(TAIL_OFFSETS), np.sin(TAIL_OFFSETS)
    along = mean[near, None] - a[near, None] * cos_d + b[near, None] * sin_d
    excess = 2 * (1 - cos_d) * along
    reach = np.zeros(near.size)
    for side in (excess[:, TAIL_HALF:], excess[:, TAIL_HALF::-1]):  # δ ≥ 0, δ ≤ 0
        inside = side <= TAIL_LEVEL
        last = TAIL_HALF - np.argmax(inside[:, ::-1], axis=1)
        nxt = np.minimum(last + 1, TAIL_HALF)
        rows = np.arange(near.size)
        f0, f1 = side[rows, last], side[rows, nxt]
        frac = np.where(nxt > last, (TAIL_LEVEL - f0) / np.maximum(f1 - f0, TINY), 0.0)
        reach = np.maximum(reach, TAIL_STEP * (last + np.clip(frac, 0.0, 1.0)))
    wide = reach > TAIL_SLACK_REACH * sigma[near]
    out[near[wide]] = reach[wide] / MIRROR_SIGMAS
    return out


def _maximum_likelihood(
    obs: FloatArray,
    cov: FloatArray,
    inclination: FloatArray,
    latitude: float,
    start: FloatArray,
) -> FloatArray:
    """argmin over A of the Mahalanobis misfit of the observations to :func:`model`."""
    n, m = obs.shape
    weight = np.linalg.inv(cov)
    candidates = np.concatenate([start[:, None], np.broadcast_to(GRID, (n, len(GRID)))], axis=1)
    res = obs[:, None, :] - model(candidates, inclination[:, None], latitude, m)
    misfit = np.einsum("nci,nij,ncj->nc", res, weight, res)
    a = candidates[np.arange(n), np.argmin(misfit, axis=1)]
    for _ in range(10):
        res = obs - model(a, inclination, latitude, m)
        d1 = jacobian(a, inclination, latitude, m)
        # second derivative of the model: −(model without its A-independent part)
        d2 = -(model(a, inclination, latitude, m) - model_offset(inclination, latitude, m))
        grad = -2 * np.einsum("ni,nij,nj->n", d1, weight, res)
        hess = 2 * (
            np.einsum("ni,nij,nj->n", d1, weight, d1) - np.einsum("ni,nij,nj->n", d2, weight, res)
        )
        step = np.where(hess > 0, grad / np.where(hess > 0, hess, 1.0), 0.0)
        a = a - np.clip(step, -0.2, 0.2)
    out: FloatArray = a
    return out


def mirror_probability(
    obs: FloatArray,
    cov: FloatArray,
    azimuth: FloatArray,
    sigma: FloatArray,
    inclination: FloatArray,
    latitude: float,
    floor: float,
) -> FloatArray:
    """Probability, for equal priors, that each station's azimuth lies on the other side of
    east–west from its solution ``azimuth`` (rad, σ ``sigma`` rad), given observations
    (n, m) with covariance (n, m, m). Only h (through cos I) and z (through sin I) see the
    sign of cos A, so toward horizontal a transverse gyro's readings fit A and its mirror
    180° − A almost alike. 1/(1 + exp(Δχ²/2)), Δχ² the excess of the least misfit of a
    minimum on the other side (:data:`MIRROR_GRID`) over A's; 0 where the other side
    holds no minimum or it is within :data:`MIRROR_SIGMAS` σ of A (the doubt σ states),
    and where it cannot reach ``floor``."""
    quad, linear, constant = _misfit_form(obs, cov, inclination, latitude)
    cos_a = np.cos(azimuth)
    own_part = _quadratic(quad, linear, cos_a, np.sin(azimuth))
    own = np.maximum(constant + own_part, 0.0)
    # a model across east–west differs from A's by ≥ |cos A| in cos, which sin cannot take
    # up: its misfit is ≥ (reach − √own)², the triangle inequality in the weighted norm
    schur = np.maximum(quad[:, 0, 0] - quad[:, 0, 1] ** 2 / quad[:, 1, 1], 0.0)
    reach = np.abs(cos_a) * np.sqrt(schur)
    near = np.flatnonzero(np.maximum(reach - np.sqrt(own), 0.0) ** 2 - own < -2 * np.log(floor))
    probability: FloatArray = np.zeros(len(obs))
    if near.size == 0:
        return probability
    quad, linear, cos_a = quad[near], linear[near], cos_a[near]
    cos_g, sin_g = np.cos(MIRROR_GRID), np.sin(MIRROR_GRID)
    misfit = _quadratic(quad[..., None], linear[..., None], cos_g, sin_g)
    before, after = np.roll(misfit, 1, axis=1), np.roll(misfit, -1, axis=1)
    other = (misfit < before) & (misfit < after) & (cos_g * cos_a[:, None] <= 0)
    rows, best = np.arange(near.size), np.argmin(np.where(other, misfit, np.inf), axis=1)
    f0, fb, fa = misfit[rows, best], before[rows, best], after[rows, best]
    curve = np.maximum(fa - 2 * f0 + fb, TINY)  # the parabola through the three
    lowest = f0 - (fa - fb) ** 2 / (8 * curve)
    where = MIRROR_GRID[best] + MIRROR_STEP * (fb - fa) / (2 * curve)
    excess = np.where(other[rows, best], np.maximum(lowest - own_part[near], 0.0), np.inf)
    apart = np.abs(np.angle(np.exp(1j * (where - azimuth[near])))) > MIRROR_SIGMAS * sigma[near]
    probability[near] = np.where(apart, np.exp(-np.logaddexp(0.0, excess / 2)), 0.0)
    return probability


def _misfit_form(
    obs: FloatArray, cov: FloatArray, inclination: FloatArray, latitude: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(quad (n, 2, 2), linear (n, 2), constant (n,)) of each station's misfit vs A,
    ``constant + qᵀ·quad·q − 2·linearᵀ·q`` for q = (cos A, sin A)."""
    m = obs.shape[1]
    k = OMEGA_DEG_H * np.cos(latitude)
    # the model is the offset plus basis·(cos A, sin A): the misfit a quadratic in them
    basis = np.zeros((len(obs), m, 2))
    basis[:, 0, 0], basis[:, 1, 1] = k * np.cos(inclination), -k
    if m == 3:
        basis[:, 2, 0] = k * np.sin(inclination)
    weight = np.linalg.inv(cov)
    res = obs - model_offset(inclination, latitude, m)
    weighted = (weight @ res[..., None])[..., 0]
    across = basis.transpose(0, 2, 1)
    linear, quad = (across @ weighted[..., None])[..., 0], across @ weight @ basis
    constant: FloatArray = np.sum(res * weighted, axis=1)
    return quad, linear, constant


def _quadratic(
    quad: FloatArray, linear: FloatArray, cos_a: FloatArray, sin_a: FloatArray
) -> FloatArray:
    """qᵀ·quad·q − 2·linearᵀ·q for q = (cos A, sin A): the misfit less its constant."""
    out: FloatArray = (
        quad[:, 0, 0] * cos_a**2
        + 2 * quad[:, 0, 1] * (cos_a * sin_a)
        + quad[:, 1, 1] * sin_a**2
        - 2 * (linear[:, 0] * cos_a + linear[:, 1] * sin_a)
    )
    return out


def model_offset(inclination: FloatArray, latitude: float, m: int) -> FloatArray:
    """The A-independent part of :func:`model` (the vertical Earth rate's share)."""
    s = OMEGA_DEG_H * np.sin(latitude)
    parts = [s * np.sin(inclination), np.zeros_like(inclination)]
    if m == 3:
        parts.append(-s * np.cos(inclination))
    return np.stack(parts, axis=-1)

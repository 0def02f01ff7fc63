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
  answer stays small: :func:`mirror_probability` says how likely the other one is.
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
    cos_a = np.cos(azimuth)
    own_part = _quadratic(quad, linear, cos_a, np.sin(azimuth))
    own = np.maximum(np.sum(res * weighted, axis=1) + own_part, 0.0)
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

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
  pair cannot tell A from 180° − A (h carries no cos A): the σ shows it (→ ∞) unless z helps.
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


def model_offset(inclination: FloatArray, latitude: float, m: int) -> FloatArray:
    """The A-independent part of :func:`model` (the vertical Earth rate's share)."""
    s = OMEGA_DEG_H * np.sin(latitude)
    parts = [s * np.sin(inclination), np.zeros_like(inclination)]
    if m == 3:
        parts.append(-s * np.cos(inclination))
    return np.stack(parts, axis=-1)

"""Predicted precision of multi-position gyrocompassing (DOMAIN.md §5).

A single-axis gyro on a frame turned to toolfaces ψ_k reads
``y_k = h cos ψ_k + r sin ψ_k + b + d·(t_k − t̄) + ε_k``; h and r (high-side and right-side
Earth-rate components, independent of ψ) follow by linear least squares, and the azimuth
from ``h = k cos A cos I + Ω sin φ sin I``, ``r = −k sin A`` with k = Ω cos φ. Rates in °/h,
angles in radians, times in seconds.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from pipeline.earth.frames import OMEGA_EARTH, FloatArray

OMEGA_DEG_H = float(np.degrees(OMEGA_EARTH) * 3600.0)
"""Earth rate in °/h (≈ 15.041)."""


def position_design(toolface: ArrayLike, time: ArrayLike) -> FloatArray:
    """Design matrix of the (h, r, bias, trend) model, one row per frame position:
    [cos ψ_k, sin ψ_k, 1, t_k − t̄] (trend per second)."""
    psi = np.asarray(toolface, dtype=float)
    t = np.asarray(time, dtype=float)
    return np.stack([np.cos(psi), np.sin(psi), np.ones_like(psi), t - t.mean()], axis=-1)


def hr_covariance(toolface: ArrayLike, time: ArrayLike, sigma: ArrayLike) -> FloatArray:
    """Covariance (2×2, (°/h)²) of the least-squares h and r from positions read with
    independent errors of standard deviation ``sigma`` (°/h, scalar or per position)."""
    design = position_design(toolface, time)
    if design.shape[0] < design.shape[1]:
        raise ValueError(f"{design.shape[0]} positions cannot resolve h, r, bias and trend")
    weights: FloatArray = (
        1.0 / np.broadcast_to(np.asarray(sigma, dtype=float), design.shape[:1]) ** 2
    )
    normal = design.T @ (design * weights[:, None])
    if np.linalg.cond(normal) > 1e12:
        raise ValueError("the frame positions do not separate h, r, bias and trend")
    cov: FloatArray = np.asarray(np.linalg.inv(normal)[:2, :2], dtype=np.float64)
    return cov

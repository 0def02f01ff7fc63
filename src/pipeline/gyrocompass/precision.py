"""Predicted precision of multi-position gyrocompassing (DOMAIN.md §5).

A single-axis gyro on a frame turned to toolfaces ψ_k reads
``y_k = h cos ψ_k + r sin ψ_k + b + d·(t_k − t̄) + ε_k``; a second transverse gyro (frame y,
the XY scheme of a two- or three-axis tool) ``−h sin ψ_k + r cos ψ_k`` plus its own bias and
trend. h and r (high-side and right-side Earth-rate components, independent of ψ) follow by
linear least squares, and the azimuth
from ``h = k cos A cos I + Ω sin φ sin I``, ``r = −k sin A`` with k = Ω cos φ. Rates in °/h,
angles in radians, times in seconds.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from pipeline.earth.frames import OMEGA_EARTH, FloatArray

OMEGA_DEG_H = float(np.degrees(OMEGA_EARTH) * 3600.0)
"""Earth rate in °/h (≈ 15.041)."""


def position_design(
    toolface: ArrayLike, time: ArrayLike, axes: int = 1, terms: int = 2
) -> FloatArray:
    """Design matrix of the frame positions' least squares, one row per position and gyro
    axis (the axes one after the other): columns h, r, then per axis ``terms`` extra
    unknowns (0 none, 1 a bias, 2 a bias and a trend per second). The frame x gyro reads
    [cos ψ_k, sin ψ_k], a second (y) gyro [−sin ψ_k, cos ψ_k]."""
    psi = np.asarray(toolface, dtype=float)
    tau = np.asarray(time, dtype=float)
    tau = tau - tau.mean()
    n = len(psi)
    c, s = np.cos(psi), np.sin(psi)
    a = np.zeros((n * axes, 2 + terms * axes))
    for axis in range(axes):
        block = a[axis * n : (axis + 1) * n]
        block[:, 0], block[:, 1] = (c, s) if axis == 0 else (-s, c)
        if terms:
            block[:, 2 + terms * axis] = 1.0
        if terms == 2:
            block[:, 3 + terms * axis] = tau
    return a


def hr_covariance(
    toolface: ArrayLike, time: ArrayLike, sigma: ArrayLike, axes: int = 1
) -> FloatArray:
    """Covariance (2×2, (°/h)²) of the least-squares h and r, with a bias and trend per
    axis, from ``axes`` transverse gyros (1 or 2) read at the positions with independent
    errors of standard deviation ``sigma`` (°/h, scalar or per position)."""
    design = position_design(toolface, time, axes)
    rows, unknowns = design.shape
    if rows < unknowns:
        raise ValueError(
            f"{rows // axes} positions of {axes} gyro axis(es) cannot resolve h, r and a bias "
            f"and trend per axis ({unknowns} unknowns from {rows} readings)"
        )
    per_position = np.broadcast_to(np.asarray(sigma, dtype=float), (rows // axes,))
    weights: FloatArray = 1.0 / np.tile(per_position, axes) ** 2
    normal = design.T @ (design * weights[:, None])
    if np.linalg.cond(normal) > 1e12:
        raise ValueError("the frame positions do not separate h, r, bias and trend")
    cov: FloatArray = np.asarray(np.linalg.inv(normal)[:2, :2], dtype=np.float64)
    return cov

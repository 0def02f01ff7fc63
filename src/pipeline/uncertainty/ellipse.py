"""Horizontal error ellipses and vertical σ from NEV covariances.

For the horizontal block C = [[nn, ne], [ne, ee]] the semi-axes at 1σ are √λ of its
eigenvalues λ = (nn + ee)/2 ± √(((nn − ee)/2)² + ne²), and the major axis points at azimuth
θ = ½·atan2(2·ne, nn − ee) clockwise from north (folded to [0°, 180°)). The smaller λ of a
block of rounded entries is known only to a few ε of the larger (Weyl: an entry's rounding
moves it that much); below :data:`_RANK_ONE` of it the block is rank one within its rounding
and the minor axis is 0 (the value there would be rounding noise, ≤ √(8ε) ≈ 4e-8 of the
major axis, whether clamped or not). An ellipse containing
the position with probability p scales both axes by k₂ = √(χ²₂(p)) = √(−2 ln(1 − p)); the
vertical interval uses the two-sided normal quantile k₁ = Φ⁻¹((1 + p)/2).
"""

from __future__ import annotations

from dataclasses import dataclass
from statistics import NormalDist

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Ellipses", "ellipses", "hla_sigma", "horizontal_scale", "vertical_scale"]

FloatArray = NDArray[np.float64]

_RANK_ONE = 8.0 * float(np.finfo(np.float64).eps)
"""Smaller over larger eigenvalue of a horizontal block at or below which it is taken as rank
one (the rounding of the entries and of ``mean − radius`` below: a few ε)."""


def horizontal_scale(confidence: float) -> float:
    """k with P(χ²₂ ≤ k²) = confidence: the 2-D ellipse scale factor."""
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1); got {confidence}")
    return float(np.sqrt(-2.0 * np.log1p(-confidence)))


def vertical_scale(confidence: float) -> float:
    """Two-sided normal quantile for a 1-D interval of probability ``confidence``."""
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1); got {confidence}")
    return NormalDist().inv_cdf(0.5 * (1.0 + confidence))


@dataclass(frozen=True)
class Ellipses:
    """Per-station horizontal ellipses (1σ semi-axes, m; azimuth of major axis, rad) and σ_V."""

    semi_major: FloatArray
    semi_minor: FloatArray
    azimuth: FloatArray
    sigma_v: FloatArray


def ellipses(
    cov_nn: ArrayLike, cov_ne: ArrayLike, cov_ee: ArrayLike, cov_vv: ArrayLike
) -> Ellipses:
    """1σ ellipses of the horizontal covariance blocks (any shape, element-wise)."""
    nn = np.asarray(cov_nn, dtype=np.float64)
    ne = np.asarray(cov_ne, dtype=np.float64)
    ee = np.asarray(cov_ee, dtype=np.float64)
    mean = 0.5 * (nn + ee)
    radius = np.hypot(0.5 * (nn - ee), ne)
    major = np.sqrt(np.clip(mean + radius, 0.0, None))
    low = mean - radius
    minor = np.sqrt(np.clip(np.where(low <= _RANK_ONE * (mean + radius), 0.0, low), 0.0, None))
    azimuth = np.mod(0.5 * np.arctan2(2.0 * ne, nn - ee), np.pi)
    sigma_v = np.sqrt(np.clip(np.asarray(cov_vv, dtype=np.float64), 0.0, None))
    return Ellipses(semi_major=major, semi_minor=minor, azimuth=azimuth, sigma_v=sigma_v)


def hla_sigma(cov: ArrayLike, inc: ArrayLike, azi: ArrayLike) -> FloatArray:
    """1σ (n, 3) high side, lateral (right) and along hole (m) of NEV covariances (n, 3, 3)
    (m²) at stations of inclination ``inc`` and true azimuth ``azi`` (rad): the variance
    along the axes (cos I cos A, cos I sin A, −sin I), (−sin A, cos A, 0) and
    (sin I cos A, sin I sin A, cos I)."""
    i, a = np.asarray(inc, dtype=np.float64), np.asarray(azi, dtype=np.float64)
    si, ci, sa, ca = np.sin(i), np.cos(i), np.sin(a), np.cos(a)
    axes = np.stack(
        (
            np.stack((ci * ca, ci * sa, -si), axis=-1),
            np.stack((-sa, ca, np.zeros_like(sa)), axis=-1),
            np.stack((si * ca, si * sa, ci), axis=-1),
        ),
        axis=1,
    )
    var = np.einsum("nij,njk,nik->ni", axes, np.asarray(cov, dtype=np.float64), axes)
    out: FloatArray = np.sqrt(np.clip(var, 0.0, None))
    return out

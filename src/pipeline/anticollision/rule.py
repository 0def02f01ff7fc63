"""The ISCWSA separation factor (Sawaryn et al., SPE-187073, SPE Drilling & Completion 2019)
and the pass/warn/fail levels of a separation rule.

For a reference point p_r (NEV covariance C_r, hole radius R_r) and the closest point p_o of
an offset well (C_o, R_o), with d = p_o − p_r, D = |d| and n̂ = d/D:

    σ_S² = n̂ᵀ (C_r + C_o) n̂                      the two wells' errors, independent
    SF   = (D − R_r − R_o − S_m) / (k·√(σ_S² + σ_pa²))

S_m the surface margin, σ_pa the 1σ project-ahead uncertainty, k the scaling factor. SF < 0
means the holes, widened by the margin, overlap. Where the centres coincide (D = 0) n̂ is
undefined: σ_S is then the largest σ over all directions (√ of the largest eigenvalue of
C_r + C_o, the conservative choice), so SF = −(R_r + R_o + S_m)/(k·√(σ_S² + σ_pa²)) — at the
common point of a sidetrack and its parent, where both covariances are zero,
−(R_r + R_o + S_m)/(k·σ_pa). The level there is fail. Lengths m, covariances m².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["LEVELS", "RuleLimits", "Separation", "SeparationRule", "levels", "separation"]

FloatArray = NDArray[np.float64]
LEVELS = ("pass", "warn", "fail")


@dataclass(frozen=True)
class SeparationRule:
    """The rule's parameters; defaults are the ISCWSA rule's (SPE-187073)."""

    k: float = 3.5
    """scaling factor of the combined σ (3.5: about 1 in 10,000 chance of crossing)"""
    sigma_pa: float = 0.5
    """1σ project-ahead uncertainty, m"""
    surface_margin: float = 0.3
    """S_m, m"""


@dataclass(frozen=True)
class RuleLimits:
    """Separation-factor limits: below ``stop`` fail, below ``caution`` warn, else pass."""

    stop: float = 1.0
    caution: float = 1.5


@dataclass(frozen=True)
class Separation:
    """Per pair of points: centre-to-centre distance D (m), σ_S (m), SF and n̂ (m, 3)."""

    distance: FloatArray
    sigma_s: FloatArray
    sf: FloatArray
    direction: FloatArray


def separation(
    p_ref: FloatArray,
    c_ref: FloatArray,
    p_off: FloatArray,
    c_off: FloatArray,
    radii: FloatArray | float,
    rule: SeparationRule,
) -> Separation:
    """SF of each pair: positions (m, 3), covariances (m, 3, 3), ``radii`` R_r + R_o (m)."""
    d = np.asarray(p_off, dtype=np.float64) - np.asarray(p_ref, dtype=np.float64)
    dist = np.linalg.norm(d, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = d / dist[:, None]
    combined = np.asarray(c_ref) + np.asarray(c_off)
    var = np.einsum("ij,ijk,ik->i", n, combined, n)
    same = dist == 0.0
    if same.any():
        var[same] = np.linalg.eigvalsh(combined[same])[:, -1]
    sigma_s = np.sqrt(np.clip(var, 0.0, None))
    sf = (dist - radii - rule.surface_margin) / (rule.k * np.sqrt(sigma_s**2 + rule.sigma_pa**2))
    return Separation(distance=dist, sigma_s=sigma_s, sf=sf, direction=n)


def levels(sf: FloatArray, limits: RuleLimits) -> NDArray[np.str_]:
    """``pass``, ``warn`` or ``fail`` per SF (an undefined SF fails)."""
    sf = np.asarray(sf, dtype=np.float64)
    out = np.full(sf.shape, "pass", dtype="<U4")
    out[sf < limits.caution] = "warn"
    out[(sf < limits.stop) | np.isnan(sf)] = "fail"
    return out

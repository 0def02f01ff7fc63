"""Tool errors that turning the frame does not remove, and their share of a station's σ.

Multi-position compassing removes each gyro's constant bias and linear drift, but not:

- the **g-dependent gyro bias** from the transverse specific force. It turns with the frame
  exactly as the horizontal Earth rate does, so it adds to the fitted high-side and
  right-side components: 1σ ``g_sensitivity · sin I`` (°/h) on each (with g-sensitivity K
  in (°/h)/g, K·g sin I is the bias of a transverse gyro in a hole of inclination I). The
  azimuth error follows as ≈ sin I · K / (Ω cos φ) (SPE 90408, the GXY-G terms). The axial
  specific force g cos I is the same at every position: its share is a constant bias, fitted.
- **accelerometer bias, misalignment and scale factor**: the same at every frame position
  of a station, so they partly cancel between opposite positions (transverse terms) and
  partly do not (the axial bias moves the inclination by −b_z sin I / g). They are
  propagated to first order through the estimator itself: for a quantity
  ``Σ_k w_k f(a_k) / Σ_k w_k`` of the per-position accelerations a_k (inclination, gravity
  toolface), an error common to the positions ``δa_k = b + G a_k`` (bias b, gain error G:
  misalignment off the diagonal, scale factor on it) moves it by
  ``Σ_k w_k ∇f(a_k) · (b + G a_k) / Σ_k w_k``, each term of b and G independent with the
  tool's 1σ magnitude.

Units: g-sensitivity (°/h)/g, bias m/s², misalignment mrad, scale factor ppm — those of the
simulator's tools (:class:`pipeline.sim.sensors.ToolSensors`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.earth.frames import FloatArray


@dataclass(frozen=True)
class ToolErrors:
    """1σ magnitudes of the tool errors compassing cannot remove."""

    g_sensitivity: float
    """(°/h)/g: g-dependent bias of a transverse gyro per g of transverse specific force"""
    acc_bias: float
    """m/s², per accelerometer axis"""
    acc_misalignment: float
    """mrad, per off-diagonal term of the accelerometer triad"""
    acc_scale_factor: float
    """ppm, per accelerometer axis"""


def g_dependent_variance(errors: ToolErrors, inclination: float) -> float:
    """Variance, (°/h)², the g-dependent gyro bias adds to each transverse Earth-rate
    component at inclination (rad)."""
    return float((errors.g_sensitivity * np.sin(inclination)) ** 2)


_OFF_DIAGONAL = ~np.eye(3, dtype=bool)
"""The off-diagonal terms of a triad's 3 × 3 matrix"""


def accelerometer_sigma(
    gradient: FloatArray, acc: FloatArray, weights: FloatArray, errors: ToolErrors
) -> FloatArray:
    """1σ of ``Σ_k w_k f(a_k) / Σ_k w_k`` from the accelerometer errors common to the
    positions (module docstring): ``gradient`` (..., n, 3) = ∇f at each position's
    acceleration ``acc`` (..., n, 3, m/s²), in f's unit per m/s²; ``weights`` (..., n). A
    stack of stations (leading axes) at once: each station's numbers as alone."""
    w = weights / weights.sum(axis=-1, keepdims=True)
    d_bias = w[..., None, :] @ gradient  # (..., 1, 3)
    d_gain = np.einsum("...k,...ki,...kj->...ij", w, gradient, acc)
    var = (
        errors.acc_bias**2 * (d_bias @ d_bias.mT)[..., 0, 0]
        + (errors.acc_misalignment * 1e-3) ** 2 * (d_gain[..., _OFF_DIAGONAL] ** 2).sum(axis=-1)
        + (errors.acc_scale_factor * 1e-6) ** 2
        * (np.diagonal(d_gain, axis1=-2, axis2=-1) ** 2).sum(axis=-1)
    )
    sigma: FloatArray = np.sqrt(var)
    return sigma

"""Canonical frames and attitude (DOMAIN.md §2), vectorised over leading axes.

Navigation frame NED (x north, y east, z down). Tool body frame b: z along the tool axis,
pointing downhole; x, y transverse. Attitude ``C_b^n = Rz(A) · Ry(I) · Rz(ψ)`` with A the
azimuth (clockwise from north), I the inclination and ψ the gravity toolface of the x axis
(0 when x points to the high side, growing clockwise looking downhole). All angles in
radians.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

OMEGA_EARTH = 7.2921150e-5
"""Earth's rotation rate, rad/s (WGS84)."""

FloatArray = NDArray[np.float64]


def sin_cos(angle: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Sine and cosine of ``angle`` (rad) by the half-angle tangent t = tan(a/2):
    ``sin = 2t/(1 + t²)``, ``cos = (1 − t²)/(1 + t²)`` — within 3e-16 of ``np.sin`` and
    ``np.cos`` (absolute; t stays finite for every finite angle), at a ninth of their CPU
    where NumPy's tangent is vectorised and its sine and cosine are not (float64)."""
    t = np.multiply(angle, 0.5, out=np.empty(np.shape(angle)))
    np.tan(t, out=t)
    return _from_tangent(t)


def tangent_sin_cos(tangent: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Sine and cosine of the angles whose half-angle tangents are ``tangent`` (tan(a/2),
    a in rad), by :func:`sin_cos`'s formulas: no trig function at all."""
    return _from_tangent(np.array(tangent, dtype=np.float64))


def _from_tangent(t: FloatArray) -> tuple[FloatArray, FloatArray]:
    """:func:`sin_cos` from the half-angle tangents ``t`` (overwritten: the sine)."""
    square = np.multiply(t, t, out=np.empty_like(t))
    scale = np.add(square, 1.0, out=np.empty_like(t))
    np.divide(1.0, scale, out=scale)
    # in place (the same operations, the same bits): a tenth less CPU than fresh temporaries
    sin: FloatArray = np.multiply(t, 2.0, out=t)
    sin *= scale
    cos: FloatArray = np.subtract(1.0, square, out=square)
    cos *= scale
    return sin, cos


TURN_REACH = 0.1
"""rad: the largest turn :func:`turned_sin_cos` takes by its series (beyond: :func:`sin_cos`)."""
_TURN_REMAINDER = 2.0**-60
"""bound of the series' truncation error, absolute (a 2,300th of an ulp of 1)."""


def turned_sin_cos(
    sin: FloatArray, cos: FloatArray, turn: FloatArray, angle: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Sine and cosine of ``angle`` = a + ``turn`` (rad) from those of a, rotated by the turn:
    ``sin(a + d) = sin a + (cos a·sin d − sin a·(1 − cos d))`` and likewise the cosine, with
    sin d and 1 − cos d by their Taylor series in d², as many terms as the largest |d| needs
    for a truncation error under 2⁻⁶⁰ (one or two for the Newton corrections and predictor
    steps of an azimuth integration) — a quarter of :func:`sin_cos`'s CPU; the rounding adds
    ≤ 2.3e-16 (absolute) to that of ``sin`` and ``cos``. A turn beyond :data:`TURN_REACH`
    (or not finite) takes :func:`sin_cos` of ``angle`` instead."""
    largest = float(max(np.max(turn), -np.min(turn))) if turn.size else 0.0  # (NaN: NaN)
    if not largest <= TURN_REACH:
        return sin_cos(angle)
    square = np.multiply(turn, turn)
    terms = 0  # sin d = d·Σ (−d²)ʲ/(2j + 1)!, 1 − cos d = d²·Σ (−d²)ʲ/(2j + 2)!, j ≤ terms
    while largest ** (2 * terms + 3) / math.factorial(2 * terms + 3) > _TURN_REMAINDER:
        terms += 1
    # Horner in d²: v ← d²·(1/(2j + 2)! − v) from j = terms down to 0, likewise the sine's
    versine = np.multiply(square, 1.0 / math.factorial(2 * terms + 2))
    for j in range(terms - 1, -1, -1):
        np.subtract(1.0 / math.factorial(2 * j + 2), versine, out=versine)
        versine *= square
    sine = turn
    if terms:
        odd = np.multiply(square, 1.0 / math.factorial(2 * terms + 1))
        for j in range(terms - 1, 0, -1):
            np.subtract(1.0 / math.factorial(2 * j + 1), odd, out=odd)
            odd *= square
        np.subtract(1.0, odd, out=odd)
        sine = np.multiply(odd, turn, out=odd)
    new_sin = np.multiply(cos, sine)
    new_sin -= np.multiply(sin, versine, out=square)
    new_sin += sin
    new_cos = np.multiply(sin, sine, out=square)
    new_cos += np.multiply(cos, versine, out=versine)
    np.subtract(cos, new_cos, out=new_cos)
    return new_sin, new_cos


def rot_z(angle: ArrayLike) -> FloatArray:
    """Rotation matrices about z, shape (..., 3, 3): [[c, -s, 0], [s, c, 0], [0, 0, 1]]."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*a.shape, 3, 3))
    out[..., 0, 0], out[..., 0, 1] = c, -s
    out[..., 1, 0], out[..., 1, 1] = s, c
    out[..., 2, 2] = 1.0
    return out


def rot_y(angle: ArrayLike) -> FloatArray:
    """Rotation matrices about y, shape (..., 3, 3): [[c, 0, s], [0, 1, 0], [-s, 0, c]]."""
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((*a.shape, 3, 3))
    out[..., 0, 0], out[..., 0, 2] = c, s
    out[..., 1, 1] = 1.0
    out[..., 2, 0], out[..., 2, 2] = -s, c
    return out


def body_to_ned(azimuth: ArrayLike, inclination: ArrayLike, toolface: ArrayLike) -> FloatArray:
    """``C_b^n = Rz(A) Ry(I) Rz(ψ)``, shape (..., 3, 3); maps body vectors to NED."""
    return rot_z(azimuth) @ rot_y(inclination) @ rot_z(toolface)


def tool_axis(azimuth: ArrayLike, inclination: ArrayLike) -> FloatArray:
    """Unit tool axis in NED, (sin I cos A, sin I sin A, cos I), shape (..., 3)."""
    a, i = np.asarray(azimuth, dtype=float), np.asarray(inclination, dtype=float)
    return np.stack([np.sin(i) * np.cos(a), np.sin(i) * np.sin(a), np.cos(i)], axis=-1)


def earth_rate_ned(latitude: ArrayLike) -> FloatArray:
    """Earth rate in NED at geodetic latitude φ (rad): Ω·(cos φ, 0, −sin φ), rad/s."""
    lat = np.asarray(latitude, dtype=float)
    zero = np.zeros_like(lat)
    return OMEGA_EARTH * np.stack([np.cos(lat), zero, -np.sin(lat)], axis=-1)


def to_body(c_bn: FloatArray, v_ned: ArrayLike) -> FloatArray:
    """Express NED vectors in the body frame: ``C_n^b v = C_b^nᵀ v``, shape (..., 3)."""
    out: FloatArray = np.einsum("...ji,...j->...i", c_bn, np.asarray(v_ned, dtype=float))
    return out


def inclination_toolface(g_body: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Inclination and gravity toolface (rad) from body gravity (gravity sign convention,
    ``g_b = C_n^b (0, 0, g)``): I = atan2(√(gx²+gy²), gz), ψ = atan2(gy, −gx)."""
    g = np.asarray(g_body, dtype=float)
    gx, gy, gz = g[..., 0], g[..., 1], g[..., 2]
    return np.arctan2(np.hypot(gx, gy), gz), np.arctan2(gy, -gx)

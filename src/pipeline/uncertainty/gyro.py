"""OWSG / ISCWSA stationary-gyro error terms (GYRO-NS, ISCWSA Rev 5; SPE 90408).

Each term is a 1σ magnitude and a weight function giving ∂(MD, I, α)/∂ε per station, where
α = A·sin I is the horizontal azimuth tilt (see :mod:`pipeline.uncertainty.model`); an
azimuth weight ∂A/∂ε of the published model therefore appears here multiplied by sin I.
Gyro rate terms divide by the horizontal Earth rate Ω cos φ (the gyrocompass azimuth error
of a bias b is b/(Ω cos φ)). Units: magnitudes as published (deg, deg/h, m, m/s², 1/m) and
converted to SI by :func:`gyro_terms`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pipeline.uncertainty.model import Propagation, StationJacobians, propagate, station_jacobians

__all__ = [
    "EARTH_RATE_RAD_H",
    "GYRO_PRESETS",
    "GyroTool",
    "Survey",
    "Term",
    "gyro_covariance",
    "gyro_terms",
]

FloatArray = NDArray[np.float64]

EARTH_RATE_RAD_H = 7.292115e-5 * 3600.0
"""Earth rotation rate, rad/h (WGS84)."""
STANDARD_G = 9.80665
#: OWSG XCL default tortuosity (rad/m), 1°/100 ft as in the GYRO-NS sheet.
XCL_TORTUOSITY = 0.000572614583987641
_DEG = np.pi / 180.0


@dataclass(frozen=True)
class Survey:
    """Stations of one survey: MD (m), inclination and true azimuth (rad), TVD (m)."""

    md: FloatArray
    inc: FloatArray
    azi: FloatArray
    tvd: FloatArray

    @classmethod
    def of(cls, md: ArrayLike, inc: ArrayLike, azi: ArrayLike, tvd: ArrayLike) -> Survey:
        arrays = [np.asarray(x, dtype=np.float64) for x in (md, inc, azi, tvd)]
        if len({a.shape for a in arrays}) != 1 or arrays[0].ndim != 1:
            raise ValueError("md, inc, azi and tvd must be 1-D arrays of equal length")
        return cls(*arrays)


@dataclass(frozen=True)
class GyroTool:
    """1σ magnitudes of the GYRO-NS terms, in the units of the OWSG sheet.

    Defaults are the OWSG GYRO-NS (A020Gb, Rev 5) values.
    """

    drfr: float = 0.35  # m, random depth reference
    dsfs: float = 5.6e-4  # -, depth scale factor
    dstg: float = 2.5e-7  # 1/m, depth stretch (global)
    sage: float = 0.2  # deg, sag (enhanced)
    xym1: float = 0.1  # deg, xy misalignment 1
    xym2: float = 0.1  # deg, xy misalignment 2
    xym3e: float = 0.3  # deg, xy misalignment 3 (random, enhanced)
    xym4e: float = 0.3  # deg, xy misalignment 4 (random, enhanced)
    axyz_mis: float = 0.0095  # deg, accelerometer misalignment
    axyz_sf: float = 1.11e-4  # -, accelerometer scale factor
    axyz_zb: float = 0.0017  # m/s², accelerometer bias
    gxy_b1: float = 0.15  # deg/h, xy gyro bias 1 (random between stations)
    gxy_b2: float = 0.15  # deg/h, xy gyro bias 2
    gxy_g1: float = 0.2  # deg/h/g, g-dependent 1
    gxy_g4: float = 0.6  # deg/h/g, g-dependent 4
    gxy_rn: float = 0.4  # deg/h, random noise
    noise_reduction: float = 1.0  # -, noise reduction factor of GXY-RN
    xcla: float = 0.167  # -, extended course length (azimuth)
    xclh: float = 0.167  # -, extended course length (inclination)
    xcl_tortuosity: float = XCL_TORTUOSITY  # rad/m
    include_xcl: bool = True
    extra: dict[str, float] = field(default_factory=dict)

    def with_measured_noise(self, sigma_azi_deg: float, latitude_deg: float) -> GyroTool:
        """A copy whose GXY-RN reproduces a measured 1σ compassing azimuth scatter at
        I = 0: σ_A = RN/(Ω cos φ), so RN = σ_A·Ω cos φ (deg/h)."""
        rate_deg_h = np.degrees(EARTH_RATE_RAD_H) * np.cos(np.radians(latitude_deg))
        return replace(self, gxy_rn=float(np.radians(sigma_azi_deg) * rate_deg_h))


GYRO_PRESETS: dict[str, GyroTool] = {
    "GYRO-NS": GyroTool(),
    "GYRO-NS-noXCL": GyroTool(include_xcl=False),
}
"""Named tool presets (OWSG short names)."""

Weight = Callable[[Survey], FloatArray]


@dataclass(frozen=True)
class Term:
    """One error source: name, propagation mode, 1σ magnitude (SI) and weights (n, 3)."""

    name: str
    mode: Propagation
    sigma: float
    weight: Weight


def _stack(d: ArrayLike, i: ArrayLike, a: ArrayLike, n: int) -> FloatArray:
    out = np.zeros((n, 3))
    out[:, 0] = d
    out[:, 1] = i
    out[:, 2] = a
    return out


def _prev(x: FloatArray) -> FloatArray:
    return np.concatenate((x[:1], x[:-1]))


def _misalign_factor(s: Survey) -> FloatArray:
    """max(1, √(10 m/ΔMD)): short-course damping of the random misalignments (0 at ΔMD = 0)."""
    dmd = s.md - _prev(s.md)
    f = np.zeros_like(dmd)
    pos = dmd > 0
    f[pos] = np.maximum(1.0, np.sqrt(10.0 / dmd[pos]))
    return f


def gyro_terms(tool: GyroTool, latitude_deg: float, *, g: float = STANDARD_G) -> list[Term]:
    """The GYRO-NS terms of ``tool`` at a latitude, magnitudes in SI (m, rad, rad/h…)."""
    horiz = EARTH_RATE_RAD_H * np.cos(np.radians(latitude_deg))
    dps = _DEG  # deg/h → rad/h: the rate terms are b/(Ω cos φ) in rad
    tort = tool.xcl_tortuosity

    def n_of(s: Survey) -> int:
        return int(s.md.size)

    terms = [
        Term("DRFR", "random", tool.drfr, lambda s: _stack(1.0, 0.0, 0.0, n_of(s))),
        Term("DSFS", "systematic", tool.dsfs, lambda s: _stack(s.md, 0.0, 0.0, n_of(s))),
        Term("DSTG", "global", tool.dstg, lambda s: _stack(s.md * s.tvd, 0.0, 0.0, n_of(s))),
        Term(
            "SAGE",
            "systematic",
            tool.sage * _DEG,
            lambda s: _stack(0.0, np.abs(np.sin(s.inc)) ** 0.25, 0.0, n_of(s)),
        ),
        Term(
            "XYM1",
            "systematic",
            tool.xym1 * _DEG,
            lambda s: _stack(0.0, np.abs(np.sin(s.inc)), 0.0, n_of(s)),
        ),
        Term(
            "XYM2",
            "systematic",
            tool.xym2 * _DEG,
            lambda s: _stack(0.0, 0.0, -np.sin(s.inc), n_of(s)),
        ),
        Term(
            "XYM3E",
            "random",
            tool.xym3e * _DEG,
            lambda s: _stack(
                0.0,
                np.abs(np.cos(s.inc)) * np.cos(s.azi) * _misalign_factor(s),
                -np.abs(np.cos(s.inc)) * np.sin(s.azi) * _misalign_factor(s),
                n_of(s),
            ),
        ),
        Term(
            "XYM4E",
            "random",
            tool.xym4e * _DEG,
            lambda s: _stack(
                0.0,
                np.abs(np.cos(s.inc)) * np.sin(s.azi) * _misalign_factor(s),
                np.abs(np.cos(s.inc)) * np.cos(s.azi) * _misalign_factor(s),
                n_of(s),
            ),
        ),
    ]
    if tool.include_xcl:
        terms += [
            Term(
                "XCLA",
                "random",
                tool.xcla,
                lambda s: _stack(
                    0.0,
                    0.0,
                    np.maximum(
                        np.sin(s.inc) * np.sin(np.abs(s.azi - _prev(s.azi))),
                        tort * (s.md - _prev(s.md)),
                    ),
                    n_of(s),
                ),
            ),
            Term(
                "XCLH",
                "random",
                tool.xclh,
                lambda s: _stack(
                    0.0,
                    np.maximum(np.abs(s.inc - _prev(s.inc)), tort * (s.md - _prev(s.md))),
                    0.0,
                    n_of(s),
                ),
            ),
        ]
    terms += [
        Term(
            "AXYZ-MIS", "systematic", tool.axyz_mis * _DEG, lambda s: _stack(0.0, 1.0, 0.0, n_of(s))
        ),
        Term(
            "AXYZ-SF",
            "systematic",
            tool.axyz_sf,
            lambda s: _stack(0.0, 1.3 * np.sin(s.inc) * np.cos(s.inc), 0.0, n_of(s)),
        ),
        Term(
            "AXYZ-ZB",
            "systematic",
            tool.axyz_zb,
            lambda s: _stack(0.0, np.sin(s.inc) / g, 0.0, n_of(s)),
        ),
        Term(
            "GXY-B1R",
            "random",
            tool.gxy_b1 * dps,
            lambda s: _stack(0.0, 0.0, np.sin(s.azi) * np.tan(s.inc) / horiz, n_of(s)),
        ),
        Term(
            "GXY-B2R",
            "random",
            tool.gxy_b2 * dps,
            lambda s: _stack(0.0, 0.0, np.cos(s.azi) * np.sin(s.inc) / horiz, n_of(s)),
        ),
        Term(
            "GXY-G1",
            "systematic",
            tool.gxy_g1 * dps,
            lambda s: _stack(0.0, 0.0, np.cos(s.azi) * np.sin(s.inc) ** 2 / horiz, n_of(s)),
        ),
        Term(
            "GXY-G4",
            "systematic",
            tool.gxy_g4 * dps,
            lambda s: _stack(
                0.0, 0.0, np.sin(s.azi) * np.tan(s.inc) * np.sin(s.inc) / horiz, n_of(s)
            ),
        ),
        Term(
            "GXY-RN",
            "random",
            tool.gxy_rn * dps,
            lambda s: _stack(
                0.0,
                0.0,
                tool.noise_reduction
                * np.sqrt(np.clip(1.0 - (np.cos(s.azi) * np.sin(s.inc)) ** 2, 0.0, None))
                * np.tan(s.inc)
                / horiz,
                n_of(s),
            ),
        ),
    ]
    return terms


def gyro_covariance(
    survey: Survey,
    latitude_deg: float,
    tool: GyroTool | str = "GYRO-NS",
    *,
    basis: str = "min_curve",
    surface_tie: bool = False,
    g: float = STANDARD_G,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) of a survey and the term names."""
    tool_ = GYRO_PRESETS[tool] if isinstance(tool, str) else tool
    terms = gyro_terms(tool_, latitude_deg, g=g)
    if basis not in ("min_curve", "balanced_tangent"):
        raise ValueError(f"unknown basis {basis!r}")
    jac: StationJacobians = station_jacobians(
        survey.md,
        survey.inc,
        survey.azi,
        basis="min_curve" if basis == "min_curve" else "balanced_tangent",
        surface_tie=surface_tie,
    )
    e_dia = np.stack([t.sigma * t.weight(survey) for t in terms])
    cov = propagate(e_dia, [t.mode for t in terms], jac)
    return [t.name for t in terms], cov

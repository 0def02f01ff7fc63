"""OWSG / ISCWSA gyro error terms: GYRO-NS (stationary) and GYRO-NS-CT (stationary and
continuous), ISCWSA Rev 5; SPE 90408.

Each term is a 1σ magnitude and a weight function giving ∂(MD, I, α)/∂ε per station, where
α = A·sin I is the horizontal azimuth tilt (see :mod:`pipeline.uncertainty.model`); an
azimuth weight ∂A/∂ε of the published model therefore appears here multiplied by sin I.
The extended-course-length terms XCLA/XCLH are the OWSG gyro sheets' measurement-error
form (an azimuth and an inclination weight); the ISCWSA MWD workbook defines them in
position instead (:mod:`pipeline.uncertainty.mwd`). Gyro rate terms divide by the
horizontal Earth rate Ω cos φ (the gyrocompass azimuth error of a bias b is b/(Ω cos φ)).
Units: magnitudes as published (deg, deg/h, m, m/s², 1/m) and converted to SI by
:func:`gyro_terms`.

Continuous mode (GYRO-NS-CT, SPE 90408 Table 7). Above the static-gyro end inclination the
tool runs continuously and its xy gyro drift and random walk accumulate along the hole at
the running speed c (m/h): the azimuth error is ``v·h_i`` with

    drift (GXY-GD)        h_i = h_{i−1} + ΔMD_i / (c·sin Ī_i)         (h in hours)
    random walk (GXY-GRW) h_i = √(h_{i−1}² + ΔMD_i / (c·sin² Ī_i))     (h in √hours)

Ī_i the mean inclination of the leg, h reset to 0 at a station at or below the end
inclination; both propagate systematically. The stationary terms are evaluated at every
station as the OWSG sheet (and welleng) do. When the initial azimuth error of the continuous
run is measured (its compassed stop's σ), ``init_sigma_azi`` replaces the stationary gyro
terms by that one systematic azimuth error (SPE 90408's initialisation error carried through
the continuous section) and the continuous section starts at the first station.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from pipeline.uncertainty.model import Propagation
from pipeline.uncertainty.terms import (
    STANDARD_G,
    XCL_TORTUOSITY,
    Survey,
    Term,
    depth_terms,
    misalignment_terms,
    previous,
    stack,
    term_covariance,
)

__all__ = [
    "EARTH_RATE_RAD_H",
    "GYRO_PRESETS",
    "GyroTool",
    "gyro_covariance",
    "gyro_terms",
]

FloatArray = NDArray[np.float64]

EARTH_RATE_RAD_H = 7.292115e-5 * 3600.0
"""Earth rotation rate, rad/h (WGS84)."""
_DEG = np.pi / 180.0


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
    continuous: bool = False  # GYRO-NS-CT: biases systematic, no G1, GD and GRW terms
    gxy_gd: float = 0.5  # deg/h, continuous xy gyro drift (GYRO-NS-CT)
    gxy_grw: float = 0.25  # deg/√h, continuous xy gyro random walk (GYRO-NS-CT)
    running_speed: float = 2743.2  # m/h, continuous running speed (GYRO-NS-CT)
    static_end_inc: float = 15.0  # deg, continuous above it (GYRO-NS-CT); < 0: from station 0
    init_sigma_azi: float | None = None  # deg, measured initial azimuth σ (GYRO-NS-CT)
    extra: dict[str, float] = field(default_factory=dict)

    def with_measured_noise(self, sigma_azi_deg: float, latitude_deg: float) -> GyroTool:
        """A copy whose GXY-RN reproduces a measured 1σ compassing azimuth scatter at
        I = 0: σ_A = f·RN/(Ω cos φ) (f the noise reduction), so RN = σ_A·Ω cos φ/f (deg/h)."""
        rate_deg_h = np.degrees(EARTH_RATE_RAD_H) * np.cos(np.radians(latitude_deg))
        rn = np.radians(sigma_azi_deg) * rate_deg_h / self.noise_reduction
        return replace(self, gxy_rn=float(rn))


GYRO_PRESETS: dict[str, GyroTool] = {
    "GYRO-NS": GyroTool(),
    "GYRO-NS-noXCL": GyroTool(include_xcl=False),
    # OWSG GYRO-NS-CT (A021Gc, Rev 5): sag 0.08°, noise reduction 0.4082
    "GYRO-NS-CT": GyroTool(continuous=True, sage=0.08, noise_reduction=0.4082),
}
"""Named tool presets (OWSG short names)."""


def _running(s: Survey, speed: float, gate: float, power: int) -> FloatArray:
    """Continuous drift (power 1: hours) or random-walk (power 2: √hours) coefficient h_i at
    each station: accumulated over legs ending above ``gate`` (rad), reset at or below it."""
    mean_sin = np.abs(np.sin(0.5 * (s.inc + previous(s.inc))))
    active = s.inc > gate
    active[0] = False
    step = np.zeros_like(s.md)
    with np.errstate(divide="ignore", invalid="ignore"):
        step[active] = (s.md - previous(s.md))[active] / (speed * mean_sin[active] ** power)
    total = np.cumsum(step)
    base = np.maximum.accumulate(np.where(active, 0.0, total))
    h = total - base
    out: FloatArray = h if power == 1 else np.sqrt(h)
    return out


def _stationary_gyro_terms(tool: GyroTool, horiz: float) -> list[Term]:
    """The xy gyro terms of a stationary gyrocompass (random biases in GYRO-NS, systematic
    in GYRO-NS-CT, whose sheet has no G1)."""
    dps = _DEG
    bias_mode: Propagation = "systematic" if tool.continuous else "random"
    suffix = "S" if tool.continuous else "R"

    terms = [
        Term(
            f"GXY-B1{suffix}",
            bias_mode,
            tool.gxy_b1 * dps,
            lambda s: stack(0.0, 0.0, np.sin(s.azi) * np.tan(s.inc) / horiz, s.size),
        ),
        Term(
            f"GXY-B2{suffix}",
            bias_mode,
            tool.gxy_b2 * dps,
            lambda s: stack(0.0, 0.0, np.cos(s.azi) * np.sin(s.inc) / horiz, s.size),
        ),
        Term(
            "GXY-G1",
            "systematic",
            tool.gxy_g1 * dps,
            lambda s: stack(0.0, 0.0, np.cos(s.azi) * np.sin(s.inc) ** 2 / horiz, s.size),
        ),
        Term(
            "GXY-G4",
            "systematic",
            tool.gxy_g4 * dps,
            lambda s: stack(
                0.0, 0.0, np.sin(s.azi) * np.tan(s.inc) * np.sin(s.inc) / horiz, s.size
            ),
        ),
        Term(
            "GXY-RN",
            "random",
            tool.gxy_rn * dps,
            lambda s: stack(
                0.0,
                0.0,
                tool.noise_reduction
                * np.sqrt(np.clip(1.0 - (np.cos(s.azi) * np.sin(s.inc)) ** 2, 0.0, None))
                * np.tan(s.inc)
                / horiz,
                s.size,
            ),
        ),
    ]
    return [t for t in terms if not (tool.continuous and t.name == "GXY-G1")]


def gyro_terms(tool: GyroTool, latitude_deg: float, *, g: float = STANDARD_G) -> list[Term]:
    """The GYRO-NS terms of ``tool`` at a latitude, magnitudes in SI (m, rad, rad/h…)."""
    horiz = EARTH_RATE_RAD_H * np.cos(np.radians(latitude_deg))
    dps = _DEG  # deg/h → rad/h: the rate terms are b/(Ω cos φ) in rad
    tort = tool.xcl_tortuosity

    terms = depth_terms(tool.drfr, tool.dsfs, tool.dstg) + misalignment_terms(
        tool.sage, tool.xym1, tool.xym2, tool.xym3e, tool.xym4e
    )
    if tool.include_xcl:
        terms += [
            Term(
                "XCLA",
                "random",
                tool.xcla,
                lambda s: stack(
                    0.0,
                    0.0,
                    np.maximum(
                        np.sin(s.inc) * np.sin(np.abs(s.azi - previous(s.azi))),
                        tort * (s.md - previous(s.md)),
                    ),
                    s.size,
                ),
            ),
            Term(
                "XCLH",
                "random",
                tool.xclh,
                lambda s: stack(
                    0.0,
                    np.maximum(np.abs(s.inc - previous(s.inc)), tort * (s.md - previous(s.md))),
                    0.0,
                    s.size,
                ),
            ),
        ]
    terms += [
        Term(
            "AXYZ-MIS", "systematic", tool.axyz_mis * _DEG, lambda s: stack(0.0, 1.0, 0.0, s.size)
        ),
        Term(
            "AXYZ-SF",
            "systematic",
            tool.axyz_sf,
            lambda s: stack(0.0, 1.3 * np.sin(s.inc) * np.cos(s.inc), 0.0, s.size),
        ),
        Term(
            "AXYZ-ZB",
            "systematic",
            tool.axyz_zb,
            lambda s: stack(0.0, np.sin(s.inc) / g, 0.0, s.size),
        ),
    ]
    init = tool.init_sigma_azi
    if init is None:
        terms += _stationary_gyro_terms(tool, horiz)
    else:  # the measured initial azimuth error, carried through the run
        terms.append(
            Term(
                "AZ-INIT",
                "systematic",
                init * _DEG,
                lambda s: stack(0.0, 0.0, np.sin(s.inc), s.size),
            )
        )
    if tool.continuous:
        gate = -np.inf if init is not None else np.radians(tool.static_end_inc)
        speed = tool.running_speed
        terms += [
            Term(
                "GXY-GD",
                "systematic",
                tool.gxy_gd * dps,
                lambda s: stack(0.0, 0.0, _running(s, speed, gate, 1) * np.sin(s.inc), s.size),
            ),
            Term(
                "GXY-GRW",
                "systematic",
                tool.gxy_grw * dps,
                lambda s: stack(0.0, 0.0, _running(s, speed, gate, 2) * np.sin(s.inc), s.size),
            ),
        ]
    return terms


def gyro_covariance(
    survey: Survey,
    latitude_deg: float,
    tool: GyroTool | str = "GYRO-NS",
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    g: float = STANDARD_G,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) of a survey and the term names."""
    tool_ = GYRO_PRESETS[tool] if isinstance(tool, str) else tool
    terms = gyro_terms(tool_, latitude_deg, g=g)
    return term_covariance(survey, terms, basis=basis, surface_tie=surface_tie)

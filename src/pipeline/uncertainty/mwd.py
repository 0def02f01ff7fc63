"""ISCWSA MWD error model, Rev 5 (magnetic MWD with axial and xy interference terms).

The 35 terms of the ISCWSA "MWD Rev 5" tool model (the OWSG MWD Rev 2 sheet): depth (DRFR,
DSFS, DSTG), accelerometer biases and scale factors (ABXY-TI1S/2S, ABZ, ASXY-TI1S–3S, ASZ),
magnetometer biases and scale factors (MBXY-TI1S/2S, MBZ, MSXY-TI1S–3S, MSZ), declination
(DEC-U, -OS, -OH, -OI, DECR), its field-strength dependent part (DBH-U, -OS, -OH, -OI, DBHR),
axial interference (AMIL), sag and misalignments (SAGE, XYM1–XYM4E) and the extended course
length terms (XCLA, XCLH). The xy sensor terms are toolface-independent (TI): an xy bias
is split into its high-side and lateral parts, an xy scale factor into a common part (σ/√2)
and the cos 2ψ and sin 2ψ halves of the differential one (σ/2 each), ψ the toolface.

Frames and inputs: true azimuth A (rad) in :class:`~pipeline.uncertainty.terms.Survey`, the
magnetic azimuth Am = A − D (D the declination, east positive); total field B (nT), dip Θ
and gravity G (m/s²) of the site. The sensor terms' azimuth weights ∂A/∂ε of the model
appear as α weights ∂A/∂ε·sin I (α = A·sin I, :mod:`pipeline.uncertainty.model`): the
xy-bias term ABXY-TI2S, whose ∂A = (cot I − tan Θ cos Am)/G is singular at I = 0, becomes
(cos I − tan Θ cos Am sin I)/G, finite, and reproduces the model's vertical-hole special
form (a lateral error ½·ΔMD·mag/G along the station's azimuth) without a special case.

XCLA/XCLH are defined in position, as in the ISCWSA example workbook (Codling, SPE 187249):
station k's own course adds, randomly,

    XCLA  ΔMD_k·max(|sin I_k sin ΔA_k|, τ·ΔMD_k)·(−sin A_k, cos A_k, 0)
    XCLH  ΔMD_k·max(|ΔI_k|, τ·ΔMD_k)·(cos I_k cos A_k, cos I_k sin A_k, −sin I_k)

times 0.167, ΔA wrapped to (−π, π] and taken as 0 where the previous station is vertical
(I < 1e-4 rad), τ the default tortuosity 1°/100 ft.

Magnitudes are in the sheet's units (m, -, 1/m, m/s², nT, deg, deg·nT) and converted to SI
by :func:`mwd_terms`. Propagation as published: random, systematic, well-by-well (DEC-U,
DBH-U) and global.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.site import MagneticReference
from pipeline.uncertainty.model import Propagation
from pipeline.uncertainty.terms import (
    STANDARD_G,
    XCL_TORTUOSITY,
    Survey,
    Term,
    Weight,
    depth_terms,
    misalignment_terms,
    previous,
    stack,
    term_covariance,
)

__all__ = [
    "MWD_PRESETS",
    "MwdTool",
    "mwd_covariance",
    "mwd_terms",
]

FloatArray = NDArray[np.float64]
#: A weight component as a function of (sin I, cos I, sin Am, cos Am).
AngleFn = Callable[[FloatArray, FloatArray, FloatArray, FloatArray], FloatArray | float]

#: Below this inclination (rad) a station counts as vertical (the workbook's limit).
VERTICAL_INC_LIMIT = 1e-4
_DEG = np.pi / 180.0


@dataclass(frozen=True)
class MwdTool:
    """1σ magnitudes of the ISCWSA MWD Rev 5 terms, in the sheet's units.

    Defaults are the ISCWSA MWD Rev 5.11 (OWSG MWD Rev 2) values; the 2019 Rev 5 example
    workbook differs only in DEC-OH (0.20°, preset ``ISCWSA-MWD-REV5``).
    """

    drfr: float = 0.35  # m, random depth reference
    dsfs: float = 5.6e-4  # -, depth scale factor
    dstg: float = 2.5e-7  # 1/m, depth stretch (global)
    abxy_ti1s: float = 0.004  # m/s², xy accelerometer bias, high-side part
    abxy_ti2s: float = 0.004  # m/s², xy accelerometer bias, lateral part
    abz: float = 0.004  # m/s², z accelerometer bias
    asxy_ti1s: float = 5e-4  # -, xy accelerometer scale factor, common part
    asxy_ti2s: float = 5e-4  # -, xy accelerometer scale factor, differential cos 2ψ
    asxy_ti3s: float = 5e-4  # -, xy accelerometer scale factor, differential sin 2ψ
    asz: float = 5e-4  # -, z accelerometer scale factor
    mbxy_ti1s: float = 70.0  # nT, xy magnetometer bias, high-side part
    mbxy_ti2s: float = 70.0  # nT, xy magnetometer bias, lateral part
    mbz: float = 70.0  # nT, z magnetometer bias
    msxy_ti1s: float = 0.0016  # -, xy magnetometer scale factor, common part
    msxy_ti2s: float = 0.0016  # -, xy magnetometer scale factor, differential cos 2ψ
    msxy_ti3s: float = 0.0016  # -, xy magnetometer scale factor, differential sin 2ψ
    msz: float = 0.0016  # -, z magnetometer scale factor
    dec_u: float = 0.16  # deg, declination, well by well
    dec_os: float = 0.24  # deg, declination, global
    dec_oh: float = 0.21  # deg, declination, global
    dec_oi: float = 0.05  # deg, declination, global
    decr: float = 0.1  # deg, declination, random
    dbh_u: float = 2350.0  # deg·nT, declination × horizontal field, well by well
    dbh_os: float = 3359.0  # deg·nT, global
    dbh_oh: float = 2840.0  # deg·nT, global
    dbh_oi: float = 356.0  # deg·nT, global
    dbhr: float = 3000.0  # deg·nT, random
    amil: float = 220.0  # nT, axial magnetic interference
    sage: float = 0.2  # deg, sag (enhanced)
    xym1: float = 0.1  # deg, xy misalignment 1
    xym2: float = 0.1  # deg, xy misalignment 2
    xym3e: float = 0.3  # deg, xy misalignment 3 (random, enhanced)
    xym4e: float = 0.3  # deg, xy misalignment 4 (random, enhanced)
    xcla: float = 0.167  # -, extended course length (azimuth)
    xclh: float = 0.167  # -, extended course length (inclination)
    xcl_tortuosity: float = XCL_TORTUOSITY  # rad/m


MWD_PRESETS: dict[str, MwdTool] = {
    "ISCWSA-MWD-REV5": MwdTool(dec_oh=0.20),
    "ISCWSA-MWD-REV5.11": MwdTool(),
}
"""Named tool models: the Rev 5 example workbook's magnitudes and Rev 5.11's."""


@dataclass(frozen=True)
class _Site:
    """Field geometry at the site: tan Θ, B cos Θ (nT), G (m/s²) and declination (rad)."""

    tan_dip: float
    b_horiz: float
    g: float
    declination: float


def _sensor_terms(tool: MwdTool, site: _Site) -> list[Term]:
    """Accelerometer and magnetometer bias and scale-factor terms (systematic)."""
    tan_d, bh, g = site.tan_dip, site.b_horiz, site.g

    def term(name: str, sigma: float, inc_w: AngleFn, alpha_w: AngleFn) -> Term:
        """A systematic term from its inclination weight and α weight (∂A/∂ε·sin I)."""

        def weight(s: Survey) -> FloatArray:
            am = s.azi - site.declination
            a = (np.sin(s.inc), np.cos(s.inc), np.sin(am), np.cos(am))
            return stack(0.0, inc_w(*a), alpha_w(*a), s.size)

        return Term(name, "systematic", sigma, weight)

    r2 = np.sqrt(2.0)
    return [
        term(
            "ABXY-TI1S",
            tool.abxy_ti1s,
            lambda si, ci, sa, ca: -ci / g,
            lambda si, ci, sa, ca: ci * tan_d * sa * si / g,
        ),
        term(
            "ABXY-TI2S",
            tool.abxy_ti2s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: (ci - tan_d * ca * si) / g,
        ),
        term(
            "ABZ",
            tool.abz,
            lambda si, ci, sa, ca: -si / g,
            lambda si, ci, sa, ca: si * tan_d * sa * si / g,
        ),
        term(
            "ASXY-TI1S",
            tool.asxy_ti1s,
            lambda si, ci, sa, ca: si * ci / r2,
            lambda si, ci, sa, ca: -si * tan_d * ci * sa * si / r2,
        ),
        term(
            "ASXY-TI2S",
            tool.asxy_ti2s,
            lambda si, ci, sa, ca: si * ci / 2.0,
            lambda si, ci, sa, ca: -si * tan_d * ci * sa * si / 2.0,
        ),
        term(
            "ASXY-TI3S",
            tool.asxy_ti3s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: (si * tan_d * ca - ci) / 2.0 * si,
        ),
        term(
            "ASZ",
            tool.asz,
            lambda si, ci, sa, ca: -si * ci,
            lambda si, ci, sa, ca: si * tan_d * ci * sa * si,
        ),
        term(
            "MBXY-TI1S",
            tool.mbxy_ti1s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: -ci * sa / bh * si,
        ),
        term(
            "MBXY-TI2S",
            tool.mbxy_ti2s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: ca / bh * si,
        ),
        term(
            "MBZ",
            tool.mbz,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: -si * sa / bh * si,
        ),
        term(
            "MSXY-TI1S",
            tool.msxy_ti1s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: si * sa * (tan_d * ci + si * ca) / r2 * si,
        ),
        term(
            "MSXY-TI2S",
            tool.msxy_ti2s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: sa * (tan_d * si * ci - ci * ci * ca - ca) / 2.0 * si,
        ),
        term(
            "MSXY-TI3S",
            tool.msxy_ti3s,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: (ci * ca * ca - ci * sa * sa - tan_d * si * ca) / 2.0 * si,
        ),
        term(
            "MSZ",
            tool.msz,
            lambda si, ci, sa, ca: 0.0,
            lambda si, ci, sa, ca: -(si * ca + tan_d * ci) * si * sa * si,
        ),
    ]


def _declination_terms(tool: MwdTool, site: _Site) -> list[Term]:
    """DEC (∂A/∂ε = 1), DBH (1/(B cos Θ)) and AMIL (sin I sin Am/(B cos Θ)) terms."""

    def azimuth(scale: float) -> Weight:
        return lambda s: stack(0.0, 0.0, scale * np.sin(s.inc), s.size)

    decs: list[tuple[str, Propagation, float]] = [
        ("DEC-U", "well_by_well", tool.dec_u),
        ("DEC-OS", "global", tool.dec_os),
        ("DEC-OH", "global", tool.dec_oh),
        ("DEC-OI", "global", tool.dec_oi),
        ("DECR", "random", tool.decr),
    ]
    dbhs: list[tuple[str, Propagation, float]] = [
        ("DBH-U", "well_by_well", tool.dbh_u),
        ("DBH-OS", "global", tool.dbh_os),
        ("DBH-OH", "global", tool.dbh_oh),
        ("DBH-OI", "global", tool.dbh_oi),
        ("DBHR", "random", tool.dbhr),
    ]
    bh = site.b_horiz
    terms = [Term(n, m, v * _DEG, azimuth(1.0)) for n, m, v in decs]
    terms += [Term(n, m, v * _DEG, azimuth(1.0 / bh)) for n, m, v in dbhs]
    terms.append(
        Term(
            "AMIL",
            "systematic",
            tool.amil,
            lambda s: stack(
                0.0, 0.0, np.sin(s.inc) ** 2 * np.sin(s.azi - site.declination) / bh, s.size
            ),
        )
    )
    return terms


def _xcl_terms(tool: MwdTool) -> list[Term]:
    """XCLA and XCLH in position (see the module docstring), random."""
    tort = tool.xcl_tortuosity

    def course(s: Survey) -> FloatArray:
        return s.md - previous(s.md)

    def xcla(s: Survey) -> FloatArray:
        dmd = course(s)
        turn = np.angle(np.exp(1j * (s.azi - previous(s.azi))))  # wrapped to (−π, π]
        lateral = np.abs(np.sin(s.inc) * np.sin(turn))
        lateral[previous(s.inc) < VERTICAL_INC_LIMIT] = 0.0
        size = dmd * np.maximum(lateral, tort * dmd)
        return stack(-size * np.sin(s.azi), size * np.cos(s.azi), 0.0, s.size)

    def xclh(s: Survey) -> FloatArray:
        dmd = course(s)
        size = dmd * np.maximum(np.abs(s.inc - previous(s.inc)), tort * dmd)
        ci = np.cos(s.inc)
        return stack(
            size * ci * np.cos(s.azi), size * ci * np.sin(s.azi), -size * np.sin(s.inc), s.size
        )

    return [
        Term("XCLA", "random", tool.xcla, xcla, frame="nev"),
        Term("XCLH", "random", tool.xclh, xclh, frame="nev"),
    ]


def mwd_terms(tool: MwdTool, magnetic: MagneticReference, *, g: float = STANDARD_G) -> list[Term]:
    """The ISCWSA MWD Rev 5 terms of ``tool`` at a site's field, magnitudes in SI, in the
    workbook's order."""
    dip = np.radians(magnetic.dip)
    site = _Site(
        tan_dip=float(np.tan(dip)),
        b_horiz=float(magnetic.total_field * np.cos(dip)),
        g=g,
        declination=float(np.radians(magnetic.declination)),
    )
    return (
        depth_terms(tool.drfr, tool.dsfs, tool.dstg)
        + _sensor_terms(tool, site)
        + _declination_terms(tool, site)
        + misalignment_terms(tool.sage, tool.xym1, tool.xym2, tool.xym3e, tool.xym4e)
        + _xcl_terms(tool)
    )


def mwd_covariance(
    survey: Survey,
    magnetic: MagneticReference,
    tool: MwdTool | str = "ISCWSA-MWD-REV5.11",
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    g: float = STANDARD_G,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) (m²) of a survey and the term names."""
    tool_ = MWD_PRESETS[tool] if isinstance(tool, str) else tool
    terms = mwd_terms(tool_, magnetic, g=g)
    return term_covariance(survey, terms, basis=basis, surface_tie=surface_tie)

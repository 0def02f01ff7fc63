"""The published ISCWSA/OWSG weighting functions, by code: one registry, one function each.

A weighting function turns the named quantities of a survey
(:class:`~pipeline.uncertainty.quantities.Quantities`) into each station's weights (n, 3)
per unit of the term's magnitude (SI). Measurement terms (``frame="dia"``) give
∂(MD, I, α)/∂ε with α = A·sin I the horizontal azimuth tilt
(:mod:`pipeline.uncertainty.model`): a published azimuth weight ∂A/∂ε appears multiplied by
sin I, which keeps the xy terms (cot I, 1/sin I) finite at vertical. Course-length terms in
position (``frame="nev"``) give the NEV error each station's own course adds.

Sources: SPE 67616 (Williamson, "Accuracy prediction for directional measurement while
drilling", the ISCWSA MWD model, Rev 0–4), the ISCWSA "Error Model Rev 5" documents and
example workbook (toolface-independent xy sensor terms, enhanced misalignments XYM3E/XYM4E,
SAGE, surface tie-on; XCLA/XCLH after Codling, SPE 187249), and SPE 90408 (Torkildsen et
al., "Prediction of wellbore position accuracy when surveyed with gyroscopic tools", the
ISCWSA gyro model; OWSG GYRO-NS / GYRO-NS-CT sheets). Each function's docstring names its
source and states its weights.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pipeline.uncertainty.quantities import Quantities
from pipeline.uncertainty.terms import misalignment_factor, previous, stack

__all__ = ["WEIGHT_FUNCTIONS", "WeightFunction"]

FloatArray = NDArray[np.float64]
Frame = Literal["dia", "nev"]
#: Below this inclination (rad) a station counts as vertical (the ISCWSA workbook's limit).
VERTICAL_INC_LIMIT = 1e-4


@dataclass(frozen=True)
class WeightFunction:
    """A registered weighting function: its code, the measurements it acts on (``depth``,
    ``inc``, ``azi``, or ``nev`` for a term in position), the SI dimension of the magnitude
    it expects, the model parameters and site quantities (``latitude``, ``magnetic``) it
    reads, and the function."""

    code: str
    acts_on: frozenset[str]
    dimension: str
    fn: Callable[[Quantities], FloatArray]
    parameters: tuple[str, ...] = ()
    site: frozenset[str] = frozenset()

    @property
    def frame(self) -> Frame:
        return "nev" if "nev" in self.acts_on else "dia"

    @property
    def doc(self) -> str:
        return (self.fn.__doc__ or "").strip()


WEIGHT_FUNCTIONS: dict[str, WeightFunction] = {}
"""Every weighting function by code."""


def _weight(
    code: str, acts_on: str, dimension: str, parameters: tuple[str, ...] = (), site: str = ""
) -> Callable[[Callable[[Quantities], FloatArray]], Callable[[Quantities], FloatArray]]:
    def register(fn: Callable[[Quantities], FloatArray]) -> Callable[[Quantities], FloatArray]:
        WEIGHT_FUNCTIONS[code] = WeightFunction(
            code, frozenset(acts_on.split()), dimension, fn, parameters, frozenset(site.split())
        )
        return fn

    return register


def _dia(q: Quantities, d: ArrayLike, i: ArrayLike, a: ArrayLike) -> FloatArray:
    return stack(d, i, a, q.n)


def _mag_angles(q: Quantities) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """sin I, cos I, sin Am, cos Am (Am the magnetic azimuth)."""
    am = q.azm
    return np.sin(q.inc), np.cos(q.inc), np.sin(am), np.cos(am)


# ------------------------------------------------------------------ depth (SPE 67616 §depth)


@_weight("DREF", "depth", "m")
def dref(q: Quantities) -> FloatArray:
    """Depth reference error (SPE 67616; ISCWSA MWD Rev 4/5 DRFR): ∂MD/∂ε = 1."""
    return _dia(q, 1.0, 0.0, 0.0)


@_weight("DSF", "depth", "-")
def dsf(q: Quantities) -> FloatArray:
    """Depth scale factor (SPE 67616; ISCWSA DSFS): ∂MD/∂ε = MD."""
    return _dia(q, q.md, 0.0, 0.0)


@_weight("DST", "depth", "1/m")
def dst(q: Quantities) -> FloatArray:
    """Depth stretch, thermal/tension (SPE 67616; ISCWSA DSTG): ∂MD/∂ε = MD·TVD."""
    return _dia(q, q.md * q.tvd, 0.0, 0.0)


# ------------------------------------------------------------------ magnetic sensors (Rev 5 TI)


@_weight("ABXY-TI1", "inc azi", "m/s2", site="magnetic")
def abxy_ti1(q: Quantities) -> FloatArray:
    """xy accelerometer bias, high-side part (ISCWSA MWD Rev 4/5, toolface independent):
    ∂I = −cos I/G, ∂A = cos I tan Θ sin Am/G."""
    si, ci, sa, _ca = _mag_angles(q)
    tan_d, g = q.tan_dip, q.g
    return _dia(q, 0.0, -ci / g, ci * tan_d * sa * si / g)


@_weight("ABXY-TI2", "azi", "m/s2", site="magnetic")
def abxy_ti2(q: Quantities) -> FloatArray:
    """xy accelerometer bias, lateral part (ISCWSA MWD Rev 4/5): ∂A = (cot I − tan Θ cos Am)/G,
    as α weight (cos I − tan Θ cos Am sin I)/G, finite at vertical (the vertical-hole form
    of the Rev 5 workbook without a special case)."""
    si, ci, _sa, ca = _mag_angles(q)
    tan_d, g = q.tan_dip, q.g
    return _dia(q, 0.0, 0.0, (ci - tan_d * ca * si) / g)


@_weight("ABZ", "inc azi", "m/s2", site="magnetic")
def abz(q: Quantities) -> FloatArray:
    """z accelerometer bias (SPE 67616; ISCWSA MWD Rev 4/5): ∂I = −sin I/G,
    ∂A = sin I tan Θ sin Am/G."""
    si, _ci, sa, _ca = _mag_angles(q)
    tan_d, g = q.tan_dip, q.g
    return _dia(q, 0.0, -si / g, si * tan_d * sa * si / g)


@_weight("ASXY-TI1", "inc azi", "-", site="magnetic")
def asxy_ti1(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, common part (ISCWSA MWD Rev 4/5):
    ∂I = sin I cos I/√2, ∂A = −sin I tan Θ cos I sin Am/√2."""
    si, ci, sa, _ca = _mag_angles(q)
    tan_d, r2 = q.tan_dip, np.sqrt(2.0)
    return _dia(q, 0.0, si * ci / r2, -si * tan_d * ci * sa * si / r2)


@_weight("ASXY-TI2", "inc azi", "-", site="magnetic")
def asxy_ti2(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, differential cos 2ψ half (ISCWSA MWD Rev 4/5):
    ∂I = sin I cos I/2, ∂A = −sin I tan Θ cos I sin Am/2."""
    si, ci, sa, _ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, si * ci / 2.0, -si * tan_d * ci * sa * si / 2.0)


@_weight("ASXY-TI3", "azi", "-", site="magnetic")
def asxy_ti3(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, differential sin 2ψ half (ISCWSA MWD Rev 4/5):
    ∂A = (sin I tan Θ cos Am − cos I)/2."""
    si, ci, _sa, ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, 0.0, (si * tan_d * ca - ci) / 2.0 * si)


@_weight("ASZ", "inc azi", "-", site="magnetic")
def asz(q: Quantities) -> FloatArray:
    """z accelerometer scale factor (SPE 67616; ISCWSA MWD Rev 4/5): ∂I = −sin I cos I,
    ∂A = sin I tan Θ cos I sin Am."""
    si, ci, sa, _ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, -si * ci, si * tan_d * ci * sa * si)


@_weight("MBXY-TI1", "azi", "nT", site="magnetic")
def mbxy_ti1(q: Quantities) -> FloatArray:
    """xy magnetometer bias, high-side part (ISCWSA MWD Rev 4/5): ∂A = −cos I sin Am/(B cos Θ)."""
    si, ci, sa, _ca = _mag_angles(q)
    return _dia(q, 0.0, 0.0, -ci * sa / q.b_horiz * si)


@_weight("MBXY-TI2", "azi", "nT", site="magnetic")
def mbxy_ti2(q: Quantities) -> FloatArray:
    """xy magnetometer bias, lateral part (ISCWSA MWD Rev 4/5): ∂A = cos Am/(B cos Θ)."""
    si, _ci, _sa, ca = _mag_angles(q)
    return _dia(q, 0.0, 0.0, ca / q.b_horiz * si)


@_weight("MBZ", "azi", "nT", site="magnetic")
def mbz(q: Quantities) -> FloatArray:
    """z magnetometer bias (SPE 67616; ISCWSA MWD Rev 4/5): ∂A = −sin I sin Am/(B cos Θ)."""
    si, _ci, sa, _ca = _mag_angles(q)
    return _dia(q, 0.0, 0.0, -si * sa / q.b_horiz * si)


@_weight("MSXY-TI1", "azi", "-", site="magnetic")
def msxy_ti1(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, common part (ISCWSA MWD Rev 4/5):
    ∂A = sin I sin Am (tan Θ cos I + sin I cos Am)/√2."""
    si, ci, sa, ca = _mag_angles(q)
    tan_d, r2 = q.tan_dip, np.sqrt(2.0)
    return _dia(q, 0.0, 0.0, si * sa * (tan_d * ci + si * ca) / r2 * si)


@_weight("MSXY-TI2", "azi", "-", site="magnetic")
def msxy_ti2(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, differential cos 2ψ half (ISCWSA MWD Rev 4/5):
    ∂A = sin Am (tan Θ sin I cos I − cos² I cos Am − cos Am)/2."""
    si, ci, sa, ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, 0.0, sa * (tan_d * si * ci - ci * ci * ca - ca) / 2.0 * si)


@_weight("MSXY-TI3", "azi", "-", site="magnetic")
def msxy_ti3(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, differential sin 2ψ half (ISCWSA MWD Rev 4/5):
    ∂A = (cos I cos² Am − cos I sin² Am − tan Θ sin I cos Am)/2."""
    si, ci, sa, ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, 0.0, (ci * ca * ca - ci * sa * sa - tan_d * si * ca) / 2.0 * si)


@_weight("MSZ", "azi", "-", site="magnetic")
def msz(q: Quantities) -> FloatArray:
    """z magnetometer scale factor (SPE 67616; ISCWSA MWD Rev 4/5):
    ∂A = −(sin I cos Am + tan Θ cos I) sin I sin Am."""
    si, ci, sa, ca = _mag_angles(q)
    tan_d = q.tan_dip
    return _dia(q, 0.0, 0.0, -(si * ca + tan_d * ci) * si * sa * si)


# ------------------------------------------------------------------ declination and interference


@_weight("AZ", "azi", "rad")
def az(q: Quantities) -> FloatArray:
    """An azimuth reference error (SPE 67616 declination DEC; ISCWSA DEC-U/-OS/-OH/-OI/DECR,
    Rev 4 DECG; a measured initial azimuth, SPE 90408): ∂A/∂ε = 1."""
    return _dia(q, 0.0, 0.0, 1.0 * np.sin(q.inc))


@_weight("DBH", "azi", "rad.nT", site="magnetic")
def dbh(q: Quantities) -> FloatArray:
    """Declination error proportional to 1/(B cos Θ) (SPE 67616 DBH; ISCWSA DBH-U/-OS/-OH/-OI,
    DBHR, Rev 4 DBHG): ∂A/∂ε = 1/(B cos Θ)."""
    return _dia(q, 0.0, 0.0, 1.0 / q.b_horiz * np.sin(q.inc))


@_weight("AMIL", "azi", "nT", site="magnetic")
def amil(q: Quantities) -> FloatArray:
    """Axial magnetic interference (ISCWSA MWD Rev 4/5 AMIL): ∂A = sin I sin Am/(B cos Θ)."""
    return _dia(q, 0.0, 0.0, np.sin(q.inc) ** 2 * np.sin(q.azi - q.declination) / q.b_horiz)


# ------------------------------------------------------------------ sag and misalignments


@_weight("SAG", "inc", "rad")
def sag(q: Quantities) -> FloatArray:
    """BHA sag (SPE 67616; ISCWSA MWD Rev 4 SAG): ∂I = sin I."""
    return _dia(q, 0.0, np.sin(q.inc), 0.0)


@_weight("SAGE", "inc", "rad")
def sage(q: Quantities) -> FloatArray:
    """BHA sag, enhanced (ISCWSA Rev 5 SAGE): ∂I = |sin I|^¼."""
    return _dia(q, 0.0, np.abs(np.sin(q.inc)) ** 0.25, 0.0)


@_weight("XYM1", "inc", "rad")
def xym1(q: Quantities) -> FloatArray:
    """xy misalignment 1 (SPE 67616 MX/MY, ISCWSA Rev 4/5 XYM1): ∂I = |sin I|."""
    return _dia(q, 0.0, np.abs(np.sin(q.inc)), 0.0)


@_weight("XYM2", "azi", "rad")
def xym2(q: Quantities) -> FloatArray:
    """xy misalignment 2 (ISCWSA Rev 4/5 XYM2): ∂A = −1."""
    return _dia(q, 0.0, 0.0, -np.sin(q.inc))


@_weight("XYM3", "inc azi", "rad")
def xym3(q: Quantities) -> FloatArray:
    """xy misalignment 3 (ISCWSA Rev 4 XYM3): ∂I = |cos I| cos A, ∂A = −|cos I| sin A/sin I
    (A true)."""
    c = np.abs(np.cos(q.inc))
    return _dia(q, 0.0, c * np.cos(q.azi), -c * np.sin(q.azi))


@_weight("XYM4", "inc azi", "rad")
def xym4(q: Quantities) -> FloatArray:
    """xy misalignment 4 (ISCWSA Rev 4 XYM4): ∂I = |cos I| sin A, ∂A = |cos I| cos A/sin I."""
    c = np.abs(np.cos(q.inc))
    return _dia(q, 0.0, c * np.sin(q.azi), c * np.cos(q.azi))


@_weight("XYM3E", "inc azi", "rad")
def xym3e(q: Quantities) -> FloatArray:
    """xy misalignment 3, enhanced (ISCWSA Rev 5 XYM3E): XYM3's weights times
    max(1, √(10 m/ΔMD)) (0 at ΔMD = 0), the short-course damping."""
    c = np.abs(np.cos(q.inc)) * misalignment_factor(q.survey)
    return _dia(q, 0.0, c * np.cos(q.azi), -c * np.sin(q.azi))


@_weight("XYM4E", "inc azi", "rad")
def xym4e(q: Quantities) -> FloatArray:
    """xy misalignment 4, enhanced (ISCWSA Rev 5 XYM4E): XYM4's weights times
    max(1, √(10 m/ΔMD))."""
    c = np.abs(np.cos(q.inc)) * misalignment_factor(q.survey)
    return _dia(q, 0.0, c * np.sin(q.azi), c * np.cos(q.azi))


# ------------------------------------------------------------------ extended course length


@_weight("XCLA", "nev", "-", ("tortuosity",))
def xcla(q: Quantities) -> FloatArray:
    """Extended course length, azimuth (ISCWSA Rev 5; Codling, SPE 187249), in position:
    ΔMD·max(|sin I sin ΔA|, τ·ΔMD)·(−sin A, cos A, 0), ΔA wrapped to (−π, π] and 0 after a
    vertical station, τ the parameter ``tortuosity`` (rad/m)."""
    tort = q.parameter("tortuosity")
    dmd = q.dmd
    turn = np.angle(np.exp(1j * (q.azi - previous(q.azi))))
    lateral = np.abs(np.sin(q.inc) * np.sin(turn))
    lateral[previous(q.inc) < VERTICAL_INC_LIMIT] = 0.0
    size = dmd * np.maximum(lateral, tort * dmd)
    return stack(-size * np.sin(q.azi), size * np.cos(q.azi), 0.0, q.n)


@_weight("XCLH", "nev", "-", ("tortuosity",))
def xclh(q: Quantities) -> FloatArray:
    """Extended course length, inclination (ISCWSA Rev 5; SPE 187249), in position:
    ΔMD·max(|ΔI|, τ·ΔMD)·(cos I cos A, cos I sin A, −sin I)."""
    tort = q.parameter("tortuosity")
    dmd = q.dmd
    size = dmd * np.maximum(np.abs(q.inc - previous(q.inc)), tort * dmd)
    ci = np.cos(q.inc)
    return stack(size * ci * np.cos(q.azi), size * ci * np.sin(q.azi), -size * np.sin(q.inc), q.n)


# ------------------------------------------------------------------ gyro (SPE 90408, OWSG GYRO-NS)


@_weight("AXYZ-MIS", "inc", "rad")
def axyz_mis(q: Quantities) -> FloatArray:
    """Accelerometer misalignment (SPE 90408; OWSG GYRO-NS AXYZ-MIS): ∂I = 1."""
    return _dia(q, 0.0, 1.0, 0.0)


@_weight("AXYZ-SF", "inc", "-")
def axyz_sf(q: Quantities) -> FloatArray:
    """Accelerometer scale factor (SPE 90408; OWSG AXYZ-SF): ∂I = 1.3 sin I cos I."""
    return _dia(q, 0.0, 1.3 * np.sin(q.inc) * np.cos(q.inc), 0.0)


@_weight("AXYZ-ZB", "inc", "m/s2")
def axyz_zb(q: Quantities) -> FloatArray:
    """Accelerometer bias (SPE 90408; OWSG AXYZ-ZB): ∂I = sin I/G."""
    return _dia(q, 0.0, np.sin(q.inc) / q.g, 0.0)


@_weight("GXY-B1", "azi", "rad/h", site="latitude")
def gxy_b1(q: Quantities) -> FloatArray:
    """xy gyro bias 1, stationary gyrocompass (SPE 90408; OWSG GXY-B1): α weight
    sin A tan I/(Ω cos φ)."""
    return _dia(q, 0.0, 0.0, np.sin(q.azi) * np.tan(q.inc) / q.omega_h)


@_weight("GXY-B2", "azi", "rad/h", site="latitude")
def gxy_b2(q: Quantities) -> FloatArray:
    """xy gyro bias 2 (SPE 90408; OWSG GXY-B2): α weight cos A sin I/(Ω cos φ)."""
    return _dia(q, 0.0, 0.0, np.cos(q.azi) * np.sin(q.inc) / q.omega_h)


@_weight("GXY-G1", "azi", "rad/h/g", site="latitude")
def gxy_g1(q: Quantities) -> FloatArray:
    """xy gyro g-dependent error 1 (SPE 90408; OWSG GXY-G1): α weight
    cos A sin² I/(Ω cos φ)."""
    return _dia(q, 0.0, 0.0, np.cos(q.azi) * np.sin(q.inc) ** 2 / q.omega_h)


@_weight("GXY-G4", "azi", "rad/h/g", site="latitude")
def gxy_g4(q: Quantities) -> FloatArray:
    """xy gyro g-dependent error 4 (SPE 90408; OWSG GXY-G4): α weight
    sin A tan I sin I/(Ω cos φ)."""
    return _dia(q, 0.0, 0.0, np.sin(q.azi) * np.tan(q.inc) * np.sin(q.inc) / q.omega_h)


@_weight("GXY-RN", "azi", "rad/h", ("noise_reduction",), site="latitude")
def gxy_rn(q: Quantities) -> FloatArray:
    """xy gyro random noise (SPE 90408; OWSG GXY-RN): α weight
    f·√(1 − cos² A sin² I)·tan I/(Ω cos φ), f the parameter ``noise_reduction``."""
    f = q.parameter("noise_reduction")
    root = np.sqrt(np.clip(1.0 - (np.cos(q.azi) * np.sin(q.inc)) ** 2, 0.0, None))
    return _dia(q, 0.0, 0.0, f * root * np.tan(q.inc) / q.omega_h)


def _running(q: Quantities, power: int) -> FloatArray:
    """Continuous drift (power 1: hours) or random-walk (power 2: √hours) coefficient at each
    station, accumulated over legs ending above the ``static_end_inc`` gate and reset at or
    below it (SPE 90408 Table 7)."""
    speed, gate = q.parameter("running_speed"), q.parameter("static_end_inc")
    mean_sin = np.abs(np.sin(0.5 * (q.inc + previous(q.inc))))
    active = q.inc > gate
    active[0] = False
    step = np.zeros_like(q.md)
    with np.errstate(divide="ignore", invalid="ignore"):
        step[active] = q.dmd[active] / (speed * mean_sin[active] ** power)
    total = np.cumsum(step)
    base = np.maximum.accumulate(np.where(active, 0.0, total))
    h = total - base
    out: FloatArray = h if power == 1 else np.sqrt(h)
    return out


@_weight("GXY-GD", "azi", "rad/h", ("running_speed", "static_end_inc"))
def gxy_gd(q: Quantities) -> FloatArray:
    """Continuous xy gyro drift (SPE 90408 Table 7; OWSG GYRO-NS-CT GXY-GD): ∂A = h_i hours,
    h_i = h_{i−1} + ΔMD_i/(c sin Ī_i) above the static end inclination (reset at or below
    it), c the ``running_speed`` (m/h), Ī the leg's mean inclination."""
    return _dia(q, 0.0, 0.0, _running(q, 1) * np.sin(q.inc))


@_weight("GXY-GRW", "azi", "rad/sqrt(h)", ("running_speed", "static_end_inc"))
def gxy_grw(q: Quantities) -> FloatArray:
    """Continuous xy gyro random walk (SPE 90408 Table 7; OWSG GXY-GRW): ∂A = h_i √hours,
    h_i = √(h_{i−1}² + ΔMD_i/(c sin² Ī_i)), gated as GXY-GD."""
    return _dia(q, 0.0, 0.0, _running(q, 2) * np.sin(q.inc))


# ------------------------------------------------------------------ axial correction (OWSG +AX)


def _ax(q: Quantities) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """sin I, cos I, sin Am, cos Am and the axial-correction factor 1/(1 − sin² I sin² Am)
    of the OWSG +AX sheets (the short-collar correction's sensitivity, SPE 67616 App.)."""
    si, ci, sa, ca = _mag_angles(q)
    return si, ci, sa, ca, 1.0 / (1.0 - (si * sa) ** 2)


def _ax_lever(q: Quantities) -> FloatArray:
    """sin Am (tan Θ cos I + sin I cos Am)/(1 − sin² I sin² Am), the factor the +AX
    accelerometer and magnetometer weights share."""
    si, ci, sa, ca, k = _ax(q)
    return sa * (q.tan_dip * ci + si * ca) * k


@_weight("ABIXY-TI1", "inc azi", "m/s2", site="magnetic")
def abixy_ti1(q: Quantities) -> FloatArray:
    """xy accelerometer bias, high side, axially corrected (OWSG +AX sheets): ∂I = −cos I/G,
    ∂A = cos² I sin Am (tan Θ cos I + sin I cos Am)/(G (1 − sin² I sin² Am))."""
    si, ci = np.sin(q.inc), np.cos(q.inc)
    return _dia(q, 0.0, -ci / q.g, ci * ci * _ax_lever(q) / q.g * si)


@_weight("ABIXY-TI2", "azi", "m/s2", site="magnetic")
def abixy_ti2(q: Quantities) -> FloatArray:
    """xy accelerometer bias, lateral, axially corrected (OWSG +AX):
    ∂A = (cot I − tan Θ cos Am)/(G (1 − sin² I sin² Am)), as α weight
    (cos I − tan Θ cos Am sin I)/(G (1 − sin² I sin² Am)), finite at vertical."""
    si, ci, _sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, (ci - q.tan_dip * ca * si) * k / q.g)


@_weight("ABIZ", "inc azi", "m/s2", site="magnetic")
def abiz(q: Quantities) -> FloatArray:
    """z accelerometer bias, axially corrected (OWSG +AX): ∂I = −sin I/G,
    ∂A = sin I cos I sin Am (tan Θ cos I + sin I cos Am)/(G (1 − sin² I sin² Am))."""
    si, ci = np.sin(q.inc), np.cos(q.inc)
    return _dia(q, 0.0, -si / q.g, si * ci * _ax_lever(q) / q.g * si)


@_weight("ASIXY-TI1", "inc azi", "-", site="magnetic")
def asixy_ti1(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, common, axially corrected (OWSG +AX):
    ∂I = sin I cos I/√2, ∂A = −sin I cos² I sin Am (tan Θ cos I + sin I cos Am)/(√2 (1 − …))."""
    si, ci, r2 = np.sin(q.inc), np.cos(q.inc), np.sqrt(2.0)
    return _dia(q, 0.0, si * ci / r2, -si * ci * ci * _ax_lever(q) / r2 * si)


@_weight("ASIXY-TI2", "inc azi", "-", site="magnetic")
def asixy_ti2(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, cos 2ψ half, axially corrected (OWSG +AX):
    ∂I = sin I cos I/2, ∂A = −sin I cos² I sin Am (tan Θ cos I + sin I cos Am)/(2 (1 − …))."""
    si, ci = np.sin(q.inc), np.cos(q.inc)
    return _dia(q, 0.0, si * ci / 2.0, -si * ci * ci * _ax_lever(q) / 2.0 * si)


@_weight("ASIXY-TI3", "azi", "-", site="magnetic")
def asixy_ti3(q: Quantities) -> FloatArray:
    """xy accelerometer scale factor, sin 2ψ half, axially corrected (OWSG +AX):
    ∂A = (tan Θ sin I cos Am − cos I)/(2 (1 − sin² I sin² Am))."""
    si, ci, _sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, (q.tan_dip * si * ca - ci) * k / 2.0 * si)


@_weight("ASIZ", "inc azi", "-", site="magnetic")
def asiz(q: Quantities) -> FloatArray:
    """z accelerometer scale factor, axially corrected (OWSG +AX): ∂I = −sin I cos I,
    ∂A = sin I cos² I sin Am (tan Θ cos I + sin I cos Am)/(1 − sin² I sin² Am)."""
    si, ci = np.sin(q.inc), np.cos(q.inc)
    return _dia(q, 0.0, -si * ci, si * ci * ci * _ax_lever(q) * si)


@_weight("MBIXY-TI1", "azi", "nT", site="magnetic")
def mbixy_ti1(q: Quantities) -> FloatArray:
    """xy magnetometer bias, high side, axially corrected (OWSG +AX):
    ∂A = −cos I sin Am/(B cos Θ (1 − sin² I sin² Am))."""
    si, ci, sa, _ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, -ci * sa * k / q.b_horiz * si)


@_weight("MBIXY-TI2", "azi", "nT", site="magnetic")
def mbixy_ti2(q: Quantities) -> FloatArray:
    """xy magnetometer bias, lateral, axially corrected (OWSG +AX):
    ∂A = cos Am/(B cos Θ (1 − sin² I sin² Am))."""
    si, _ci, _sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, ca * k / q.b_horiz * si)


@_weight("MSIXY-TI1", "azi", "-", site="magnetic")
def msixy_ti1(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, common, axially corrected (OWSG +AX):
    ∂A = sin I sin Am (tan Θ cos I + sin I cos Am)/(√2 (1 − sin² I sin² Am))."""
    si = np.sin(q.inc)
    return _dia(q, 0.0, 0.0, si * _ax_lever(q) / np.sqrt(2.0) * si)


@_weight("MSIXY-TI2", "azi", "-", site="magnetic")
def msixy_ti2(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, cos 2ψ half, axially corrected (OWSG +AX):
    ∂A = sin Am (tan Θ sin I cos I − cos² I cos Am − cos Am)/(2 (1 − sin² I sin² Am))."""
    si, ci, sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, sa * (q.tan_dip * si * ci - ci * ci * ca - ca) * k / 2.0 * si)


@_weight("MSIXY-TI3", "azi", "-", site="magnetic")
def msixy_ti3(q: Quantities) -> FloatArray:
    """xy magnetometer scale factor, sin 2ψ half, axially corrected (OWSG +AX):
    ∂A = (cos I cos² Am − cos I sin² Am − tan Θ sin I cos Am)/(2 (1 − sin² I sin² Am))."""
    si, ci, sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, (ci * (ca * ca - sa * sa) - q.tan_dip * si * ca) * k / 2.0 * si)


@_weight("MDI", "azi", "rad", site="magnetic")
def mdi(q: Quantities) -> FloatArray:
    """Dip-angle error of the axial correction (OWSG +AX MDI-*):
    ∂A = −sin I sin Am (cos I − tan Θ sin I cos Am)/(1 − sin² I sin² Am)."""
    si, ci, sa, ca, k = _ax(q)
    return _dia(q, 0.0, 0.0, -si * sa * (ci - q.tan_dip * si * ca) * k * si)


@_weight("MFI", "azi", "nT", site="magnetic")
def mfi(q: Quantities) -> FloatArray:
    """Total-field error of the axial correction (OWSG +AX MFI-*):
    ∂A = −sin I sin Am (tan Θ cos I + sin I cos Am)/((1 − sin² I sin² Am) B)."""
    si = np.sin(q.inc)
    return _dia(q, 0.0, 0.0, -si * _ax_lever(q) / q.b_total * si)


# ------------------------------------------------------------------ film, dipmeter, blind (OWSG)


@_weight("AMID", "azi", "rad", site="magnetic")
def amid(q: Quantities) -> FloatArray:
    """Axial magnetic interference as an angle (OWSG film/dipmeter sheets AMID):
    ∂A = sin I sin Am."""
    si = np.sin(q.inc)
    return _dia(q, 0.0, 0.0, si * np.sin(q.azm) * si)


@_weight("CNA", "azi", "-")
def cna(q: Quantities) -> FloatArray:
    """Cone of uncertainty, azimuth (OWSG BLIND/UNKNOWN/FINDS CNA): ∂A = 1/sin I, α weight
    1 (at vertical the sheet's singular vector (−sin A, cos A, 0))."""
    return _dia(q, 0.0, 0.0, 1.0)


@_weight("CNI", "inc", "-")
def cni(q: Quantities) -> FloatArray:
    """Cone of uncertainty, inclination (OWSG BLIND/UNKNOWN/FINDS CNI): ∂I = 1."""
    return _dia(q, 0.0, 1.0, 0.0)

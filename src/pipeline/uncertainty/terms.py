"""Error terms of the ISCWSA error models and their evaluation over a survey.

A :class:`Term` is one error source: a name, a propagation mode, a 1σ magnitude in SI and a
weight function of the survey. Most terms are measurement errors (``frame="dia"``): the
weight is ∂(MD, I, α)/∂ε per station, α = A·sin I the horizontal azimuth tilt (see
:mod:`pipeline.uncertainty.model`), so an azimuth weight ∂A/∂ε of a published model appears
multiplied by sin I. Course-length terms defined directly in position (``frame="nev"``, the
ISCWSA MWD workbook's XCLA/XCLH) give the NEV error (m per unit ε) each station's own course
adds; it acts on that station and every one below it alike (e_k = e*_k).

Tool models build their terms from model files (:mod:`pipeline.uncertainty.toolmodel`,
weighting functions in :mod:`pipeline.uncertainty.weightfns`); a caller may also build
:class:`Term` objects directly and propagate them with :func:`term_covariance`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pipeline.uncertainty.model import (
    Basis,
    Propagation,
    leg_effects,
    propagate_nev,
    station_jacobians,
)

__all__ = [
    "STANDARD_G",
    "Frame",
    "Survey",
    "Term",
    "Weight",
    "misalignment_factor",
    "previous",
    "stack",
    "term_covariance",
    "term_effects",
]

FloatArray = NDArray[np.float64]
Frame = Literal["dia", "nev"]

STANDARD_G = 9.80665
"""Standard gravity (m/s²), the ISCWSA models' G."""


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

    @property
    def size(self) -> int:
        return int(self.md.size)


Weight = Callable[[Survey], FloatArray]


@dataclass(frozen=True)
class Term:
    """One error source: name, propagation mode, 1σ magnitude (SI) and weights (n, 3):
    ∂(MD, I, α)/∂ε for ``frame="dia"``, the NEV error per unit ε for ``frame="nev"``."""

    name: str
    mode: Propagation
    sigma: float
    weight: Weight
    frame: Frame = "dia"


def stack(d: ArrayLike, i: ArrayLike, a: ArrayLike, n: int) -> FloatArray:
    """Weights (n, 3) from three columns (scalars broadcast)."""
    out = np.zeros((n, 3))
    out[:, 0] = d
    out[:, 1] = i
    out[:, 2] = a
    return out


def previous(x: FloatArray) -> FloatArray:
    """Each station's predecessor value (station 0 its own)."""
    return np.concatenate((x[:1], x[:-1]))


def misalignment_factor(s: Survey) -> FloatArray:
    """max(1, √(10 m/ΔMD)): short-course damping of the random misalignments (0 at ΔMD = 0)."""
    dmd = s.md - previous(s.md)
    f = np.zeros_like(dmd)
    pos = dmd > 0
    f[pos] = np.maximum(1.0, np.sqrt(10.0 / dmd[pos]))
    return f


def term_effects(
    survey: Survey, terms: Sequence[Term], *, basis: Basis, surface_tie: bool
) -> tuple[FloatArray, FloatArray]:
    """Each term's NEV effect (m, n, 3) on the stations below each station (e_k) and on the
    station itself (e*_k), as :func:`term_covariance` propagates them (see
    :mod:`pipeline.uncertainty.model`)."""
    full = np.empty((len(terms), survey.size, 3))
    star = np.empty_like(full)
    dia = np.array([t.frame == "dia" for t in terms], dtype=bool)
    if dia.any():
        jac = station_jacobians(
            survey.md, survey.inc, survey.azi, basis=basis, surface_tie=surface_tie
        )
        e_dia = np.stack([t.sigma * t.weight(survey) for t in terms if t.frame == "dia"])
        full[dia], star[dia] = leg_effects(e_dia, jac)
    for k, t in enumerate(terms):
        if t.frame != "dia":
            full[k] = star[k] = t.sigma * t.weight(survey)
    return full, star


def term_covariance(
    survey: Survey,
    terms: Sequence[Term],
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) of a survey (m²) and the term names.

    ``basis`` and ``surface_tie`` as in :func:`pipeline.uncertainty.model.station_jacobians`.
    """
    if basis not in ("min_curve", "balanced_tangent"):
        raise ValueError(f"unknown basis {basis!r}; expected 'min_curve' or 'balanced_tangent'")
    basis_: Basis = "min_curve" if basis == "min_curve" else "balanced_tangent"
    full, star = term_effects(survey, terms, basis=basis_, surface_tie=surface_tie)
    cov = propagate_nev(full, star, [t.mode for t in terms])
    return [t.name for t in terms], cov

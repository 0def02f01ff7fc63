"""Position covariance of a survey assembled from tied sections (a definitive survey).

A definitive survey is one list of stations made of sections, each one run's stations over
a depth interval; a section below the first is tied at the last station of the section
above, so its first course runs from that station (the run above's MD and angles) to its
own first station. The position of every station is minimum curvature through the list,
and its error is the ISCWSA propagation over the list (SPE 67616,
:mod:`pipeline.uncertainty.model`) with each station's measurement errors those of its own
run:

    ε_K = Σ_{k<K} e_k + e*_K,   e_k, e*_k the effects of station k's errors, weighted by
                                the terms of the run station k comes from

So a run's depth errors act on its own MD (the course from the tie to the run's first
station is as long as the run's MD there minus the MD of the tie above); the angle errors
of the tie station, the run above's, move the course below it too; and nothing carried
from above is lost at a tie: the covariance is continuous.

Term weights are evaluated per section over its stations and the tie station above (so
that a course-length weight sees the course into the section's first station); the tie
station's own weight is the run above's.

Correlation between sections follows the ISCWSA propagation modes, an error source being
one standard-normal draw per *correlation key*:

    random        one draw per station: independent everywhere
    systematic    one draw per run: correlated within the run, independent between runs
    well_by_well  one draw per well (``well_by_well="shared"``, the ISCWSA rule), or per
                  run (``"per_run"``)
    global        one draw for all: shared by every run

so the covariance of a station is Σ over keys of v vᵀ (v the summed NEV effect of every
term of that key) plus the random terms' Σ e eᵀ.

Frame NEV (north, east, vertical down), lengths m, angles rad, covariances m².
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.uncertainty.model import (
    Basis,
    Propagation,
    leg_effects,
    propagate_nev,
    station_jacobians,
)
from pipeline.uncertainty.terms import Survey, Term

__all__ = ["Section", "WellByWell", "definitive_covariance"]

FloatArray = NDArray[np.float64]
WellByWell = Literal["shared", "per_run"]
Key = tuple[str, ...]


@dataclass(frozen=True)
class Section:
    """One section: the run id that scopes its systematic terms, the rows ``start`` to
    ``stop`` (exclusive) of the survey it lists, and the run's error terms."""

    run: str
    start: int
    stop: int
    terms: Sequence[Term]


def _key(run: str, term: Term, well_by_well: WellByWell) -> Key:
    """The correlation key of a systematic, well-by-well or global term."""
    if term.mode == "global" or (term.mode == "well_by_well" and well_by_well == "shared"):
        return (term.mode, term.name)
    return (term.mode, run, term.name)


def _errors(survey: Survey, section: Section) -> FloatArray:
    """Each term's 1σ weight (m, n, 3) over the whole survey, zero off the section's rows,
    evaluated over the section's stations and the tie station above."""
    lo = max(section.start - 1, 0)
    part = Survey(*(x[lo : section.stop] for x in (survey.md, survey.inc, survey.azi, survey.tvd)))
    out = np.zeros((len(section.terms), survey.size, 3))
    own = section.start - lo
    for j, term in enumerate(section.terms):
        out[j, section.start : section.stop] = (term.sigma * term.weight(part))[own:]
    return out


def definitive_covariance(
    survey: Survey,
    sections: Sequence[Section],
    *,
    basis: Basis = "balanced_tangent",
    surface_tie: bool = False,
    well_by_well: WellByWell = "shared",
) -> FloatArray:
    """NEV covariance (n, 3, 3) of the stations of ``survey`` (m²), listed by ``sections``
    (contiguous, top down, covering it); ``surface_tie`` applies the ISCWSA surface tie-on
    allowance at the first station."""
    jac = station_jacobians(survey.md, survey.inc, survey.azi, basis=basis, surface_tie=surface_tie)
    sums: dict[Key, tuple[FloatArray, FloatArray]] = {}
    randoms: list[tuple[FloatArray, FloatArray]] = []
    for section in sections:
        errors = _errors(survey, section)
        dia = np.array([t.frame == "dia" for t in section.terms], dtype=bool)
        full, star = errors.copy(), errors.copy()  # position-defined terms: e_k = e*_k
        if dia.any():
            full[dia], star[dia] = leg_effects(errors[dia], jac)
        for j, term in enumerate(section.terms):
            if term.mode == "random":
                randoms.append((full[j], star[j]))
                continue
            key = _key(section.run, term, well_by_well)
            zero = np.zeros_like(full[j])
            f, s = sums.get(key, (zero, zero))
            sums[key] = (f + full[j], s + star[j])
    effects = [*sums.values(), *randoms]
    if not effects:
        return np.zeros((survey.size, 3, 3))
    systematic: list[Propagation] = ["systematic"] * len(sums)
    random: list[Propagation] = ["random"] * len(randoms)
    full_all = np.stack([f for f, _ in effects])
    star_all = np.stack([s for _, s in effects])
    cov: FloatArray = propagate_nev(full_all, star_all, systematic + random).sum(axis=0)
    return cov

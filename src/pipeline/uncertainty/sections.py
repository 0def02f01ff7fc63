"""Position covariance of a survey assembled from tied sections (a definitive survey).

A definitive survey is a chain of sections, each one run's stations over a depth interval.
The first section starts from the surface tie; every later section is *tied* to the section
above at its first station (the tie station): that station is placed on the path above at
its MD, and the section's own stations are integrated from it. So the position error of a
station k of section s is

    ε_k = ε_tie(s) + ε_own,k

ε_tie(s) the error of the path above at the tie MD (itself carrying every section above)
and ε_own,k the error of section s's own terms propagated from a fixed tie
(:func:`pipeline.uncertainty.model.station_jacobians` with ``surface_tie=False``: the tie
station's angle errors move the legs below it, its own depth error does not move it — its
MD is placed on the path above, in that path's depths).

Correlation between sections follows the ISCWSA propagation modes (SPE 67616), an error
source being one standard-normal draw per *correlation key*:

    random        one draw per station: independent everywhere
    systematic    one draw per run: correlated within the run, independent between runs
    well_by_well  one draw per well (``well_by_well="shared"``, the ISCWSA rule), or per
                  run (``"per_run"``)
    global        one draw for all: shared by every run

so the covariance of a station is Σ over keys of v vᵀ (v the summed NEV effect of that key,
tie included) plus the random terms' Σ e eᵀ. The error at a tie MD between two stations
i and i + 1 of the section above (fraction f) is interpolated linearly in the errors:
ε(T) = (1 − f)·ε_i + f·ε_{i+1}, exact at a station and first order between them.

Frame NEV (north, east, vertical down), lengths m, angles rad, covariances m².
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.uncertainty.model import Basis
from pipeline.uncertainty.terms import Survey, Term, term_effects

__all__ = ["Carried", "Section", "WellByWell", "section_covariance"]

FloatArray = NDArray[np.float64]
WellByWell = Literal["shared", "per_run"]
Key = tuple[str, ...]


@dataclass(frozen=True)
class Section:
    """One section: the run's stations from its tie station (or the surface) on, the run's
    error terms and the run id that scopes its systematic terms."""

    run: str
    survey: Survey
    terms: Sequence[Term]


@dataclass
class Carried:
    """The position error at a tie: one NEV effect vector (m) per correlation key, and the
    covariance (3, 3) (m²) of the random terms."""

    vectors: dict[Key, FloatArray] = field(default_factory=dict)
    random: FloatArray = field(default_factory=lambda: np.zeros((3, 3)))


def _key(run: str, term: Term, well_by_well: WellByWell) -> Key | None:
    """The correlation key of a term (None: random, one draw per station)."""
    if term.mode == "random":
        return None
    if term.mode == "global" or (term.mode == "well_by_well" and well_by_well == "shared"):
        return (term.mode, term.name)
    return (term.mode, run, term.name)


def section_covariance(
    section: Section,
    carried: Carried,
    *,
    basis: Basis = "balanced_tangent",
    surface_tie: bool = False,
    well_by_well: WellByWell = "shared",
    tie_next: float | None = None,
) -> tuple[FloatArray, Carried | None]:
    """NEV covariance (n, 3, 3) of a section's stations given the error carried to its tie,
    and the error carried to the next section's tie at MD ``tie_next`` (None: no next).

    ``surface_tie`` applies the ISCWSA surface tie-on allowance (the first section only).
    """
    full, star = term_effects(section.survey, section.terms, basis=basis, surface_tie=surface_tie)
    keys = [_key(section.run, t, well_by_well) for t in section.terms]
    # systematic-type effect on each station: s_K = Σ_{k<K} e_k + e*_K
    below = np.cumsum(full, axis=1) - full
    summed = below + star
    vectors: dict[Key, FloatArray] = {
        k: np.broadcast_to(v, summed.shape[1:]) for k, v in carried.vectors.items()
    }
    rand = np.array([k is None for k in keys], dtype=bool)
    for j, key in enumerate(keys):
        if key is not None:
            vectors[key] = vectors.get(key, np.zeros(summed.shape[1:])) + summed[j]
    f_r, s_r = full[rand], star[rand]
    outer = np.einsum("tni,tnj->nij", f_r, f_r)
    random = np.cumsum(outer, axis=0) - outer + np.einsum("tni,tnj->nij", s_r, s_r)
    cov = carried.random + random
    for v in vectors.values():
        cov = cov + v[:, :, None] * v[:, None, :]
    if tie_next is None:
        return cov, None
    i, frac = _locate(section.survey.md, tie_next)
    nxt = min(i + 1, section.survey.size - 1)
    at = {key: (1.0 - frac) * v[i] + frac * v[nxt] for key, v in vectors.items()}
    a = (1.0 - frac) * s_r[:, i] + frac * f_r[:, i]
    b = frac * s_r[:, nxt]
    tie_random = (
        carried.random
        + (np.cumsum(outer, axis=0)[i] - outer[i])
        + np.einsum("ti,tj->ij", a, a)
        + np.einsum("ti,tj->ij", b, b)
    )
    return cov, Carried(at, tie_random)


def _locate(md: FloatArray, at: float) -> tuple[int, float]:
    """Station index i and fraction f of MD ``at`` between stations i and i + 1."""
    if not md[0] <= at <= md[-1]:
        raise ValueError(f"tie MD {at} m is outside the section [{md[0]}, {md[-1]}] m")
    i = int(np.clip(np.searchsorted(md, at, side="right") - 1, 0, md.size - 1))
    if i == md.size - 1:
        return i, 0.0
    return i, float((at - md[i]) / (md[i + 1] - md[i]))

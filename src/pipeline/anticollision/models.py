"""Each well's position covariance from its tool model, by the model's name.

One function, :func:`well_covariance`, gives the NEV covariance (n, 3, 3) of a well's
stations under a named ISCWSA tool model, all terms summed (Williamson, SPE 67616), with the
models' defaults (balanced-tangent Jacobians). The models are those of a
:class:`~pipeline.uncertainty.engine.ModelCatalogue` (the shipped tool-model files and those
the run's plugins registered, handed down by the caller; the shipped ones by default);
names are case-insensitive. A clearance scan needs nothing else of the error models.

Where a survey starts (``start``):

- ``surface``: the well's own root. The ISCWSA surface tie-on: the first station's depth
  error moves it along its tangent and the first course carries the whole of its attitude
  error (the first leg's angle weights doubled).
- ``same_run``: a survey cut at a station of its own run (a parent well below a kick-off):
  depth errors act on the whole MD from the depth datum; the first station's attitude error
  moves the first course, correlated with the run's own terms below.
- ``other_run``: a survey whose first station was surveyed by another run (a sidetrack's
  kick-off station on its parent): depth errors as ``same_run``; the first station's
  attitude error over the first course is added uncorrelated with the run's terms (ISCWSA
  common practice: the tie-on uncertainty simply added, uncorrelated).

The conventions of the ISCWSA clearance set, options here (:class:`Conventions`): the first
station's position is exact (zero covariance there) and a vertical station's azimuth, for
the model's weights and Jacobians, is 0° (true north); the alternatives are the covariance
the start gives at the first station and the azimuth each vertical station lists (an
undefined one: the direction the hole leaves vertical in).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.survey.stations import defined_azimuths
from pipeline.uncertainty.engine import (
    SHIPPED,
    ModelCatalogue,
    OutsideValidity,
    bounded_covariance,
    find_model,
    within_range,
)
from pipeline.uncertainty.model import Propagation, propagate_nev
from pipeline.uncertainty.quantities import ModelSite, Quantities
from pipeline.uncertainty.terms import Survey, term_effects

__all__ = [
    "Conventions",
    "ModelSite",
    "Start",
    "TermEffects",
    "model_survey",
    "needs",
    "resolve_model",
    "term_effects_of",
    "well_covariance",
]

FloatArray = NDArray[np.float64]
Start = Literal["surface", "same_run", "other_run"]
VERTICAL_BELOW = 1e-9
"""Inclination (rad) below which a station is vertical for :attr:`Conventions.vertical_azimuth`."""


@dataclass(frozen=True)
class Conventions:
    """Conventions of the covariance that the ISCWSA clearance set fixes (its defaults)."""

    first_station_exact: bool = True
    """the first station's covariance is zero (the set's: the surface position is exact);
    False: what the survey's start gives there (a 0.35 m along-hole σ from the depth
    reference term of the MWD models)"""
    vertical_azimuth: Literal["north", "given"] = "north"
    """azimuth of a vertical station in the model: ``north`` 0° (the set's and welleng's),
    ``given`` the station's own as listed (an undefined one: the next defined station's, the
    direction the hole leaves vertical in)"""


def resolve_model(name: str, catalogue: ModelCatalogue = SHIPPED) -> str:
    """The canonical spelling of a model name given in any case (ValueError: unknown)."""
    known = list(catalogue.files())
    for model in known:
        if model.casefold() == name.strip().casefold():
            return model
    raise ValueError(f"unknown tool model {name!r}; expected one of {known}")


def needs(model: str, catalogue: ModelCatalogue = SHIPPED) -> frozenset[str]:
    """What a model needs of the site: ``latitude`` and/or ``magnetic``."""
    return find_model(model, catalogue).needs


@dataclass(frozen=True)
class TermEffects:
    """Each term's NEV effects (m, n, 3) on the stations below each station (``full``) and
    on the station itself (``star``), its propagation mode, and the covariance (3, 3) added
    uncorrelated to every station below the first (``other_run``; else zero)."""

    names: list[str]
    modes: list[Propagation]
    full: FloatArray
    star: FloatArray
    tie: FloatArray


def model_survey(
    md: FloatArray, inc: FloatArray, azi_true: FloatArray, tvd: FloatArray, conventions: Conventions
) -> Survey:
    """A survey as the error models take it: azimuths true, a vertical station's by the
    conventions."""
    return Survey.of(md, inc, _azimuths(inc, azi_true, conventions), tvd)


def _azimuths(inc: FloatArray, azi_true: FloatArray, conventions: Conventions) -> FloatArray:
    vertical = np.asarray(inc) < VERTICAL_BELOW
    if conventions.vertical_azimuth == "north":
        return np.where(vertical, 0.0, defined_azimuths(azi_true))
    return defined_azimuths(azi_true)


def term_effects_of(
    model: str,
    survey: Survey,
    site: ModelSite,
    catalogue: ModelCatalogue = SHIPPED,
    start: Start = "surface",
) -> TermEffects:
    """The terms' NEV effects on a survey's stations under tool model ``model``, from
    ``start``; the survey's azimuths true and defined at every station (:func:`well_covariance`
    makes them by its :class:`Conventions`)."""
    tool = find_model(resolve_model(model, catalogue), catalogue)
    within_range(survey, tool, "refuse")
    shared = Quantities(survey, site, tool.parameters, tool.name)
    terms = tool.terms_for(
        lambda s: shared if s is survey else Quantities(s, site, tool.parameters, tool.name)
    )
    surface = start == "surface"
    full, star = term_effects(survey, terms, basis="balanced_tangent", surface_tie=surface)
    tie = np.zeros((3, 3))
    if not surface:
        # the first station's depth error along its tangent (depths from the datum)
        dia = [k for k, t in enumerate(terms) if t.frame == "dia"]
        first = np.array([terms[k].sigma * terms[k].weight(survey)[0] for k in dia])
        si, ci = np.sin(survey.inc[0]), np.cos(survey.inc[0])
        tangent = np.array([si * np.cos(survey.azi[0]), si * np.sin(survey.azi[0]), ci])
        seed = first[:, :1] * tangent
        full[dia, 0] += seed
        star[dia, 0] += seed
        if start == "other_run" and survey.size > 1:
            # the first station's attitude error over the first course: full[:, 0] less the
            # depth parts (the seed and the course's −(t0 + t1)/2 along-hole share)
            t1 = np.array(
                [
                    np.sin(survey.inc[1]) * np.cos(survey.azi[1]),
                    np.sin(survey.inc[1]) * np.sin(survey.azi[1]),
                    np.cos(survey.inc[1]),
                ]
            )
            attitude = full[dia, 0] - seed + first[:, :1] * 0.5 * (tangent + t1)
            full[dia, 0] -= attitude
            tie = np.einsum("ti,tj->ij", attitude, attitude)
    return TermEffects([t.name for t in terms], [t.mode for t in terms], full, star, tie)


def well_covariance(
    model: str,
    md: FloatArray,
    inc: FloatArray,
    azi_true: FloatArray,
    tvd: FloatArray,
    site: ModelSite,
    catalogue: ModelCatalogue = SHIPPED,
    *,
    start: Start = "surface",
    conventions: Conventions = Conventions(),
    outside_validity: OutsideValidity = "refuse",
) -> FloatArray:
    """NEV covariance (n, 3, 3), m², true north, of one survey's stations (MD, TVD m;
    inclination, true azimuth rad, NaN azimuth at vertical) under tool model ``model``,
    from ``start`` (module docstring); a station outside the model's range refused or,
    ``outside_validity="flag"``, NaN from it down
    (:func:`pipeline.uncertainty.engine.term_covariances`)."""
    survey = model_survey(md, inc, azi_true, tvd, conventions)
    tool = find_model(resolve_model(model, catalogue), catalogue)

    def compute(head: Survey) -> FloatArray:
        fx = term_effects_of(model, head, site, catalogue, start)
        cov: FloatArray = propagate_nev(fx.full, fx.star, fx.modes).sum(axis=0)
        cov[1:] += fx.tie
        if conventions.first_station_exact:
            cov[0] = 0.0
        return cov

    inside = within_range(survey, tool, outside_validity)
    return bounded_covariance(survey, inside, compute, tool.name, outside_validity)

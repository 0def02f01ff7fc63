"""Sidetracks and common parent sections: where an offset well shares the reference's hole.

A sidetrack leaves its parent at a kick-off point; above it the two wellbores are one hole,
surveyed once. The common point is named (the kick-off MD on the reference) or detected: the
offset's first station, and those after it, lying on the reference path within a tolerance;
the deepest of them is the common point. Below it each well is scanned as a survey that
starts there (:func:`cut`), its covariance zeroed at the common point (the ISCWSA clearance
set's rule; :mod:`pipeline.anticollision.models`, starts ``same_run`` and ``other_run``).

Frame NEV, metres; MD in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.anticollision.geometry import closest_points
from pipeline.survey.interpolate import MinCurvePath

__all__ = ["Kickoff", "common_point", "cut", "named_kickoff"]

FloatArray = NDArray[np.float64]
_SAME_MD = 1e-9
"""MD difference (m) below which a cut falls on a station."""


@dataclass(frozen=True)
class Kickoff:
    """The deepest common point: its MD on the reference and on the offset (m), its distance
    from the reference path (m) and how it was found (``named`` or ``detected``)."""

    reference_md: float
    offset_md: float
    distance: float
    how: str


def common_point(reference: MinCurvePath, offset: MinCurvePath, tolerance: float) -> Kickoff | None:
    """The deepest of the offset's leading stations that lie within ``tolerance`` (m) of the
    reference path (None: its first station does not)."""
    near = closest_points(reference, offset.r.T)
    gap = np.linalg.norm(near.position - offset.r.T, axis=1)
    off = np.flatnonzero(gap > tolerance)
    if off.size and off[0] == 0:
        return None
    j = int(off[0] - 1) if off.size else offset.md.size - 1
    return Kickoff(float(near.md[j]), float(offset.md[j]), float(gap[j]), "detected")


def named_kickoff(reference: MinCurvePath, offset: MinCurvePath, md: float) -> Kickoff:
    """The kick-off at MD ``md`` on the reference (and, one depth datum, on the offset);
    ValueError where either path does not reach it."""
    for what, path in (("reference", reference), ("offset", offset)):
        if not path.md[0] - _SAME_MD <= md <= path.md[-1]:
            raise ValueError(
                f"kick-off MD {md:g} m is outside the {what}'s stations "
                f"({path.md[0]:g}–{path.md[-1]:g} m)"
            )
    at = np.array([md])
    k_r, f_r = reference.locate(at)
    k_o, f_o = offset.locate(at)
    gap = np.linalg.norm(reference.position(k_r, f_r) - offset.position(k_o, f_o))
    return Kickoff(md, md, float(gap), "named")


def cut(
    path: MinCurvePath, md: float
) -> tuple[FloatArray, FloatArray, FloatArray, tuple[float, float, float]]:
    """A path's survey from MD ``md`` down: a station there (on the path between stations,
    else the station itself) and every station below; MD m, inclination and azimuth rad
    (NaN azimuth kept), and the first station's position (north, east, TVD)."""
    at = path.points(np.array([float(md)]), np.array([0], dtype=np.intp))
    below = path.md > md + _SAME_MD
    return (
        np.concatenate(([float(md)], path.md[below])),
        np.concatenate((at.inc, path.inc[below])),
        np.concatenate((at.azi, path.azi[below])),
        (float(at.north[0]), float(at.east[0]), float(at.tvd[0])),
    )

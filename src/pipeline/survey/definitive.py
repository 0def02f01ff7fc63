"""Which run's stations a definitive survey takes at each depth, and where runs are tied.

Each run covers the MDs from its first to its last station, clipped to its ``md_from`` /
``md_to``. At every depth the covering runs compete by the overlap rule:

    priority  the higher ``priority`` wins; at equal priority the run starting deeper
    upper     the run that started higher keeps the depth (a lower run takes over below it)
    lower     the run that started deeper takes over from its first station

Consecutive depths won by one run are a *section*. A section below the first is tied to the
section above at the last listed station of that section (its *tie MD*): the survey is one
list of stations, the section's first course runs from that station. A station on the
boundary between two sections is listed once, from the section above. Every station not
listed is kept for QC with its role: ``overlap`` (inside another section's depths),
``excluded`` (outside its run's range) or ``left_out`` (beyond the survey's first or last
listed station: a stretch at an end shorter than ``min_length``). MDs in m.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

__all__ = ["OverlapRule", "RunStations", "Section", "SurveyGapError", "plan_sections", "roles"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
OverlapRule = Literal["priority", "upper", "lower"]


class SurveyGapError(ValueError):
    """No run covers an interval between the definitive survey's first and last MD, or a
    run adds no station below the section above it."""


@dataclass(frozen=True)
class RunStations:
    """One run's station MDs (m, increasing), its priority and depth range (m, None: open)."""

    name: str
    md: FloatArray
    priority: int = 0
    md_from: float | None = None
    md_to: float | None = None

    def coverage(self) -> tuple[float, float]:
        lo = float(self.md[0]) if self.md_from is None else max(self.md_from, float(self.md[0]))
        hi = float(self.md[-1]) if self.md_to is None else min(self.md_to, float(self.md[-1]))
        return lo, hi


@dataclass(frozen=True)
class Section:
    """A section: run index and the run's station rows listed in the definitive survey."""

    run: int
    listed: IntArray
    top: float
    """MD where the section starts winning, m"""
    tie_md: float | None
    """MD of the last listed station of the section above (None: the first section)"""

    def tie_above(self, runs: Sequence[RunStations]) -> float:
        """MD of this section's last listed station: the tie of the section below, m."""
        return float(runs[self.run].md[self.listed[-1]])


def _winner(runs: Sequence[RunStations], cands: list[int], rule: OverlapRule) -> int:
    lo = [runs[r].coverage()[0] for r in cands]
    if rule == "upper":
        order = [(-lo[k], float(runs[r].priority), -r) for k, r in enumerate(cands)]
    elif rule == "lower":
        order = [(lo[k], float(runs[r].priority), r) for k, r in enumerate(cands)]
    else:
        order = [(float(runs[r].priority), lo[k], r) for k, r in enumerate(cands)]
    return cands[max(range(len(cands)), key=lambda k: order[k])]


def _segments(runs: Sequence[RunStations], rule: OverlapRule) -> list[tuple[int, float, float]]:
    """(run, top, bottom) of every stretch of depth one run wins, in MD order."""
    cover = [r.coverage() for r in runs]
    for run, (lo, hi) in zip(runs, cover, strict=True):
        if not lo < hi:
            raise SurveyGapError(
                f"run {run.name!r}: fewer than two stations within its depth range "
                f"({run.md_from} – {run.md_to} m; stations {run.md[0]} – {run.md[-1]} m)"
            )
    edges = sorted({x for pair in cover for x in pair})
    segments: list[tuple[int, float, float]] = []
    for top, bottom in itertools.pairwise(edges):
        cands = [i for i, (lo, hi) in enumerate(cover) if lo <= top and hi >= bottom]
        if not cands:
            above = [runs[i].name for i, (_, hi) in enumerate(cover) if hi <= top]
            below = [runs[i].name for i, (lo, _) in enumerate(cover) if lo >= bottom]
            raise SurveyGapError(
                f"no run covers {top:g} – {bottom:g} m MD (runs ending above: "
                f"{', '.join(above)}; starting below: {', '.join(below)}): runs must overlap "
                "or meet — start the run below with its tie-on station (the last station of "
                "the run above)"
            )
        win = _winner(runs, cands, rule)
        if segments and segments[-1][0] == win:
            segments[-1] = (win, segments[-1][1], bottom)
        else:
            segments.append((win, top, bottom))
    return segments


def _absorb_slivers(
    runs: Sequence[RunStations], segments: list[tuple[int, float, float]], min_length: float
) -> list[tuple[int, float, float]]:
    """Segments shorter than ``min_length`` given to a neighbour whose run covers them, or,
    at the top and bottom of the survey, left out (an out-run starting a millimetre above
    the in-run does not make a section of its own)."""
    cover = [r.coverage() for r in runs]
    out = list(segments)
    k = 0
    while len(out) > 1 and k < len(out):
        _, top, bottom = out[k]
        if bottom - top >= min_length:
            k += 1
            continue
        for j in (k - 1, k + 1):
            if 0 <= j < len(out):
                lo, hi = cover[out[j][0]]
                if lo <= top and hi >= bottom:
                    nr, ntop, nbottom = out[j]
                    out[j] = (nr, min(ntop, top), max(nbottom, bottom))
                    del out[k]
                    break
        else:
            k += 1
            continue
        merged: list[tuple[int, float, float]] = []
        for seg in out:
            if merged and merged[-1][0] == seg[0]:
                merged[-1] = (seg[0], merged[-1][1], seg[2])
            else:
                merged.append(seg)
        out, k = merged, 0
    while len(out) > 1 and out[0][2] - out[0][1] < min_length:
        del out[0]  # the survey starts where the run below starts
    while len(out) > 1 and out[-1][2] - out[-1][1] < min_length:
        del out[-1]
    return out


def plan_sections(
    runs: Sequence[RunStations], rule: OverlapRule = "priority", min_length: float = 1.0
) -> list[Section]:
    """The sections of the definitive survey of ``runs`` under ``rule``; a stretch shorter
    than ``min_length`` (m) a run wins goes to a neighbouring section whose run covers it
    (at the survey's ends, where none does, it is left out).

    Raises:
        SurveyGapError: a depth no run covers, or a run adding no station below the one above.
    """
    segments: list[tuple[int, float, float]] = []
    for r, top, bottom in _absorb_slivers(runs, _segments(runs, rule), min_length):
        md = runs[r].md
        if segments and not np.any((md > top) & (md <= bottom)):
            continue  # no station of the run below its top: its neighbours take the stretch
        if segments and segments[-1][0] == r:
            segments[-1] = (r, segments[-1][1], bottom)
        else:
            segments.append((r, top, bottom))
    sections: list[Section] = []
    for r, top, bottom in segments:
        md = runs[r].md
        inside = (md >= top) & (md <= bottom)
        if sections:
            inside &= md > sections[-1].tie_above(runs)  # the boundary: listed from above
        listed = np.flatnonzero(inside)
        if not listed.size:  # its only station is the boundary, listed from above
            raise SurveyGapError(
                f"run {runs[r].name!r} adds no station below {top:g} m MD: widen its range"
            )
        tie_md = sections[-1].tie_above(runs) if sections else None
        sections.append(Section(r, listed, top, tie_md))
    return sections


SAME_DEPTH_M = 0.01
"""Stations this close in MD (m) are at one depth (an in-run's and an out-run's compassed at
one stop): one beyond the survey's end by less overlaps its end station."""


def roles(runs: Sequence[RunStations], sections: Sequence[Section]) -> list[list[str]]:
    """Per run, each station's role: ``listed``, ``overlap``, ``excluded`` or ``left_out``
    (inside its run's range but more than :data:`SAME_DEPTH_M` above the survey's first or
    below its last listed station: a stretch at an end shorter than ``min_length`` that no
    other run covers)."""
    listed = np.concatenate([runs[sec.run].md[sec.listed] for sec in sections])
    top, bottom = listed.min() - SAME_DEPTH_M, listed.max() + SAME_DEPTH_M
    out = []
    for r, run in enumerate(runs):
        lo, hi = run.coverage()
        inside = (run.md >= lo) & (run.md <= hi)
        role = np.where(inside, "overlap", "excluded").astype(object)
        role[inside & ((run.md < top) | (run.md > bottom))] = "left_out"
        for sec in sections:
            if sec.run == r:
                role[sec.listed] = "listed"
        out.append([str(x) for x in role])
    return out

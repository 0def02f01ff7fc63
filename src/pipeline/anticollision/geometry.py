"""Closest approach of points to a well's minimum-curvature path, vectorised over points.

Each step of a minimum-curvature path is a circular arc in the plane of its end tangents
t1, t2 (dogleg β, course L, radius R = L/β). With a = t1, b the unit part of t2 normal to t1
and C = r1 + R·b the arc's centre, the arc is p(θ) = C + R(sin θ·a − cos θ·b), θ ∈ [0, β],
and the squared distance to a point Q is |Q − C|² + R² − 2R·(q_a sin θ − q_b cos θ),
q = Q − C. It is least at θ* = atan2(q_a, −q_b) when θ* lies on the arc, else at the end
with the larger q_a sin θ − q_b cos θ. A near-straight step (β below ``STRAIGHT_BELOW``) is
the segment: the projection of Q on t1 clamped to [0, L]. The point found is then placed on
the arc exactly (:class:`~pipeline.survey.interpolate.MinCurvePath`).

Which steps to try. Each step is cut into pieces no longer than h (h = the median course)
and each piece stands for its mid-point. If a piece holds the closest point q (distance d*),
its mid-point lies within h/2 of q along the path, so within d* + h/2 ≤ d₁ + h/2 of Q, d₁ the
distance to the nearest mid-point (a point of the path, so d* ≤ d₁). Every step owning a
mid-point in that ball is tried, so the minimum over the whole path is found, not only next
to the nearest station.

Frame: NEV (north, east, vertical down), metres; MD in metres.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pipeline.survey.interpolate import MinCurvePath

__all__ = ["STRAIGHT_BELOW", "Closest", "ClosestPoints", "closest_points"]

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]

STRAIGHT_BELOW = 1e-6
"""Dogleg (rad) below which a step is taken as straight for finding the closest point
(its sagitta, L·β/8, is then below a micrometre per 10 m of course)."""


@dataclass(frozen=True)
class Closest:
    """The closest point of a path to each query point."""

    md: FloatArray
    """MD of the closest point (m)"""
    position: FloatArray
    """(m, 3) its NEV position (m)"""
    step: IndexArray
    """index of the step (station k → k + 1) holding it"""
    fraction: FloatArray
    """its fraction of that step's course, in [0, 1]"""


def _pieces(path: MinCurvePath) -> tuple[FloatArray, IndexArray, float]:
    """Mid-points (m, 3) of pieces of the path no longer than h (each step cut into
    ⌈L/h⌉ equal pieces), the step each piece belongs to, and h."""
    h = float(np.median(path.length))
    count = np.maximum(np.ceil(path.length / h - 1e-9).astype(np.intp), 1)
    step = np.repeat(np.arange(path.length.size, dtype=np.intp), count)
    first = np.repeat(np.cumsum(count) - count, count)
    f = (np.arange(step.size) - first + 0.5) / count[step]
    return path.position(step, f).T, step, h


def _on_arc(path: MinCurvePath, q: FloatArray, k: IndexArray) -> FloatArray:
    """Course fraction (in [0, 1]) of the point of step k closest to q (m, 3), per pair."""
    r1 = path.r[:, k].T
    a = path.t1[:, k].T
    t2 = path.t2[:, k].T
    beta = path.beta[k]
    length = path.length[k]
    rel = q - r1
    straight_f = np.clip(np.einsum("ij,ij->i", rel, a) / length, 0.0, 1.0)
    b = t2 - np.einsum("ij,ij->i", t2, a)[:, None] * a
    nb = np.linalg.norm(b, axis=1)
    arc = (beta >= STRAIGHT_BELOW) & (nb > 0.0)
    out: FloatArray = straight_f
    if arc.any():
        a_, rel_, beta_ = a[arc], rel[arc], beta[arc]
        b_ = b[arc] / nb[arc, None]
        radius = length[arc] / beta_
        qc = rel_ - radius[:, None] * b_
        qa = np.einsum("ij,ij->i", qc, a_)
        qb = np.einsum("ij,ij->i", qc, b_)
        theta = np.arctan2(qa, -qb)
        inside = (theta >= 0.0) & (theta <= beta_)
        end = np.where(-qb >= qa * np.sin(beta_) - qb * np.cos(beta_), 0.0, beta_)
        out = out.copy()
        out[arc] = np.where(inside, theta, end) / beta_
    return out


class ClosestPoints:
    """The closest point of one path (at least two stations) to any points: its pieces and
    their k-d tree built once, queried many times."""

    def __init__(self, path: MinCurvePath):
        from scipy.spatial import cKDTree

        self.path = path
        mids, self.step, self.h = _pieces(path)
        self.tree = cKDTree(mids)

    def __call__(self, points: FloatArray) -> Closest:
        """The point of the path closest to each of ``points`` (m, 3)."""
        path, step, h, tree = self.path, self.step, self.h, self.tree
        q = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        nearest, _ = tree.query(q)
        balls = tree.query_ball_point(q, nearest + 0.5 * h + 1e-9 * (1.0 + nearest))
        counts = np.fromiter(map(len, balls), dtype=np.intp, count=q.shape[0])
        found = np.fromiter(itertools.chain.from_iterable(balls), dtype=np.intp, count=counts.sum())
        pair_q = np.repeat(np.arange(q.shape[0], dtype=np.intp), counts)
        pair_k = step[found]
        f = _on_arc(path, q[pair_q], pair_k)
        where = path.position(pair_k, f).T
        dist = np.linalg.norm(where - q[pair_q], axis=1)
        starts = np.cumsum(counts) - counts  # every point has a candidate: its nearest piece
        least = np.repeat(np.minimum.reduceat(dist, starts), counts)
        hits = np.flatnonzero(dist == least)
        best = hits[np.searchsorted(pair_q[hits], np.arange(q.shape[0]))]
        k, fb = pair_k[best], f[best]
        md = path.md[k] + fb * path.length[k]
        return Closest(md=md, position=where[best], step=k, fraction=fb)


def closest_points(path: MinCurvePath, points: FloatArray) -> Closest:
    """The point of ``path`` (at least two stations) closest to each of ``points`` (m, 3)."""
    return ClosestPoints(path)(points)

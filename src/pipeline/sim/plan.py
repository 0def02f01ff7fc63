"""Well plans: a smooth well path evaluated, with its derivatives, at any measured depth.

Frame NED: north, east, TVD (down positive), in metres. Inclination I from vertical, azimuth A
clockwise from north, so the unit tangent is t = (sin I cos A, sin I sin A, cos I). Plans and
stations are given in degrees (DLS in deg/30m); :class:`PathState` is in radians and metres.

The path is a chain of circular arcs, each joining unit tangents t0 → t1 over a length L with
dogleg β = 2·asin(|t1 − t0|/2): exactly the arc minimum curvature assumes between two stations,
so positions at arc ends equal :func:`pipeline.survey.mincurve.minimum_curvature`. With the
curvature κ = β/L, the unit bend direction n ⊥ t0 in the plane of the arc, s = MD − MD0 and
θ = κs, the arc is

    t(s)  = cos θ · t0 + sin θ · n
    r(s)  = r0 + s · [sinc θ · t0 + sin(θ/2) sinc(θ/2) · n]        (sinc x = sin x / x)
    dt/ds = κ(−sin θ · t0 + cos θ · n),    d²t/ds² = −κ² t

which is the slerp of t0 → t1 written without any small-β cancellation; arcs with β below
``STRAIGHT_BELOW`` are straight (κ = 0, n = 0).

Tie-in: the path's first point (``start_md``) is at NED (``start_north``, ``start_east``,
``start_tvd``), by default (0, 0, start_md), i.e. a straight vertical hole above the start,
the same default as the ``minimum_curvature`` stage's ``tie_tvd``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Self

import numpy as np
import pyarrow as pa
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from pipeline.earth.frames import tool_axis
from pipeline.survey.mincurve import REVERSAL_MARGIN, minimum_curvature
from pipeline.tables import DLS_COURSE_M, DLS_UNIT, Stations

__all__ = ["PathState", "Section", "StationProblem", "WellPath", "WellPlan", "build_path"]

FloatArray = NDArray[np.float64]

#: Arcs whose dogleg (rad) is below this are straight. The arc formulas have no cancellation,
#: so the threshold only guards the bend direction's 0/0; the position error it allows is
#: below L·β/2, i.e. 5e-11 m on a 100 m arc.
STRAIGHT_BELOW = 1e-12
#: Where sin I is below this the tangent counts as vertical: the azimuth falls back to the
#: direction the tangent is moving toward (or the arc's nominal azimuth) and dazi is 0.
VERTICAL_BELOW = 1e-9
#: Slack (m) when comparing a section's arc length with its given length.
LENGTH_TOL = 1e-9
#: Course length (m) of a dogleg severity in DLS_UNIT.

_TWO_PI = 2.0 * np.pi


class StationProblem(ValueError):
    """A station the well path cannot be built through; ``station`` is its 0-based index."""

    def __init__(self, station: int, message: str) -> None:
        super().__init__(message)
        self.station = station


MIN_DLS = 1e-3
"""Smallest dogleg severity of a plan's arc, deg/30m: a radius of curvature of 1,700 km (a
45° build would be 1,350 km long); a smaller one is a hold. 5e-324 made the arc infinite."""


class Section(BaseModel):
    """One plan section. Lengths in m, angles in deg, dogleg severity in deg/30m.

    ``vertical`` (only from inclination 0) and ``hold`` run straight and need ``length`` or
    ``to_md``. ``build``, ``drop``, ``turn`` and ``curve`` turn at ``dls`` to the target
    (``inc``, ``azi``) (each defaults to the current value) along the great-circle arc, the
    short way round; with ``length`` or ``to_md`` the arc is followed by a hold to the end of
    the section, which must leave room for the arc. A build may not lower the inclination, a
    drop may not raise it, and a turn changes only the azimuth of an inclined hole.
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    kind: Literal["vertical", "hold", "build", "drop", "turn", "curve"]
    length: float | None = Field(None, gt=0, description="section length along MD, m")
    to_md: float | None = Field(None, description="MD at the end of the section, m")
    dls: float | None = Field(
        None,
        ge=MIN_DLS,
        description=f"dogleg severity of the arc, {DLS_UNIT} (at least {MIN_DLS:g})",
    )
    inc: float | None = Field(None, ge=0, le=180, description="target inclination, deg")
    azi: float | None = Field(None, description="target azimuth, deg clockwise from north")


class WellPlan(BaseModel):
    """A well plan: the attitude at ``start_md`` and the sections that follow (m, deg).

    The start point is at NED (``start_north``, ``start_east``, ``start_tvd``); ``start_tvd``
    defaults to ``start_md`` (a straight vertical hole above the start). On a vertical hole
    ``start_azi`` is the nominal azimuth reported until the path leaves vertical. Sections are
    checked against the attitude they start from when the plan is validated.
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    start_md: float = Field(0.0, ge=0, description="MD of the first point, m")
    start_inc: float = Field(0.0, ge=0, le=180, description="inclination at start_md, deg")
    start_azi: float = Field(0.0, description="azimuth at start_md, deg clockwise from north")
    start_north: float = Field(0.0, description="northing of the first point, m")
    start_east: float = Field(0.0, description="easting of the first point, m")
    start_tvd: float | None = Field(
        None, description="TVD of the first point, m; default: start_md"
    )
    sections: list[Section] = Field(min_length=1, description="sections in MD order")

    @model_validator(mode="after")
    def _sections_fit(self) -> Self:
        _stations(self)
        return self


@dataclass(frozen=True)
class PathState:
    """The path at the requested MDs, one row each. NED frame; metres and radians.

    ``azi`` is in [0, 2π). Where the tangent is vertical (sin I < ``VERTICAL_BELOW``) it is the
    azimuth the tangent is moving toward (the right-hand limit along MD), or on a straight
    vertical arc the arc's nominal azimuth; there ``dazi`` is 0 and only ``sin_inc_dazi``
    (which tends to 0) is meaningful.
    """

    position: FloatArray  #: (n, 3) m, north, east, TVD
    tangent: FloatArray  #: (n, 3) unit tangent dr/ds
    dtangent: FloatArray  #: (n, 3) 1/m, dt/ds
    d2tangent: FloatArray  #: (n, 3) 1/m², d²t/ds²
    inc: FloatArray  #: (n,) rad
    azi: FloatArray  #: (n,) rad in [0, 2π)
    dinc: FloatArray  #: (n,) rad/m, dI/ds
    sin_inc_dazi: FloatArray  #: (n,) rad/m, sin I · dA/ds
    dazi: FloatArray  #: (n,) rad/m, dA/ds (0 where the tangent is vertical)


@dataclass(frozen=True)
class WellPath:
    """A chain of circular arcs in NED (m), one row per arc; arc i runs from ``md0[i]`` to
    ``md1[i]`` and ``md0[i + 1] == md1[i]``. Build it with :func:`build_path` or
    :meth:`from_stations`.
    """

    md0: FloatArray  #: (n,) m, MD at the start of each arc
    md1: FloatArray  #: (n,) m, MD at the end of each arc
    t0: FloatArray  #: (n, 3) unit tangent at the start
    t1: FloatArray  #: (n, 3) unit tangent at the end
    beta: FloatArray  #: (n,) rad, dogleg
    r0: FloatArray  #: (n, 3) m, position at the start
    vertical_azi: FloatArray  #: (n,) rad, azimuth reported on a straight vertical arc

    @classmethod
    def from_stations(
        cls,
        md: ArrayLike,
        inc: ArrayLike,
        azi: ArrayLike,
        *,
        start_north: float = 0.0,
        start_east: float = 0.0,
        start_tvd: float | None = None,
    ) -> WellPath:
        """Join consecutive stations (MD m, inclination and azimuth deg) by minimum-curvature
        arcs. The first station is at NED (``start_north``, ``start_east``, ``start_tvd``);
        ``start_tvd`` defaults to the first MD.

        Raises:
            ValueError: fewer than two stations, unequal shapes, non-finite values, MD not
                strictly increasing, inclination outside [0, 180] deg, or a reversal.
        """
        md_a, inc_d, azi_d = (np.asarray(x, dtype=np.float64) for x in (md, inc, azi))
        if md_a.ndim != 1 or md_a.size < 2 or not md_a.shape == inc_d.shape == azi_d.shape:
            raise ValueError(
                "md, inc and azi must be 1-D arrays of equal length >= 2; got shapes "
                f"{md_a.shape}, {inc_d.shape}, {azi_d.shape}"
            )
        for name, values in (("md", md_a), ("inc", inc_d), ("azi", azi_d)):
            if not np.isfinite(values).all():
                k = _first(~np.isfinite(values))
                raise StationProblem(k, f"{name}: station {k} is not finite")
        if (np.diff(md_a) <= 0).any():
            k = _first(np.diff(md_a) <= 0) + 1
            raise StationProblem(k, f"md: must increase strictly; station {k} is at {md_a[k]} m")
        if ((inc_d < 0) | (inc_d > 180)).any():
            k = _first((inc_d < 0) | (inc_d > 180))
            raise StationProblem(k, f"inc: station {k} is {inc_d[k]} deg, outside [0, 180]")
        inc_r, azi_r = np.radians(inc_d), np.radians(azi_d)
        t = tool_axis(azi_r, inc_r)
        beta = _dogleg(t[:-1], t[1:])
        if (beta > np.pi - REVERSAL_MARGIN).any():
            k = _first(beta > np.pi - REVERSAL_MARGIN) + 1
            raise StationProblem(
                k,
                f"station {k} turns {np.degrees(beta[k - 1]):.3f} deg from the previous "
                "station: a reversal has no unique circular arc",
            )
        track = minimum_curvature(
            md_a,
            inc_r,
            azi_r,
            tie_north=start_north,
            tie_east=start_east,
            tie_tvd=md_a[0] if start_tvd is None else start_tvd,
        )
        r = np.stack([track.north, track.east, track.tvd], axis=-1)
        return cls(
            md0=md_a[:-1],
            md1=md_a[1:],
            t0=t[:-1],
            t1=t[1:],
            beta=beta,
            r0=r[:-1],
            vertical_azi=_wrap(azi_r[:-1]),
        )

    @property
    def start_md(self) -> float:
        """MD of the first point, m."""
        return float(self.md0[0])

    @property
    def end_md(self) -> float:
        """MD of the last point, m."""
        return float(self.md1[-1])

    def evaluate(self, md: ArrayLike) -> PathState:
        """The path at each MD (m, scalar or 1-D, within [start_md, end_md]), vectorised.

        An MD on the joint of two arcs is evaluated on the arc that starts there.
        """
        s_md = np.atleast_1d(np.asarray(md, dtype=np.float64))
        if s_md.ndim != 1:
            raise ValueError(f"md must be a scalar or 1-D; got shape {s_md.shape}")
        outside = ~((s_md >= self.start_md) & (s_md <= self.end_md))
        if outside.any():
            raise ValueError(
                f"md {s_md[_first(outside)]} m is outside the path "
                f"[{self.start_md}, {self.end_md}] m"
            )
        kappa, bend = self._curvature()
        arc = np.searchsorted(self.md0, s_md, side="right") - 1
        k = kappa[arc]
        s = s_md - self.md0[arc]
        theta = k * s
        cos, sin = np.cos(theta), np.sin(theta)
        curved = k > 0.0
        along_t = np.divide(sin, k, out=s.copy(), where=curved)  # s·sin θ/θ
        along_n = np.sin(0.5 * theta)
        along_n *= along_n
        along_n *= 2.0
        np.divide(along_n, k, out=along_n, where=curved)  # s·(1 − cos θ)/θ, 0 if straight
        t, dt, r = [], [], []
        for j in range(3):  # north, east, down: contiguous 1-D columns are fastest
            t0, n = self.t0[:, j][arc], bend[:, j][arc]
            t.append(cos * t0 + sin * n)
            dt.append(k * (cos * n - sin * t0))
            r.append(self.r0[:, j][arc] + along_t * t0 + along_n * n)
        return _state(r, t, dt, k, self.vertical_azi[arc])

    def stations(self, md: ArrayLike) -> pa.Table:
        """A :class:`pipeline.tables.Stations` table (md m, inc and azi deg, true north) of
        the path at the given MDs."""
        state = self.evaluate(md)
        return Stations.compiled().make_table(
            {
                "md": np.atleast_1d(np.asarray(md, dtype=np.float64)),
                "inc": np.degrees(state.inc),
                "azi": np.degrees(state.azi),
            },
            north_reference="true",
        )

    def _curvature(self) -> tuple[FloatArray, FloatArray]:
        """Curvature κ (n,) in 1/m and unit bend direction n (n, 3) of each arc (0 if straight)."""
        curved = self.beta >= STRAIGHT_BELOW
        chord = self.t1 - self.t0
        bend = chord - np.sum(chord * self.t0, axis=1, keepdims=True) * self.t0
        # again: near a reversal the first pass leaves a part along t0 of ~1e-16/sin β
        bend -= np.sum(bend * self.t0, axis=1, keepdims=True) * self.t0
        norm = np.linalg.norm(bend, axis=1, keepdims=True)
        bend = np.divide(bend, norm, out=np.zeros_like(bend), where=curved[:, None])
        kappa = np.divide(
            self.beta, self.md1 - self.md0, out=np.zeros_like(self.beta), where=curved
        )
        return kappa, bend


def build_path(plan: WellPlan) -> WellPath:
    """The well path of a plan: its section ends joined by minimum-curvature arcs."""
    md, inc, azi = _stations(plan)
    return WellPath.from_stations(
        md,
        inc,
        azi,
        start_north=plan.start_north,
        start_east=plan.start_east,
        start_tvd=plan.start_tvd,
    )


def _stations(plan: WellPlan) -> tuple[list[float], list[float], list[float]]:
    """MD (m), inclination and azimuth (deg) of every arc end of the plan, start included.

    Raises ValueError naming the section (index and kind) and field of the first problem.
    """
    md, inc, azi = [plan.start_md], [plan.start_inc], [plan.start_azi]
    for i, sec in enumerate(plan.sections):
        where = f"sections[{i}] ({sec.kind})"
        here = md[-1]
        end = _section_end(where, sec, here)
        if sec.kind in ("vertical", "hold"):
            _check_straight(where, sec, end, inc[-1])
            tgt_inc, tgt_azi, beta, arc = inc[-1], azi[-1], 0.0, 0.0
        else:
            tgt_inc = inc[-1] if sec.inc is None else sec.inc
            tgt_azi = azi[-1] if sec.azi is None else sec.azi
            beta, arc = _arc(where, sec, (inc[-1], azi[-1]), (tgt_inc, tgt_azi))
        if end is None:
            ends = [here + arc]
        elif here + arc > end + LENGTH_TOL:
            given = f"length is {sec.length}" if sec.to_md is None else f"to_md leaves {end - here}"
            raise ValueError(
                f"{where}: needs {np.degrees(beta):.1f} deg of dogleg at dls {sec.dls} "
                f"{DLS_UNIT} = {arc:.1f} m, but {given} m"
            )
        else:  # the arc (stretched to the end if within LENGTH_TOL of it), then a hold
            ends = [here + arc, end] if end - (here + arc) > LENGTH_TOL else [end]
        for stop in ends:
            if stop > md[-1]:
                md.append(stop)
                inc.append(tgt_inc)
                azi.append(tgt_azi)
    return md, inc, azi


def _section_end(where: str, sec: Section, here: float) -> float | None:
    """MD (m) at the end of a section that gives length or to_md, else None."""
    if sec.length is not None and sec.to_md is not None:
        raise ValueError(f"{where}: length/to_md: give one, not both")
    if sec.to_md is not None:
        if sec.to_md <= here:
            raise ValueError(f"{where}: to_md: {sec.to_md} m is not beyond the current MD {here} m")
        return sec.to_md
    return None if sec.length is None else here + sec.length


def _check_straight(where: str, sec: Section, end: float | None, cur_inc: float) -> None:
    for name in ("dls", "inc", "azi"):
        if getattr(sec, name) is not None:
            raise ValueError(
                f"{where}: {name}: not allowed, the section keeps the current attitude"
            )
    if end is None:
        raise ValueError(f"{where}: length/to_md: one of them is required")
    if sec.kind == "vertical" and cur_inc != 0.0:
        raise ValueError(
            f"{where}: kind: the current inclination is {cur_inc} deg, not 0; use hold or drop"
        )


def _arc(
    where: str, sec: Section, current: tuple[float, float], target: tuple[float, float]
) -> tuple[float, float]:
    """Dogleg (rad) and length (m) of the arc from the current to the target (inc, azi) (deg)
    at the section's DLS; (0, 0) if the target is the current attitude (then the section
    needs length or to_md)."""
    (cur_inc, cur_azi), (tgt_inc, tgt_azi) = current, target
    if sec.dls is None:
        raise ValueError(f"{where}: dls: required for a {sec.kind} section ({DLS_UNIT})")
    if sec.kind == "build" and tgt_inc < cur_inc:
        raise ValueError(
            f"{where}: inc: target {tgt_inc} deg is below the current {cur_inc} deg; "
            "a build must not decrease inclination (use drop or curve)"
        )
    if sec.kind == "drop" and tgt_inc > cur_inc:
        raise ValueError(
            f"{where}: inc: target {tgt_inc} deg is above the current {cur_inc} deg; "
            "a drop must not increase inclination (use build or curve)"
        )
    if sec.kind == "turn":
        if tgt_inc != cur_inc:
            raise ValueError(
                f"{where}: inc: a turn keeps the inclination ({cur_inc} deg), got {tgt_inc} deg; "
                "use curve"
            )
        if cur_inc in (0.0, 180.0):
            raise ValueError(f"{where}: inc: a turn needs an inclined hole, not {cur_inc} deg")
        if (tgt_azi - cur_azi) % 360.0 == 0.0:
            raise ValueError(f"{where}: azi: a turn must change the azimuth ({cur_azi} deg)")
    beta = _turn(cur_inc, cur_azi, tgt_inc, tgt_azi)
    if beta > np.pi - REVERSAL_MARGIN:
        raise ValueError(
            f"{where}: inc/azi: the target ({tgt_inc}, {tgt_azi}) deg reverses the hole "
            f"(dogleg {np.degrees(beta):.3f} deg); a 180 deg reversal has no unique arc, "
            "split it into two sections"
        )
    if beta >= STRAIGHT_BELOW:
        return beta, beta / np.radians(sec.dls) * DLS_COURSE_M
    if sec.length is None and sec.to_md is None:
        raise ValueError(
            f"{where}: inc/azi: the target ({tgt_inc}, {tgt_azi}) deg is the current attitude, "
            "so the section has zero length; change the target or give length/to_md"
        )
    return 0.0, 0.0


def _turn(inc0: float, azi0: float, inc1: float, azi1: float) -> float:
    """Dogleg (rad) between two attitudes given in deg."""
    t = tool_axis(np.radians([azi0, azi1]), np.radians([inc0, inc1]))
    return float(_dogleg(t[0], t[1]))


def _state(
    r: list[FloatArray],
    t: list[FloatArray],
    dt: list[FloatArray],
    kappa: FloatArray,
    vertical_azi: FloatArray,
) -> PathState:
    """The path state from the (north, east, down) columns of position, tangent and dt/ds,
    the curvature and the nominal azimuth of vertical straight arcs (rad) at each sample."""
    (tx, ty, tz), (dtx, dty, dtz) = t, dt
    sin_inc = np.hypot(tx, ty)
    level = sin_inc >= VERTICAL_BELOW
    inv_sin = np.divide(1.0, sin_inc, out=np.zeros_like(sin_inc), where=level)
    azi = np.arctan2(ty, tx)
    # dt/ds across (sin I·dA/ds) and along (cos I·dI/ds + ...) the horizontal direction e
    across = (tx * dty - ty * dtx) * inv_sin
    along = (tx * dtx + ty * dty) * inv_sin
    vertical = np.flatnonzero(~level)
    if vertical.size:  # e is the direction the tangent moves toward, or the nominal azimuth
        vx, vy = dtx[vertical], dty[vertical]
        azi[vertical] = np.where(np.hypot(vx, vy) > 0.0, np.arctan2(vy, vx), vertical_azi[vertical])
        ex, ey = np.cos(azi[vertical]), np.sin(azi[vertical])
        across[vertical] = ex * vy - ey * vx
        along[vertical] = ex * vx + ey * vy
    np.add(azi, _TWO_PI, out=azi, where=azi < 0.0)
    azi[azi >= _TWO_PI] = 0.0  # a tiny negative angle + 2π rounds to 2π
    tangent = np.stack(t, axis=1)
    return PathState(
        position=np.stack(r, axis=1),
        tangent=tangent,
        dtangent=np.stack(dt, axis=1),
        d2tangent=-(kappa * kappa)[:, None] * tangent,
        inc=np.arctan2(sin_inc, tz),
        azi=azi,
        dinc=tz * along - sin_inc * dtz,
        sin_inc_dazi=across,
        dazi=across * inv_sin,
    )


def _dogleg(t0: FloatArray, t1: FloatArray) -> FloatArray:
    """Angle (rad) between unit vectors along the last axis, 2·asin(|t1 − t0|/2)."""
    chord = np.linalg.norm(t1 - t0, axis=-1)
    beta: FloatArray = 2.0 * np.arcsin(np.minimum(0.5 * chord, 1.0))
    return beta


def _wrap(angle: FloatArray) -> FloatArray:
    """Angles (rad) in [0, 2π)."""
    wrapped = np.mod(angle, _TWO_PI)
    return np.where(wrapped < _TWO_PI, wrapped, 0.0)


def _first(mask: NDArray[np.bool_]) -> int:
    return int(np.argmax(mask))

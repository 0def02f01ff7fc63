"""Survey timelines: what the tool does when — stops, frame moves, travel — as a table of
segments, evaluated vectorised at every sample time.

Each segment moves MD from ``md_a`` to ``md_b`` and the frame angle (frame relative to the
housing) from ``th_a`` to ``th_b`` along a normalised profile s(u), u = (t − t0)/T ∈ [0, 1]:
``hold`` (s = 0), ``smooth`` (rest to rest, s = u − sin 2πu / 2π), ``linear`` (s = u),
``accel`` (rest to constant speed, s = u − sin πu / π) and ``decel`` (the reverse,
s = u + sin πu / π). MD in metres, angles in radians, time in seconds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from pipeline.earth.frames import FloatArray
from pipeline.sim.spec import ContinuousSurvey, PointSurvey, StopScheme

IntArray = np.ndarray


class Profile(IntEnum):
    HOLD = 0
    SMOOTH = 1
    LINEAR = 2
    ACCEL = 3
    DECEL = 4


@dataclass
class Timeline:
    """Segments in time order, starting at rest at MD ``md`` with frame angle ``theta``
    (the cursors, which then follow the end of the last segment). ``station``/``position``
    are −1 where not applicable; ``stabilised`` marks travel where the frame servo adds to
    the profile's angle."""

    md: float
    theta: float
    t0: list[float] = field(default_factory=list)
    duration: list[float] = field(default_factory=list)
    md_a: list[float] = field(default_factory=list)
    md_b: list[float] = field(default_factory=list)
    md_profile: list[int] = field(default_factory=list)
    th_a: list[float] = field(default_factory=list)
    th_b: list[float] = field(default_factory=list)
    th_profile: list[int] = field(default_factory=list)
    station: list[int] = field(default_factory=list)
    position: list[int] = field(default_factory=list)
    stabilised: list[bool] = field(default_factory=list)

    @property
    def end(self) -> float:
        """Time at the end of the last segment, s."""
        return self.t0[-1] + self.duration[-1] if self.t0 else 0.0

    def add(
        self,
        duration: float,
        *,
        md: tuple[float, Profile] | None = None,
        theta: tuple[float, Profile] | None = None,
        station: int = -1,
        position: int = -1,
        stabilised: bool = False,
    ) -> None:
        """Append a segment taking MD and frame angle from the cursors to the given
        targets along the given profiles (both held when not given)."""
        md_b, md_prof = md if md else (self.md, Profile.HOLD)
        th_b, th_prof = theta if theta else (self.theta, Profile.HOLD)
        self.t0.append(self.end)
        self.duration.append(duration)
        self.md_a.append(self.md)
        self.md_b.append(md_b)
        self.md_profile.append(md_prof)
        self.th_a.append(self.theta)
        self.th_b.append(th_b)
        self.th_profile.append(th_prof)
        self.station.append(station)
        self.position.append(position)
        self.stabilised.append(stabilised)
        self.md, self.theta = md_b, th_b

    def add_stop(self, scheme: StopScheme, station: int, turn_first: bool = False) -> None:
        """A compassing stop: settle, then dwell at each frame position (frame angles
        relative to the housing), turning the frame the short way to each. ``turn_first``:
        the move to the first position is made even where the frame is there already (one of
        no angle), so that the stop's timing does not depend on the angle it starts from."""
        self.add(scheme.settle_time, station=station)
        for j, angle in enumerate(np.radians(scheme.positions)):
            target = nearest_equivalent(angle, self.theta)
            if abs(target - self.theta) > 1e-12 or (turn_first and j == 0):
                self.add(scheme.move_time, theta=(target, Profile.SMOOTH), station=station)
            self.add(scheme.dwell, station=station, position=j)

    def at(self, t: FloatArray) -> Sampled:
        """Evaluate MD, frame angle and their time derivatives at sample times ``t``."""
        t0 = np.asarray(self.t0)
        seg = np.clip(np.searchsorted(t0, t, side="right") - 1, 0, len(t0) - 1)
        dur = np.asarray(self.duration)[seg]
        u = np.clip((t - t0[seg]) / dur, 0.0, 1.0)
        md, md_d, md_dd = _along(
            u,
            dur,
            np.asarray(self.md_a)[seg],
            np.asarray(self.md_b)[seg],
            np.asarray(self.md_profile)[seg],
        )
        th, th_d, _ = _along(
            u,
            dur,
            np.asarray(self.th_a)[seg],
            np.asarray(self.th_b)[seg],
            np.asarray(self.th_profile)[seg],
        )
        return Sampled(
            time=t,
            segment=seg,
            md=md,
            md_rate=md_d,
            md_accel=md_dd,
            theta=th,
            theta_rate=th_d,
            station=np.asarray(self.station)[seg],
            position=np.asarray(self.position)[seg],
            stabilised=np.asarray(self.stabilised)[seg],
        )


@dataclass(frozen=True)
class Sampled:
    """A timeline evaluated at sample times (MD m, m/s, m/s²; frame angle rad, rad/s)."""

    time: FloatArray
    segment: IntArray
    md: FloatArray
    md_rate: FloatArray
    md_accel: FloatArray
    theta: FloatArray
    theta_rate: FloatArray
    station: IntArray
    position: IntArray
    stabilised: IntArray


def _along(
    u: FloatArray, dur: FloatArray, a: FloatArray, b: FloatArray, profile: IntArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Value, first and second time derivative along each sample's segment profile."""
    s, ds, dds = np.zeros_like(u), np.zeros_like(u), np.zeros_like(u)
    for code in (Profile.SMOOTH, Profile.LINEAR, Profile.ACCEL, Profile.DECEL):
        m = profile == code
        if m.any():
            s[m], ds[m], dds[m] = _profile(code, u[m])
    delta = b - a
    return a + delta * s, delta * ds / dur, delta * dds / dur**2


def _profile(code: Profile, u: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """s(u), s'(u), s''(u) of a normalised profile (see the module docstring)."""
    if code == Profile.SMOOTH:
        w = 2 * np.pi * u
        return u - np.sin(w) / (2 * np.pi), 1 - np.cos(w), 2 * np.pi * np.sin(w)
    if code == Profile.LINEAR:
        return u, np.ones_like(u), np.zeros_like(u)
    sign = 1.0 if code == Profile.DECEL else -1.0
    p = np.pi * u
    return u + sign * np.sin(p) / np.pi, 1 + sign * np.cos(p), -sign * np.pi * np.sin(p)


def nearest_equivalent(angle: float, reference: float) -> float:
    """``angle`` + 2πk closest to ``reference`` (rad): frames turn the short way."""
    return float(reference + (angle - reference + np.pi) % (2 * np.pi) - np.pi)


def point_timeline(survey: PointSurvey, station_mds: FloatArray) -> Timeline:
    """Stops at each station; smooth travel between them at the mean speed."""
    timeline = Timeline(md=float(station_mds[0]), theta=float(np.radians(survey.positions[0])))
    for k, md in enumerate(station_mds):
        if k:
            timeline.add((md - timeline.md) / survey.speed, md=(float(md), Profile.SMOOTH))
        timeline.add_stop(survey, station=k)
    return timeline


def continuous_timeline(
    survey: ContinuousSurvey, start_md: float, end_md: float, align: float = 0.0
) -> Timeline:
    """Compassing stop, frame turned to ``align`` (rad), accelerate, log at constant
    speed, brake, compassing stop. While moving (``stabilised``) the servo's correction is
    added to the frame angle by the caller. With the servo on, the closing stop always turns
    the frame to its first position: the caller samples a timeline built with a provisional
    ``align`` and then the one built with the servo's, and both must end at the same time
    (a closing stop that skipped the move in one lost ``move_time`` of its last position)."""
    ramp_len = survey.speed * survey.ramp_time / 2
    cruise = end_md - start_md - 2 * ramp_len
    if cruise < 0:
        raise ValueError(
            f"survey: {end_md - start_md:.1f} m is too short to accelerate to "
            f"{survey.speed} m/s and stop again ({2 * ramp_len:.1f} m needed)"
        )
    timeline = Timeline(md=start_md, theta=float(np.radians(survey.stop.positions[0])))
    timeline.add_stop(survey.stop, station=0)
    target = nearest_equivalent(align, timeline.theta)
    timeline.add(survey.stop.move_time, theta=(target, Profile.SMOOTH), station=0)
    timeline.add(survey.ramp_time, md=(start_md + ramp_len, Profile.ACCEL), stabilised=True)
    timeline.add(cruise / survey.speed, md=(end_md - ramp_len, Profile.LINEAR), stabilised=True)
    timeline.add(survey.ramp_time, md=(end_md, Profile.DECEL), stabilised=True)
    timeline.add_stop(survey.stop, station=1, turn_first=survey.stabilisation.enabled)
    return timeline

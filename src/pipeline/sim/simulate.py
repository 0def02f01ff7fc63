"""The survey simulator: from a plan (site, well, tool, survey) to raw sensor samples and
the truth they were made from.

Physics in the canonical frames (DOMAIN.md §2). The navigation frame is the wellhead's
local-level NED frame, treated as Earth-fixed: over a well's few kilometres the change of
latitude and the transport rate (< 0.04 °/h at 1 m/s) are neglected, and gravity is the
wellhead's normal gravity. Sensors sit on the frame (body axes b); the housing rolls with
cable torsion while moving; the frame turns relative to the housing by the frame angle θ.

- Attitude ``C_b^n = Rz(A)·Ry(I)·Rz(ψ)``, ψ = Φ − A + θ where Φ is the housing's
  north-referenced roll (well defined through vertical) and θ the frame angle.
- Gyros: ``ω_ib^b = C_n^b ω_ie^n + ω_nb^b`` with
  ``ω_nb^b = Rz(ψ)ᵀ (−sin I·Ȧ, İ, 0) + (0, 0, ω_h + θ̇)``, ω_h the housing spin rate.
- Accelerometers (gravity sign convention): ``C_n^b ((0, 0, g) − a^n)``, a^n the tool's
  acceleration along the path.
- Magnetometers: ``C_n^b B^n`` from the site's geomagnetic reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from pipeline.earth.frames import FloatArray, body_to_ned, to_body
from pipeline.sim.plan import VERTICAL_BELOW, WellPath
from pipeline.sim.sensors import ToolSensors, gauss_markov, measure, odometer_md
from pipeline.sim.spec import ContinuousSurvey, PointSurvey, SimulationSpec, Torsion
from pipeline.sim.timeline import Sampled, Timeline, continuous_timeline, point_timeline
from pipeline.tables import RawSamples, SimTruth

RAD_S_TO_DEG_H = np.degrees(1.0) * 3600.0


@dataclass(frozen=True)
class Kinematics:
    """True motion at every sample: time s, MD m, angles rad, rates rad/s, NED position
    m; body-frame ideal signals: rate rad/s, gravity-convention acceleration m/s², field nT."""

    sampled: Sampled
    inc: FloatArray
    azi: FloatArray
    toolface: FloatArray
    housing_toolface: FloatArray
    theta: FloatArray
    position: FloatArray
    c_bn: FloatArray
    rate_body: FloatArray
    accel_body: FloatArray
    field_body: FloatArray | None


@dataclass(frozen=True)
class Simulation:
    """Simulator output: raw samples, per-sample truth and the true stations."""

    samples: pa.Table
    truth: pa.Table
    stations: pa.Table


def simulate(spec: SimulationSpec) -> Simulation:
    """Run a point or continuous simulation (free-gyro surveys: :mod:`pipeline.sim.freegyro`)."""
    survey = spec.survey
    if not isinstance(survey, PointSurvey | ContinuousSurvey):
        raise TypeError("simulate() runs point and continuous surveys; use simulate_free_gyro")
    rng = np.random.default_rng(spec.seed)
    path = spec.path()
    tool = spec.tool.model()
    kin = kinematics(spec, path, tool, rng)
    return Simulation(
        samples=_samples(kin, tool, rng),
        truth=_truth(kin),
        stations=_stations(kin, path),
    )


def station_mds(survey: PointSurvey, path: WellPath) -> FloatArray:
    """Station MDs of a point survey, within the plan."""
    if survey.stations is not None:
        mds = np.asarray(survey.stations, dtype=float)
    else:
        assert survey.every is not None
        mds = np.arange(path.start_md, path.end_md + 1e-9, survey.every)
    outside = mds[(mds < path.start_md - 1e-9) | (mds > path.end_md + 1e-9)]
    if len(outside):
        raise ValueError(
            f"survey.stations: MD {outside[0]:g} m is outside the plan "
            f"({path.start_md:g}–{path.end_md:g} m)"
        )
    clipped: FloatArray = np.clip(mds, path.start_md, path.end_md)  # rounding at the ends
    return clipped


def kinematics(
    spec: SimulationSpec, path: WellPath, tool: ToolSensors, rng: np.random.Generator
) -> Kinematics:
    """True attitude, motion and ideal sensor signals at every sample."""
    survey = spec.survey
    assert isinstance(survey, PointSurvey | ContinuousSurvey)
    if isinstance(survey, PointSurvey):
        timeline: Timeline = point_timeline(survey, station_mds(survey, path))
    else:
        start = path.start_md if survey.start_md is None else survey.start_md
        end = path.end_md if survey.end_md is None else survey.end_md
        timeline = continuous_timeline(survey, start, end)
    t = np.arange(int(np.floor(timeline.end * tool.sample_rate)) + 1) / tool.sample_rate
    spin_rate = _torsion_rate(survey.torsion, t, rng)
    s = timeline.at(t)
    state = path.evaluate(s.md)
    inc, azi = state.inc, state.azi
    inc_rate = state.dinc * s.md_rate
    sin_inc_azi_rate = state.sin_inc_dazi * s.md_rate
    moving = np.abs(s.md_rate) / survey.speed
    housing_spin = spin_rate * moving
    # Φ̇ = ω_h + (1 − cos I)·Ȧ = ω_h + tan(I/2)·(sin I·Ȧ): bounded through vertical
    roll_rate = housing_spin + np.tan(inc / 2) * sin_inc_azi_rate
    steps = np.diff(t) * (roll_rate[1:] + roll_rate[:-1]) / 2  # trapezoidal integral
    roll = np.radians(survey.start_roll) + np.concatenate([[0.0], np.cumsum(steps)])
    housing_tf = roll - azi
    theta, theta_rate = s.theta, s.theta_rate
    if isinstance(survey, ContinuousSurvey) and survey.stabilisation.enabled:
        residual, residual_rate = _smooth_gauss_markov(
            t, np.radians(survey.stabilisation.residual), survey.stabilisation.correlation, rng
        )
        # frame angle that puts the gyro at the high side; on an exactly vertical hole (no
        # high side) it aims at the azimuth the hole leaves vertical toward, so the frame
        # does not jump at the kick-off
        servo_tf = roll - _leaving_azimuth(azi, inc)
        servo = residual - servo_tf
        first = int(np.argmax(s.stabilised))
        timeline = continuous_timeline(
            survey, timeline.md_a[0], timeline.md, align=float(servo[first])
        )
        s = timeline.at(t)
        stab = s.stabilised.astype(bool)
        last = len(t) - 1 - int(np.argmax(stab[::-1]))
        # the servo's error grows in with the speed (smoothstep of it): the frame rate has
        # no step where the servo engages or lets go, nor a kink where the ramps end
        speed_rate = np.sign(s.md_rate) * s.md_accel / survey.speed
        engage = moving**2 * (3 - 2 * moving)
        engage_rate = 6 * moving * (1 - moving) * speed_rate
        error = engage * (residual - residual[first])
        error_rate = engage_rate * (residual - residual[first]) + engage * residual_rate
        correction = np.where(stab, error - (servo_tf - servo_tf[first]), 0.0)
        correction[last + 1 :] = correction[last]
        azi_rate = state.dazi * s.md_rate
        correction_rate = np.where(stab, error_rate - (roll_rate - azi_rate), 0.0)
        theta, theta_rate = s.theta + correction, s.theta_rate + correction_rate
    toolface = housing_tf + theta
    c_bn = body_to_ned(azi, inc, toolface)
    cos_tf, sin_tf = np.cos(toolface), np.sin(toolface)
    # ω_nb^b = Rz(ψ)ᵀ (−sin I·Ȧ, İ, 0) + (0, 0, ω_h + θ̇)
    motion = np.stack(
        [
            -cos_tf * sin_inc_azi_rate + sin_tf * inc_rate,
            sin_tf * sin_inc_azi_rate + cos_tf * inc_rate,
            housing_spin + theta_rate,
        ],
        axis=-1,
    )
    rate_body = to_body(c_bn, spec.site.earth_rate()) + motion
    accel_ned = state.dtangent * s.md_rate[:, None] ** 2 + state.tangent * s.md_accel[:, None]
    gravity = np.array([0.0, 0.0, spec.site.gravity])
    accel_body = to_body(c_bn, gravity - accel_ned)
    field_body = to_body(c_bn, spec.site.magnetic.ned()) if spec.site.magnetic is not None else None
    return Kinematics(
        sampled=s,
        inc=inc,
        azi=azi,
        toolface=toolface,
        housing_toolface=housing_tf,
        theta=theta,
        position=state.position,
        c_bn=c_bn,
        rate_body=rate_body,
        accel_body=accel_body,
        field_body=field_body,
    )


def _leaving_azimuth(azi: FloatArray, inc: FloatArray) -> FloatArray:
    """Azimuth (rad) with each exactly vertical sample's replaced by that of the next inclined
    sample (unchanged where none follows): constant, hence rate-free, through vertical."""
    inclined = np.sin(inc) >= VERTICAL_BELOW
    index = np.where(inclined, np.arange(azi.size), azi.size)
    following = np.minimum.accumulate(index[::-1])[::-1]
    leaving: FloatArray = np.where(
        following < azi.size, azi[np.minimum(following, azi.size - 1)], azi
    )
    return leaving


def _torsion_rate(torsion: Torsion, t: FloatArray, rng: np.random.Generator) -> FloatArray:
    """Housing spin rate (rad/s) of the torsion model before scaling by the tool's motion:
    a smooth random spin plus the rate of a sinusoidal roll oscillation."""
    spin, _ = _smooth_gauss_markov(t, np.radians(torsion.spin_sigma), torsion.spin_correlation, rng)
    w = 2 * np.pi / torsion.oscillation_period
    rate: FloatArray = spin + np.radians(torsion.oscillation) * w * np.cos(w * t)
    return rate


def _smooth_gauss_markov(
    t: FloatArray, sigma: float, correlation: float, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    """A smooth random process with the variance (σ²) and correlation time of a first-order
    Gauss–Markov process: the exact AR(1) on knots 1/4 of a correlation time apart,
    interpolated by a cubic spline. Returns value and time derivative at ``t``."""
    if sigma == 0 or len(t) < 2:
        return np.zeros_like(t), np.zeros_like(t)
    step = correlation / 4
    knots = np.arange(0.0, t[-1] + 2 * step, step)
    values = gauss_markov(len(knots), step, sigma, correlation, rng)
    from scipy.interpolate import CubicSpline  # imported on use: slow to import

    spline = CubicSpline(knots, values)
    return spline(t), spline(t, 1)


def _samples(kin: Kinematics, tool: ToolSensors, rng: np.random.Generator) -> pa.Table:
    s = kin.sampled
    rate = measure(
        kin.rate_body * RAD_S_TO_DEG_H, tool.gyro, s.time, rng, specific_force=kin.accel_body
    )
    accel = measure(kin.accel_body, tool.accelerometer, s.time, rng)
    columns: dict[str, object] = {
        "time": s.time,
        "md": odometer_md(s.md, tool.odometer, rng),
        "frame_angle": np.degrees(kin.theta) % 360.0,
    }
    for i, axis in enumerate("xyz"):
        if axis in tool.gyro_axes:
            columns[f"gyro_{axis}"] = rate[:, i]
    columns |= {f"acc_{axis}": accel[:, i] for i, axis in enumerate("xyz")}
    if tool.magnetometer is not None:
        if kin.field_body is None:
            raise ValueError("site.magnetic: the tool has magnetometers; give the reference field")
        field = measure(kin.field_body, tool.magnetometer, s.time, rng)
        columns |= {f"mag_{axis}": field[:, i] for i, axis in enumerate("xyz")}
    columns["station"] = pa.array(s.station, mask=s.station < 0)
    columns["position"] = pa.array(s.position, mask=s.position < 0)
    return RawSamples.compiled().make_table(columns)


def _truth(kin: Kinematics) -> pa.Table:
    s = kin.sampled
    return SimTruth.compiled().make_table(
        {
            "time": s.time,
            "md": s.md,
            "inc": np.degrees(kin.inc),
            "azi": np.degrees(kin.azi) % 360.0,
            "toolface": np.degrees(kin.toolface) % 360.0,
            "housing_toolface": np.degrees(kin.housing_toolface) % 360.0,
            "frame_angle": np.degrees(kin.theta) % 360.0,
            "north": kin.position[:, 0],
            "east": kin.position[:, 1],
            "tvd": kin.position[:, 2],
        },
        north_reference="true",
    )


def _stations(kin: Kinematics, path: WellPath) -> pa.Table:
    """True stations (one per compassing stop) as a Stations table with times."""
    s = kin.sampled
    ids = np.unique(s.station[s.station >= 0])
    first = np.array([np.argmax(s.station == k) for k in ids], dtype=int)
    table = path.stations(s.md[first])
    return table.append_column("station", pa.array(ids, pa.int64())).append_column(
        "time", pa.array(s.time[first])
    )

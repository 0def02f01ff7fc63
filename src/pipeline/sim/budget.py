"""Error budget of a point survey before the job: the azimuth and inclination precision a
tool preset will deliver at each station of a plan (DOMAIN.md §5, seed 004 Eqs. 8–9).

Per station, for the frame positions and dwell of the plan:
- gyro: white noise averaged over each dwell (σ = 60·ARW/√τ °/h) plus the bias
  instability taken as an independent per-position error (conservative: the trend term
  absorbs its slow part), propagated through the least squares of h, r and a bias and trend
  per transverse gyro (one for a single-axis tool, two for an XY or three-axis one, as the
  compass stage fits them) and the maximum-likelihood azimuth, its σ the stage's
  (:func:`pipeline.gyrocompass.azimuth.tail_sigma` of the planned readings); reported for
  the least favourable starting toolface;
- gyro g-dependent bias: turning with the frame like the Earth rate, compassing cannot remove
  it — σ ``g_sensitivity · sin I`` °/h on h and r (:mod:`pipeline.gyrocompass.systematic`),
  ≈ sin I · K / (Ω cos φ) in azimuth;
- accelerometers: white noise averaged over the whole stop, and the bias, misalignment and
  scale factor propagated through the inclination estimator at the plan's frame positions
  (least favourable starting toolface) → σ_I; its leak into the azimuth through
  ∂A/∂I = −sin A (cos A tan I − tan φ).
Gyro biases and linear drift are removed by the multi-position scheme and do not appear. Where
the planned horizontal gravity is not ``tilt_detection`` times its σ (σ_I and the accelerometer
resolution, the compass stage's defaults) above zero the azimuth is undefined, as the compass
stage will declare it: the azimuth σ columns are NaN there. They are NaN too where the
planned readings fit the mirror azimuth 180° − A about as well
(:func:`pipeline.gyrocompass.azimuth.mirror_probability` above the stage's ``ambiguity``,
least favourable starting toolface): near horizontal the stage rejects the station. The
tool's error magnitudes are its 1σ values as :func:`pipeline.sim.sensors.compass_errors`
takes them — the same the compass stage uses for a simulated tool.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa

from pipeline.earth.frames import FloatArray
from pipeline.gyrocompass.azimuth import cramer_rao, mirror_probability, model, tail_sigma
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.precision import hr_covariance
from pipeline.gyrocompass.systematic import ToolErrors, accelerometer_sigma
from pipeline.sim.plan import PathState
from pipeline.sim.sensors import compass_errors, per_axis
from pipeline.sim.simulate import station_mds
from pipeline.sim.spec import PointSurvey, SimulationSpec
from pipeline.tables import ErrorBudget

OFFSETS = np.radians(np.arange(0.0, 360.0, 10.0))
UNOBSERVABLE = 180.0
"""A predicted σ_azi (°) from which the text says the azimuth is unobservable."""


def error_budget(spec: SimulationSpec) -> pa.Table:
    """Predicted 1σ inclination and azimuth errors at each station of a point survey."""
    survey = spec.survey
    if not isinstance(survey, PointSurvey):
        raise ValueError(f"an error budget needs a point survey, not {survey.mode!r}")
    tool = spec.tool.model()
    path = spec.path()
    mds = station_mds(survey, path)
    state = path.evaluate(mds)
    lat = np.radians(spec.site.latitude)
    g = spec.site.gravity

    theta = np.radians(survey.positions)
    step = survey.dwell + survey.move_time
    times = np.arange(len(theta)) * step + survey.dwell / 2
    gyro_sigma = np.hypot(
        60.0 * per_axis(tool.gyro.noise_density)[0] / np.sqrt(survey.dwell),
        per_axis(tool.gyro.bias_instability)[0],
    )
    axes = min(len(tool.gyro_axes), 2)  # the compass stage fits the transverse gyros
    covs = [hr_covariance(theta + off, times, gyro_sigma, axes) for off in OFFSETS]

    stop = len(theta) * survey.dwell
    accel_noise = per_axis(tool.accelerometer.noise_density) / (60.0 * np.sqrt(stop))
    errors = compass_errors(tool)
    accel_errors = np.array([_accel_sigma(i, theta, g, errors) for i in state.inc])
    sigma_inc = np.hypot(accel_noise[:2].mean() / g, accel_errors)

    g_var = (errors.g_sensitivity * np.sin(state.inc)) ** 2
    g_cov = g_var[:, None, None] * np.eye(2)
    n = len(mds)
    planned = model(state.azi, state.inc, lat, 2)
    # the compass stage weighs the mirror against the bound, states the tail's σ
    bound_fit = np.max([cramer_rao(state.azi, state.inc, lat, c + g_cov) for c in covs], axis=0)
    sigma_gyro, sigma_fit = (
        np.max(
            [_fit_sigma(planned, np.broadcast_to(c, (n, 2, 2)) + extra, state, lat) for c in covs],
            axis=0,
        )
        for extra in (np.zeros((n, 2, 2)), g_cov)
    )
    sigma_g = cramer_rao(state.azi, state.inc, lat, g_cov + 1e-30 * np.eye(2))
    leak = np.abs(np.sin(state.azi) * (np.cos(state.azi) * np.tan(state.inc) - np.tan(lat)))
    sigma_accel = leak * sigma_inc
    defaults = CompassOptions()
    sigma_tilt = np.hypot(sigma_inc, defaults.acc_resolution * 1e-6)
    undefined = np.abs(np.sin(state.inc)) <= defaults.tilt_detection * sigma_tilt
    mirror = np.max(
        [
            mirror_probability(
                planned, c + g_cov, state.azi, bound_fit, state.inc, lat, defaults.ambiguity
            )
            for c in covs
        ],
        axis=0,
    )
    for sigma in (sigma_fit, sigma_gyro, sigma_g, sigma_accel):
        sigma[undefined | (mirror > defaults.ambiguity)] = np.nan
    return ErrorBudget.compiled().make_table(
        {
            "md": mds,
            "inc": np.degrees(state.inc),
            "azi": np.degrees(state.azi) % 360.0,
            "sigma_inc": np.degrees(sigma_inc),
            "sigma_azi": np.degrees(np.hypot(sigma_fit, sigma_accel)),
            "sigma_azi_gyro": np.degrees(sigma_gyro),
            "sigma_azi_g": np.degrees(sigma_g),
            "sigma_azi_accel": np.degrees(sigma_accel),
            "mirror": mirror,
        },
        north_reference="true",
    )


def budget_lines(table: pa.Table) -> list[str]:
    """The budget as text: a header and one line per station (degrees); a station without an
    azimuth says why in words."""
    lines = [
        f"{'MD m':>9} {'INC°':>7} {'AZI°':>7} {'σI°':>7} {'σA°':>7} {'gyro':>7} {'g-sens':>7} "
        f"{'acc':>7}"
    ]
    ambiguity = CompassOptions().ambiguity
    for row in table.to_pylist():
        azimuth = (
            f"{row['sigma_azi']:7.3f} {row['sigma_azi_gyro']:7.3f} {row['sigma_azi_g']:7.3f} "
            f"{row['sigma_azi_accel']:7.3f}"
            if np.isfinite(row["sigma_azi"]) and row["sigma_azi"] < UNOBSERVABLE
            else "  azimuth unobservable (east–west near horizontal: the transverse gyros carry "
            "no azimuth)"
            if np.isfinite(row["sigma_azi"])
            else f"  azimuth ambiguous (180° − A fits alike, probability {row['mirror']:.2g})"
            if row["mirror"] > ambiguity
            else "  azimuth undefined (vertical within the accelerometers' resolution)"
        )
        lines.append(
            f"{row['md']:9.1f} {row['inc']:7.2f} {row['azi']:7.2f} {row['sigma_inc']:7.4f} "
            + azimuth
        )
    return lines


def _fit_sigma(planned: FloatArray, cov: FloatArray, state: PathState, lat: float) -> FloatArray:
    """The compass stage's σ_azi (rad) for the planned readings (n, 2) in °/h with
    covariance (n, 2, 2), at the path's azimuths and inclinations, latitude ``lat`` (rad)."""
    bound = cramer_rao(state.azi, state.inc, lat, cov)
    return tail_sigma(planned, cov, state.azi, bound, state.inc, lat)


def _accel_sigma(inc: float, theta: FloatArray, g: float, errors: ToolErrors) -> float:
    """σ of the inclination (rad) from the accelerometer errors compassing leaves, at the
    frame angles ``theta`` (rad), for the least favourable starting toolface."""
    worst = 0.0
    for offset in OFFSETS:
        psi = theta + offset
        acc = g * np.stack(
            [-np.sin(inc) * np.cos(psi), np.sin(inc) * np.sin(psi), np.full_like(psi, np.cos(inc))],
            axis=-1,
        )
        grad = (
            np.stack(
                [
                    -np.cos(psi) * np.cos(inc),
                    np.sin(psi) * np.cos(inc),
                    -np.full_like(psi, np.sin(inc)),
                ],
                axis=-1,
            )
            / g
        )
        worst = max(worst, float(accelerometer_sigma(grad, acc, np.ones_like(psi), errors)))
    return worst

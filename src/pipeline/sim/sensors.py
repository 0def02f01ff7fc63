"""Sensor error models of survey tools: ideal sensor signals in, measured signals out.

Signals are per sample, three body axes (DOMAIN.md §2): angular rate ω_ib^b in deg/h,
accelerometer in m/s² in the gravity sign convention (at rest ``g_b = C_n^b (0, 0, g)``, a
vertical tool reads (0, 0, +g)), magnetic field in nT.

Error model of one triad (:func:`measure`), per sample k at time t_k (s)::

    measured = (I + S + M) · true + b + ḃ · t_k / 3600 + x_k + n_k  [+ K · f_k / g₀ for gyros]

- ``S = diag(scale_factor) · 1e-6`` (ppm);
- ``M`` = ``misalignment`` · 1e-3 (mrad), zero diagonal: ``M[i][j]`` is the sensitivity of
  sensor axis i to the true component along body axis j (small-angle tilt of axis i towards
  j). The six off-diagonal terms cover both misalignment and non-orthogonality;
- ``b`` constant bias, ``ḃ`` bias trend per hour (t counted from the start of the run, t = 0);
- ``x_k`` a first-order Gauss–Markov bias of standard deviation σ = ``bias_instability`` and
  correlation time τ, the exact discrete AR(1)
  ``x_{k+1} = e^{−dt/τ} x_k + σ √(1 − e^{−2dt/τ}) w_k``, started from its stationary
  distribution N(0, σ²);
- ``n_k`` white noise of per-sample standard deviation ``noise_density · c / √dt``
  (dt in s), with c = ``white_noise_factor`` of the sensor class:
  gyro ARW N deg/√h → σ = 60 N/√dt deg/h (Allan deviation at τ = 1 s: 60 N deg/h);
  accelerometer VRW N (m/s)/√h → σ = N/(60 √dt) m/s² (Allan deviation at 1 s: N/60 m/s²);
  magnetometer N nT/√Hz → σ = N √fs nT (Allan deviation at 1 s: N nT, i.e. N is read in the
  Allan/IEEE sense; a one-sided datasheet density would give N √(fs/2));
- gyros only: ``K`` = ``g_sensitivity`` in (deg/h)/g, ``f_k`` the accelerometer's ideal
  signal (m/s², gravity sign convention as above), g₀ = 9.80665 m/s².

Randomness comes only from the ``numpy.random.Generator`` passed in. :func:`measure` always
draws the Gauss–Markov driving noise first, then the white noise, each (n, 3) standard
normals, whichever terms are switched on: a seed gives the same noise realisation whatever
the other error settings.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, field_validator

from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.gyrocompass.systematic import ToolErrors

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]

ZERO3: Vec3 = (0.0, 0.0, 0.0)
ZERO33: Mat3 = (ZERO3, ZERO3, ZERO3)
UNIFORM_RTOL = 1e-6
"""Largest relative deviation of a sample interval from the mean one for uniform sampling."""


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class TriadErrors(_Model):
    """Errors of one three-axis sensor, per axis, in the sensor's unit (see the subclasses:
    :class:`GyroErrors` deg/h, :class:`AccelerometerErrors` m/s²,
    :class:`MagnetometerErrors` nT). ``measured = (I + S + M) · true + bias + …`` (module
    docstring)."""

    white_noise_factor: ClassVar[float]
    """c in the per-sample white-noise σ = noise_density · c / √dt (dt in s)."""

    bias: Vec3 = Field(
        ZERO3, description="constant bias; deg/h (gyro), m/s² (accelerometer), nT (magnetometer)"
    )
    bias_trend: Vec3 = Field(
        ZERO3,
        description="bias change per hour, linear in time from t = 0: (deg/h)/h (gyro), "
        "(m/s²)/h (accelerometer), nT/h (magnetometer)",
    )
    scale_factor: Vec3 = Field(ZERO3, description="scale-factor error of each axis, ppm")
    misalignment: Mat3 = Field(
        ZERO33,
        description="axis misalignment and non-orthogonality, mrad: row i, column j is the "
        "sensitivity of sensor axis i to the true component along body axis j; zero diagonal",
    )
    noise_density: float | Vec3 = Field(
        0.0,
        description="white-noise density (a scalar applies to every axis): gyro angle random "
        "walk deg/√h, accelerometer velocity random walk (m/s)/√h, magnetometer nT/√Hz",
    )
    bias_instability: float | Vec3 = Field(
        0.0,
        description="standard deviation of the first-order Gauss–Markov bias (a scalar applies "
        "to every axis); deg/h (gyro), m/s² (accelerometer), nT (magnetometer)",
    )
    correlation_time: float = Field(
        100.0, gt=0, description="correlation time of the Gauss–Markov bias, s"
    )

    @field_validator("noise_density", "bias_instability")
    @classmethod
    def _non_negative(cls, value: float | Vec3) -> float | Vec3:
        if np.any(np.asarray(value) < 0):
            raise ValueError(f"must be ≥ 0 on every axis (a standard deviation), got {value}")
        return value

    @field_validator("misalignment")
    @classmethod
    def _zero_diagonal(cls, value: Mat3) -> Mat3:
        diagonal = tuple(value[i][i] for i in range(3))
        if any(diagonal):
            raise ValueError(
                f"diagonal must be zero (an axis's own gain error is scale_factor), got {diagonal}"
            )
        return value


class GyroErrors(TriadErrors):
    """Gyro (angular-rate sensor) errors: biases in deg/h, ARW in deg/√h, plus a bias
    proportional to specific force, Δω = K · (f / g₀)."""

    white_noise_factor: ClassVar[float] = 60.0

    g_sensitivity: Mat3 = Field(
        ZERO33,
        description="g-dependent bias matrix K, (deg/h)/g: Δω = K · (a_b / g₀), a_b the "
        "accelerometer signal in m/s² (gravity sign convention), g₀ = 9.80665 m/s²",
    )


class AccelerometerErrors(TriadErrors):
    """Accelerometer errors: biases in m/s², velocity random walk in (m/s)/√h."""

    white_noise_factor: ClassVar[float] = 1.0 / 60.0


class MagnetometerErrors(TriadErrors):
    """Magnetometer errors: biases in nT, noise density in nT/√Hz."""

    white_noise_factor: ClassVar[float] = 1.0


class OdometerErrors(_Model):
    """Errors of the depth (cable) odometer: measured MD = MD · (1 + scale) + noise."""

    scale_factor: float = Field(0.0, description="scale-factor error, ppm of measured depth")
    noise: float = Field(0.0, ge=0, description="white noise standard deviation per sample, m")


class ToolSensors(_Model):
    """The sensors of a simulated survey tool: which gyro axes it has, the errors of each
    sensor, its sample rate. (Not an ISCWSA error model of position uncertainty: that is
    :class:`pipeline.uncertainty.toolmodel.ToolModel`.)"""

    name: str = Field(min_length=1, description="name of the tool (a preset's)")
    description: str = Field("", description="what the tool is and where its numbers come from")
    gyro_axes: Literal["x", "xy", "xyz"] = Field(
        description="gyro input axes: 'x' a single-axis gyro on the frame x axis, 'xy' a "
        "two-axis (dynamically tuned) gyro, 'xyz' a three-axis gyro triad"
    )
    gyro: GyroErrors = Field(description="gyro errors (deg/h, ARW deg/√h)")
    accelerometer: AccelerometerErrors = Field(
        description="accelerometer errors (m/s², VRW (m/s)/√h)"
    )
    magnetometer: MagnetometerErrors | None = Field(
        None, description="magnetometer errors (nT, nT/√Hz); None: the tool has none"
    )
    odometer: OdometerErrors = Field(description="depth odometer errors (ppm, m)")
    sample_rate: float = Field(100.0, gt=0, description="sensor sample rate, Hz")


def measure(
    ideal: ArrayLike,
    errors: TriadErrors,
    time: ArrayLike,
    rng: np.random.Generator,
    *,
    specific_force: ArrayLike | None = None,
) -> FloatArray:
    """Measured signals (n, 3) of one triad from its ideal signals (n, 3), in the sensor's
    unit (deg/h, m/s² or nT), at uniformly spaced ``time`` (n,) in s counted from the start
    of the run. ``specific_force`` (n, 3), m/s² in the gravity sign convention, feeds the
    g-dependent gyro bias: required when ``errors.g_sensitivity`` is non-zero, refused for
    non-gyro errors. The error model and its discretisation are in the module docstring."""
    true = _triads(ideal, "ideal")
    t = np.asarray(time, dtype=float)
    if t.shape != (true.shape[0],):
        raise ValueError(f"time must have shape ({true.shape[0]},) like ideal, got {t.shape}")
    dt = _sample_interval(t)
    white_factor = getattr(type(errors), "white_noise_factor", None)
    if white_factor is None:
        raise TypeError(
            "errors must be GyroErrors, AccelerometerErrors or MagnetometerErrors "
            "(the noise-density unit depends on the sensor), got TriadErrors"
        )
    g_bias = _g_dependent(errors, specific_force, true.shape[0])  # checks before any draw

    gain = (
        np.eye(3)
        + np.diag(np.asarray(errors.scale_factor) * 1e-6)
        + np.asarray(errors.misalignment) * 1e-3
    )
    out = true @ gain.T
    out += np.asarray(errors.bias) + np.outer(t / 3600.0, errors.bias_trend)
    out += gauss_markov(
        true.shape[0], dt, per_axis(errors.bias_instability), errors.correlation_time, rng
    )
    white_sigma = per_axis(errors.noise_density) * white_factor / np.sqrt(dt)
    out += rng.standard_normal(true.shape) * white_sigma
    out += g_bias
    return out


def odometer_md(md_true: ArrayLike, errors: OdometerErrors, rng: np.random.Generator) -> FloatArray:
    """Measured depth, m, same shape as ``md_true`` (m): ``md · (1 + scale·1e-6)`` plus white
    noise of standard deviation ``errors.noise`` per sample."""
    md = np.asarray(md_true, dtype=float)
    return md * (1.0 + errors.scale_factor * 1e-6) + errors.noise * rng.standard_normal(md.shape)


def _triads(values: ArrayLike, name: str) -> FloatArray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {array.shape}")
    return array


def _sample_interval(t: FloatArray) -> float:
    """The constant sample interval of ``t``, s; raises unless uniform and increasing."""
    if t.size < 2:
        raise ValueError(f"need at least 2 samples to know the sample interval, got {t.size}")
    steps = np.diff(t)
    dt = float(t[-1] - t[0]) / (t.size - 1)
    if not dt > 0 or not np.all(np.abs(steps - dt) <= UNIFORM_RTOL * dt):
        worst = int(np.argmax(np.abs(steps - dt)))
        raise ValueError(
            "time must be uniformly sampled and increasing: mean interval "
            f"{dt:g} s, but step {worst} (t = {t[worst]:g} s) is {steps[worst]:g} s"
        )
    return dt


def per_axis(value: float | Vec3) -> FloatArray:
    """A scalar-or-per-axis error parameter as a 3-vector."""
    return np.broadcast_to(np.asarray(value, dtype=float), (3,))


def gauss_markov(
    n: int, dt: float, sigma: ArrayLike, tau: float, rng: np.random.Generator
) -> FloatArray:
    """First-order Gauss–Markov sequence, shape (n, *shape of sigma), of standard deviation
    ``sigma``, correlation time ``tau`` s, sampled every ``dt`` s, started from its
    stationary distribution (exact AR(1), run by ``lfilter``)."""
    sigma = np.asarray(sigma, dtype=float)
    phi = np.exp(-dt / tau)
    drive = rng.standard_normal((n, *sigma.shape)) * sigma
    drive[1:] *= np.sqrt(-np.expm1(-2.0 * dt / tau))
    from scipy.signal import lfilter  # imported on use: scipy.signal costs ~0.8 s to import

    series: FloatArray = lfilter([1.0], [1.0, -phi], drive, axis=0)
    return series


def _g_dependent(errors: TriadErrors, specific_force: ArrayLike | None, n: int) -> FloatArray:
    """Gyro bias K · (f / g₀), (n, 3) deg/h; zeros when the model has no such term."""
    if not isinstance(errors, GyroErrors):
        if specific_force is not None:
            raise ValueError("specific_force applies to gyro errors only")
        return np.zeros((n, 3))
    k = np.asarray(errors.g_sensitivity)
    if specific_force is None:
        if k.any():
            raise ValueError("gyro g_sensitivity is non-zero: pass specific_force (n, 3), m/s²")
        return np.zeros((n, 3))
    force = _triads(specific_force, "specific_force")
    if force.shape[0] != n:
        raise ValueError(f"specific_force must have shape ({n}, 3) like ideal, got {force.shape}")
    bias: FloatArray = (force / STANDARD_GRAVITY) @ k.T
    return bias


def compass_errors(tool: ToolSensors) -> ToolErrors:
    """1σ magnitudes of the tool's errors that compassing cannot remove
    (:mod:`pipeline.gyrocompass.systematic`), as the RMS over its axes: the g-sensitivity
    of its transverse gyros (row norm of K's transverse columns, (°/h)/g), the accelerometer
    bias (m/s²), misalignment (off-diagonal terms, mrad) and scale factor (ppm)."""
    k = np.asarray(tool.gyro.g_sensitivity)[[i for i, a in enumerate("xy") if a in tool.gyro_axes]]
    acc = tool.accelerometer
    misalignment = np.asarray(acc.misalignment)[~np.eye(3, dtype=bool)]
    return ToolErrors(
        g_sensitivity=_rms(np.linalg.norm(k[:, :2], axis=1)) if k.size else 0.0,
        acc_bias=_rms(acc.bias),
        acc_misalignment=_rms(misalignment),
        acc_scale_factor=_rms(acc.scale_factor),
    )


def _rms(values: ArrayLike) -> float:
    return float(np.sqrt(np.mean(np.square(values))))


def _deep_merge(base: dict[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in overrides.items():
        current = merged.get(key)
        if isinstance(current, dict) and isinstance(value, Mapping):
            merged[key] = _deep_merge(current, value)
        else:
            merged[key] = value
    return merged


def tool_preset(name: str, **overrides: Any) -> ToolSensors:
    """A copy of preset ``name`` with ``overrides`` deep-merged into it and validated:
    ``tool_preset("mems-vrg", gyro={"bias": (1, 2, 3)})`` keeps every other gyro error.
    Unknown name → ``ValueError`` listing the presets; a bad override → pydantic
    ``ValidationError`` naming the field."""
    try:
        preset = PRESETS[name]
    except KeyError:
        raise ValueError(
            f"unknown tool preset {name!r}; known presets: {', '.join(sorted(PRESETS))}"
        ) from None
    return ToolSensors.model_validate(_deep_merge(preset.model_dump(), overrides))


_WIRELINE = OdometerErrors(scale_factor=500.0, noise=0.05)
"""Cable depth counter: 0.05 % stretch/wheel scale (about ISCWSA wireline depth scale,
~5e-4), 5 cm per-sample jitter."""

PAPER_ACC_NOISE_DENSITY = STANDARD_GRAVITY * float(np.sin(np.radians(10.0 / 60.0))) * 60.0 * 0.1
"""(m/s)/√h whose per-sample σ at 100 Hz (dt = 0.01 s, σ = N / (60 √dt)) is g·sin(10′) =
0.0285 m/s²: the accelerometer noise of 10 arc-min (1σ) of Binder & Khazov (2023)."""

PRESETS: dict[str, ToolSensors] = {
    "mems-vrg": ToolSensors(
        name="mems-vrg",
        description="Single-axis inductive MEMS vibrating-ring gyro on a rotating frame "
        "(seed 004): drift stability ~0.1 deg/h as the paper states (Gauss–Markov 0.1 deg/h, "
        "ARW 0.02 deg/√h), 5 deg/h turn-on bias and 0.5 (deg/h)/h warm-up trend that "
        "multi-position compassing removes; MEMS accelerometers 0.1-0.2 mg bias (paper: "
        "4.4e-4 g 3σ), 0.1 mg per-sample noise at 100 Hz.",
        gyro_axes="x",
        gyro=GyroErrors(
            bias=(5.0, 5.0, 5.0),
            bias_trend=(0.5, 0.5, 0.5),
            scale_factor=(300.0, 300.0, 300.0),
            misalignment=((0.0, 0.5, -1.0), (-0.5, 0.0, 0.8), (1.0, -0.8, 0.0)),
            noise_density=0.02,
            bias_instability=0.1,
            correlation_time=300.0,
            g_sensitivity=((0.1, 0.0, 0.0), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1)),
        ),
        accelerometer=AccelerometerErrors(
            bias=(1.5e-3, -1.0e-3, 2.0e-3),
            scale_factor=(200.0, 200.0, 200.0),
            misalignment=((0.0, 0.5, -0.3), (-0.5, 0.0, 0.4), (0.3, -0.4, 0.0)),
            noise_density=0.006,
            bias_instability=2.0e-4,
            correlation_time=300.0,
        ),
        odometer=_WIRELINE,
    ),
    "mems-vrg-paper": ToolSensors(
        name="mems-vrg-paper",
        description="The error set of the continuous-mode simulation in Binder & Khazov "
        "(2023), 'Versatile gyroinclinometer based on a single axis angular rate sensor', "
        "and nothing else: single-axis gyro constant error 0.1 deg/h (3σ), accelerometer "
        "constant error 4.4e-4 g (3σ), accelerometer noise 10 arc-min (1σ, taken per 100 Hz "
        "sample: 0.0285 m/s²); no gyro noise, instability, trend, scale, misalignment or "
        "g-sensitivity, an exact odometer. The biases here are one realisation of 1σ size; "
        "benchmarks/study_error_budget.py draws them per run.",
        gyro_axes="x",
        gyro=GyroErrors(bias=(0.0333, -0.0333, 0.0333)),
        accelerometer=AccelerometerErrors(
            bias=(1.44e-3, -1.44e-3, 1.44e-3),
            noise_density=PAPER_ACC_NOISE_DENSITY,
        ),
        odometer=OdometerErrors(),
    ),
    "nav-grade": ToolSensors(
        name="nav-grade",
        description="Three-axis navigation-grade (ring-laser/fibre-optic) gyro triad: ARW "
        "0.003 deg/√h, bias instability 0.01 deg/h, turn-on bias 0.01-0.03 deg/h, no "
        "g-sensitivity (optical); quartz-flex accelerometers ~50 µg bias, ~5 µg/√Hz.",
        gyro_axes="xyz",
        gyro=GyroErrors(
            bias=(0.02, -0.03, 0.01),
            scale_factor=(10.0, 10.0, 10.0),
            misalignment=((0.0, 0.05, -0.03), (-0.05, 0.0, 0.04), (0.03, -0.04, 0.0)),
            noise_density=0.003,
            bias_instability=0.01,
            correlation_time=3600.0,
        ),
        accelerometer=AccelerometerErrors(
            bias=(5.0e-4, -4.0e-4, 3.0e-4),
            scale_factor=(50.0, 50.0, 50.0),
            misalignment=((0.0, 0.05, -0.03), (-0.05, 0.0, 0.04), (0.03, -0.04, 0.0)),
            noise_density=0.003,
            bias_instability=1.0e-4,
            correlation_time=3600.0,
        ),
        odometer=_WIRELINE,
    ),
    "dtg-xy": ToolSensors(
        name="dtg-xy",
        description="Two-axis dynamically tuned gyro (XY scheme, spin along the tool axis): "
        "mass-unbalance g-sensitivity 1 (deg/h)/g cross-axis and 0.2 (deg/h)/g in-axis, "
        "random bias 0.15 deg/h (ISCWSA GYRO-NS), ARW 0.01 deg/√h, 2 deg/h turn-on bias "
        "removed by 0/180/0 compassing; quartz-flex accelerometers ~0.1 mg bias.",
        gyro_axes="xy",
        gyro=GyroErrors(
            bias=(2.0, -1.5, 0.0),
            bias_trend=(0.3, -0.3, 0.0),
            scale_factor=(500.0, 500.0, 0.0),
            misalignment=((0.0, 1.0, -0.5), (-1.0, 0.0, 0.5), ZERO3),
            noise_density=(0.01, 0.01, 0.0),
            bias_instability=(0.15, 0.15, 0.0),
            correlation_time=600.0,
            g_sensitivity=((0.2, 1.0, 0.0), (-1.0, 0.2, 0.0), ZERO3),
        ),
        accelerometer=AccelerometerErrors(
            bias=(1.0e-3, -8.0e-4, 6.0e-4),
            scale_factor=(100.0, 100.0, 100.0),
            misalignment=((0.0, 0.3, -0.2), (-0.3, 0.0, 0.2), (0.2, -0.2, 0.0)),
            noise_density=0.005,
            bias_instability=2.0e-4,
            correlation_time=600.0,
        ),
        odometer=_WIRELINE,
    ),
    "ideal": ToolSensors(
        name="ideal",
        description="Error-free three-axis tool with magnetometers: the noise-free oracle "
        "for round-trip tests.",
        gyro_axes="xyz",
        gyro=GyroErrors(),
        accelerometer=AccelerometerErrors(),
        magnetometer=MagnetometerErrors(),
        odometer=OdometerErrors(),
    ),
}
"""The tool catalogue: named tools, by preset name; copy and modify them with
:func:`tool_preset`."""

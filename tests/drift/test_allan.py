"""Allan analysis of simulated static records: ARW, bias instability (flicker floor and
Gauss–Markov bump) and RRW recovered within 10 %; the dwell recommendation; the stage."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pyarrow as pa
import pytest

from pipeline.drift.allan import (
    NoiseFit,
    allan_deviation,
    azimuth_sigma,
    fit_noise,
    recommend_dwell,
)
from pipeline.drift.tables import AllanResult, DwellRecommendation, NoiseParameters
from pipeline.errors import MissingSiteError
from pipeline.sim.sensors import AccelerometerErrors, GyroErrors, measure
from pipeline.stages import drift as drift_plugin
from pipeline.tables import RawSamples
from pipeline.well import WellMetadata

FS = 10.0  # Hz
HOURS = 4.0
ARW = 0.001  # deg/√h → Allan deviation 60·ARW deg/h at 1 s


def white(rng: np.random.Generator, n: int, arw: float = ARW) -> np.ndarray:
    """Gyro white noise, deg/h, of angle random walk ``arw`` deg/√h at FS."""
    return rng.standard_normal(n) * 60 * arw * np.sqrt(FS)


def flicker(rng: np.random.Generator, n: int, instability: float) -> np.ndarray:
    """Flicker (1/f) noise of one-sided PSD B²/(2π f), whose Allan deviation is 0.664·B."""
    f = np.fft.rfftfreq(n, 1 / FS)
    amplitude = np.zeros_like(f)
    amplitude[1:] = instability / np.sqrt(2 * np.pi * f[1:])
    spectrum = (rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))) * amplitude
    return np.fft.irfft(spectrum * np.sqrt(FS * n / 2), n)


def test_flicker_floor_gives_the_bias_instability():
    rng = np.random.default_rng(1)
    n = int(FS * HOURS * 3600)
    fit = fit_noise(allan_deviation(white(rng, n, 0.005) + flicker(rng, n, 0.2), FS))
    assert fit.white / 60 == pytest.approx(0.005, rel=0.1)
    assert fit.bias == pytest.approx(0.2, rel=0.1)


def test_rate_random_walk_from_integrated_white_noise():
    rng = np.random.default_rng(2)
    n = int(FS * HOURS * 3600)
    walk = 0.02  # (deg/h)/√s: the +1/2 line is 0.02 deg/h at τ = 3 s
    rrw = np.cumsum(rng.standard_normal(n)) * walk / np.sqrt(FS)
    fit = fit_noise(allan_deviation(white(rng, n) + rrw, FS))
    assert fit.white / 60 == pytest.approx(ARW, rel=0.1)
    assert fit.walk == pytest.approx(walk, rel=0.1)


def static_record(
    seed: int, hours: float, rate: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time, gyro (deg/h) and accelerometer (m/s²) samples of the sensor model at rest."""
    rng = np.random.default_rng(seed)
    n = int(rate * hours * 3600)
    time = np.arange(n) / rate
    gyro = measure(
        np.zeros((n, 3)),
        GyroErrors(noise_density=0.005, bias_instability=0.2, correlation_time=60.0),
        time,
        rng,
    )
    acc = measure(
        np.tile([0.0, 0.0, 9.81], (n, 1)),
        AccelerometerErrors(noise_density=0.006, bias_instability=1e-4, correlation_time=60.0),
        time,
        rng,
    )
    return time, gyro, acc


def test_gauss_markov_bias_of_the_sensor_model():
    """The simulator's bias instability is a Gauss–Markov σ_b: its Allan curve is a bump
    (0.617·σ_b at 1.89·T), fitted as such."""
    _, gyro, acc = static_record(3, 16.0, 2.0)  # 960 correlation times
    for axis in range(3):
        fit = fit_noise(allan_deviation(gyro[:, axis], 2.0), "gauss_markov")
        assert fit.white / 60 == pytest.approx(0.005, rel=0.1)
        assert fit.bias == pytest.approx(0.2, rel=0.1)
        assert fit.correlation_time == pytest.approx(60.0, rel=0.3)
    fit = fit_noise(allan_deviation(acc[:, 0], 2.0), "gauss_markov")
    assert fit.white * 60 == pytest.approx(0.006, rel=0.1)  # VRW (m/s)/√h


def test_dwell_for_white_noise_follows_one_over_root_tau():
    gyro = NoiseFit(white=1.2, bias=0.0, walk=0.0, model="flicker", correlation_time=None, rms=0)
    positions = [0.0, 90.0, 180.0, 270.0, 0.0]
    sigma_at_1s = azimuth_sigma(gyro, np.array([1.0]), 61.25, 30.0, positions)[0]
    target = 1.0
    dwell = recommend_dwell(gyro, target, 61.25, 30.0, positions, 3.0, 600.0)
    assert dwell.achievable
    assert dwell.dwell == pytest.approx((sigma_at_1s / target) ** 2, rel=0.02)
    assert target * 0.98 < dwell.sigma_azi <= target
    assert dwell.station_time == pytest.approx(5 * dwell.dwell + 4 * 3.0)
    assert dwell.sigma_rate == pytest.approx(1.2 / np.sqrt(dwell.dwell))
    # a single-position σ of 1.2/√τ deg/h: the azimuth σ is σ_h / (Ω cos φ) for (h, r)
    # differences of opposite positions, worse by up to 1/cos I at the worst azimuth
    k = 15.041 * np.cos(np.radians(61.25))
    assert sigma_at_1s == pytest.approx(
        np.degrees(1.2 / np.sqrt(2) / k / np.cos(np.radians(30))), rel=0.25
    )


def test_unreachable_target_returns_the_best_dwell():
    gyro = NoiseFit(
        white=1.2, bias=0.2, walk=0.0, model="gauss_markov", correlation_time=60.0, rms=0
    )
    dwell = recommend_dwell(gyro, 0.05, 61.25, 30.0, [0, 90, 180, 270, 0], 3.0, 600.0)
    assert not dwell.achievable
    assert dwell.dwell == dwell.best_dwell and dwell.sigma_azi == dwell.best_sigma_azi > 0.05


def test_allan_stage_on_raw_samples():
    time, gyro, acc = static_record(4, 2.0, 10.0)
    samples = RawSamples.compiled().make_table(
        {"time": time}
        | {f"gyro_{a}": gyro[:, i] for i, a in enumerate("xyz")}
        | {f"acc_{a}": acc[:, i] for i, a in enumerate("xyz")}
    )
    ctx = SimpleNamespace(well=WellMetadata(latitude=61.25))
    params = drift_plugin.AllanParams(bias_model="gauss_markov", start=60.0, target_sigma_azi=1.0)
    out = drift_plugin.allan_stage({"samples": samples}, params, ctx)
    AllanResult.validate_table(out["allan"])
    NoiseParameters.validate_table(out["noise"])
    DwellRecommendation.validate_table(out["dwell"])
    noise = {row["axis"]: row for row in out["noise"].to_pylist()}
    assert noise["gyro_y"]["arw"] == pytest.approx(0.005, rel=0.1)
    assert noise["gyro_y"]["arw_unit"] == "deg/sqrt(h)"
    assert noise["acc_z"]["arw"] == pytest.approx(0.006, rel=0.1)
    assert noise["acc_z"]["arw_unit"] == "m/s/sqrt(h)"
    assert out["allan"].column("tau")[0].as_py() == pytest.approx(0.1)
    dwell = out["dwell"].to_pylist()[0]
    assert dwell["achievable"] and dwell["sigma_azi"] <= 1.0
    assert dwell["axis"] in ("gyro_x", "gyro_y", "gyro_z")
    with pytest.raises(MissingSiteError, match="allan stage's `latitude`"):
        drift_plugin.allan_stage({"samples": samples}, params, SimpleNamespace(well=WellMetadata()))
    gap = samples.filter(pa.array(np.arange(samples.num_rows) != 5000))
    with pytest.raises(ValueError, match="uniformly sampled"):
        drift_plugin.allan_stage({"samples": gap}, drift_plugin.AllanParams(), ctx)

"""Station MDs of noisy continuous runs against the simulator: the odometer's noise must not
bias them (DOMAIN.md §6).

The tool is ideal but for the wireline odometer's white noise (5 cm per sample, no scale
error), so a station's MD error is the odometer's alone. Its predicted σ follows from the
estimators' own definitions, computed here in closed form: between the stops, the value of
the cubic Savitzky–Golay fit (a fixed linear combination of the samples: σ·‖kernel‖); at the
stops, the median of the dwell's samples (σ·√(π/2n)). The stations' positions are computed
with the true angles at the stations' times, so that the TVD error is the MDs' alone."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import pyarrow as pa
import pytest
from continuous_support import LAT, SITE, compassed
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs

from pipeline.continuous import ContinuousError, ContinuousOptions, integrate_continuous
from pipeline.sim.simulate import Simulation, simulate
from pipeline.sim.spec import SimulationSpec
from pipeline.survey.mincurve import minimum_curvature

FloatArray = NDArray[np.float64]
N_RUNS = 40
RATE = 20.0  # Hz
ODOMETER_NOISE = 0.05  # m per sample
OPTIONS = ContinuousOptions(spacing=10.0)  # stations ≥ 6 s apart: independent fit errors
SECTIONS = [
    {"kind": "vertical", "length": 20},
    {"kind": "build", "dls": 6.0, "inc": 30, "azi": 60},
    {"kind": "curve", "dls": 4.0, "inc": 40, "azi": 100},
    {"kind": "hold", "length": 100},
]
SURVEY = {
    "mode": "continuous",
    "start_md": 60,
    "end_md": 210,
    "speed": 1.5,
    "stop": {"dwell": 10.0, "move_time": 1.0},
}


@dataclass(frozen=True)
class Run:
    md_err: FloatArray  # m, station MD minus the true MD at the station's time
    sigma_md: FloatArray  # m, predicted
    tvd_err: float  # m, at the last station
    sigma_tvd: float  # m, predicted at the last station


def _sigma_md(readings: pa.Table, n_stations: int) -> FloatArray:
    """Predicted σ of the stations' MDs: the cubic fit's between the stops, the dwell
    median's at the stops."""
    points = round(OPTIONS.odometer_window * RATE) | 1
    fit = ODOMETER_NOISE * float(np.linalg.norm(savgol_coeffs(points, 3)))
    station = readings.column("station").to_numpy()
    n = readings.column("n").to_numpy()
    median = [ODOMETER_NOISE * np.sqrt(np.pi / (2 * n[station == s].sum())) for s in (0, 1)]
    return np.concatenate([[median[0]], np.full(n_stations - 2, fit), [median[1]]])


def _tvd(md: FloatArray, inc: FloatArray, azi: FloatArray, tie: FloatArray) -> FloatArray:
    """Minimum-curvature TVD (m) of stations (m, rad) tied at the position ``tie``."""
    mc = minimum_curvature(md, inc, azi, tie_north=tie[0], tie_east=tie[1], tie_tvd=tie[2])
    out: FloatArray = mc.tvd
    return out


def _simulate(seed: int) -> tuple[Simulation, pa.Table, pa.Table]:
    """Samples, position readings and compassed stops of a run."""
    spec = SimulationSpec.model_validate(
        {
            "name": "odometer",
            "seed": seed,
            "site": SITE,
            "well": {"sections": SECTIONS},
            "tool": {
                "preset": "ideal",
                "overrides": {
                    "gyro_axes": "x",
                    "sample_rate": RATE,
                    "magnetometer": None,
                    "odometer": {"noise": ODOMETER_NOISE},
                },
            },
            "survey": SURVEY,
        }
    )
    sim = simulate(spec)
    readings, stops, _ = compassed(sim.samples)
    return sim, readings, stops


def _run(seed: int) -> Run:
    sim, readings, stops = _simulate(seed)
    stations = integrate_continuous(sim.samples, stops, LAT, OPTIONS).stations
    md = stations.column("md").to_numpy()
    np.testing.assert_array_equal(md[[0, -1]], stops.column("md").to_numpy())
    t = stations.column("time").to_numpy()
    truth_t = sim.truth.column("time").to_numpy()

    def truth(name: str) -> FloatArray:
        values: FloatArray = np.interp(t, truth_t, sim.truth.column(name).to_numpy())
        return values

    md_err = md - truth("md")
    sigma_md = _sigma_md(readings, md.size)
    # positions from the station MDs and the true angles where the tool was at those times
    inc = np.radians(truth("inc"))
    azi = np.unwrap(np.radians(sim.truth.column("azi").to_numpy()))
    azi = np.interp(t, truth_t, azi)
    tie = np.array([truth("north")[0], truth("east")[0], truth("tvd")[0]])
    tvd_err = float(_tvd(md, inc, azi, tie)[-1] - truth("tvd")[-1])
    # ∂TVD_last/∂MD_j by central differences; the MD errors are independent between stations
    step = 1e-3
    jacobian = np.array(
        [
            (_tvd(md + step * e, inc, azi, tie)[-1] - _tvd(md - step * e, inc, azi, tie)[-1])
            / (2 * step)
            for e in np.eye(md.size)
        ]
    )
    sigma_tvd = float(np.sqrt(np.sum((jacobian * sigma_md) ** 2)))
    return Run(md_err, sigma_md, tvd_err, sigma_tvd)


@cache
def runs() -> tuple[Run, ...]:
    return tuple(_run(seed) for seed in range(N_RUNS))


def test_station_md_errors_are_unbiased_and_match_their_sigma() -> None:
    """Pooled over runs and stations, z = MD error/σ has mean 0 within its own standard
    error (3/√n) and unit spread. Resampling on the raw odometer's running maximum, which
    keeps the samples with positive noise, fails this: its MDs come out 1.2σ deep between
    the stops and 46σ (0.1 m) deep at the end stop, the largest of the noisy samples as the
    tool comes to rest."""
    rs = runs()
    z = np.concatenate([r.md_err / r.sigma_md for r in rs])
    print(f"MD z: n={z.size} mean={z.mean():.3f} std={z.std():.3f}")
    assert abs(z.mean()) < 3.0 / np.sqrt(z.size)
    assert 0.8 < z.std() < 1.2
    ends = np.array([r.md_err[[0, -1]] / r.sigma_md[[0, -1]] for r in rs])
    assert np.all(np.abs(ends.mean(axis=0)) < 3.0 / np.sqrt(N_RUNS))


def test_tvd_at_the_end_stop_is_unbiased() -> None:
    """The TVD error the station MDs make at the last station: mean over runs within 3σ of
    the mean (σ propagated from the MDs' through minimum curvature; 0.4 mm here, where the
    running-maximum resampling gave +0.08 m)."""
    rs = runs()
    err = np.array([r.tvd_err for r in rs])
    sigma = np.array([r.sigma_tvd for r in rs])
    sigma_mean = float(np.sqrt(np.sum(sigma**2))) / N_RUNS
    print(f"TVD at the end stop: mean {err.mean():.5f} m, σ of the mean {sigma_mean:.5f} m")
    assert abs(err.mean()) < 3.0 * sigma_mean
    assert 0.7 < np.std(err / sigma) < 1.3


def test_end_stop_not_deeper_than_the_start_is_refused() -> None:
    sim, _, stops = _simulate(0)
    md = stops.column("md").to_numpy().copy()
    md[1] = md[0] - 1.0
    index = stops.schema.get_field_index("md")
    upward = stops.set_column(index, stops.schema.field("md"), pa.array(md))
    said = rf"end stop's MD \({md[1]:.3f} m\) is not deeper than the start stop's \({md[0]:.3f} m\)"
    with pytest.raises(ContinuousError, match=said):
        integrate_continuous(sim.samples, upward, LAT, OPTIONS)

"""The stations' tilts made together (the stations of a size stacked): a stacked sum is each
station's own, the accelerometer errors' σ of a stack each station's alone, and every
station of a mixed record compassed as it is alone — bit for bit on the machines measured,
asserted within :data:`ULP` units in the last place (CPUs' kernels may differ in the last
bits)."""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pytest

from pipeline.earth.frames import body_to_ned, to_body
from pipeline.gyrocompass.options import CompassOptions
from pipeline.gyrocompass.positions import stacks
from pipeline.gyrocompass.precision import OMEGA_DEG_H
from pipeline.gyrocompass.solve import compass
from pipeline.gyrocompass.systematic import ToolErrors, accelerometer_sigma

TOOL = ToolErrors(g_sensitivity=0.1, acc_bias=1e-3, acc_misalignment=0.4, acc_scale_factor=200.0)
OFF_DIAGONAL = ~np.eye(3, dtype=bool)
ULP = 2
"""units in the last place a stacked number may differ by from a station's alone"""


def assert_same_row(alone: dict[str, object], together: dict[str, object]) -> None:
    """Two rows alike: the same keys, text and integers equal, floats within :data:`ULP`
    (NaN alike)."""
    assert alone.keys() == together.keys()
    for name, value in alone.items():
        if isinstance(value, float):
            other = together[name]
            assert isinstance(other, float), name
            np.testing.assert_array_max_ulp(value, other, maxulp=ULP)
        else:
            assert value == together[name], name


def test_stacked_sums_are_each_stations_own() -> None:
    """Stations of 1–40 positions in one column: summed along a stack's rows, each station's
    sum is its 1-D array's (the same pairwise summation: from 8 values numpy adds pairwise,
    not in order)."""
    rng = np.random.default_rng(3)
    sizes = rng.integers(1, 41, 400)
    starts = np.r_[0, np.cumsum(sizes)[:-1]]
    column = rng.normal(0, 1, sizes.sum()) * 10.0 ** rng.integers(-8, 8, sizes.sum())
    seen = 0
    for members, rows in stacks(starts, sizes):
        assert (sizes[members] == rows.shape[1]).all()
        for i, total in zip(members, column[rows].sum(axis=1), strict=True):
            alone = column[starts[i] : starts[i] + sizes[i]].sum()
            np.testing.assert_array_max_ulp(total, alone, maxulp=ULP)
            seen += 1
    assert seen == len(sizes)


def one_sigma(gradient: np.ndarray, acc: np.ndarray, weights: np.ndarray) -> float:
    """The accelerometer errors' σ of one station (numpy on its own 1-D and 2-D arrays, how
    it was made station by station)."""
    w = weights / weights.sum()
    d_bias = w @ gradient
    d_gain = np.einsum("k,ki,kj->ij", w, gradient, acc)
    var = (
        TOOL.acc_bias**2 * float(d_bias @ d_bias)
        + (TOOL.acc_misalignment * 1e-3) ** 2 * float((d_gain[OFF_DIAGONAL] ** 2).sum())
        + (TOOL.acc_scale_factor * 1e-6) ** 2 * float((d_gain.diagonal() ** 2).sum())
    )
    return float(np.sqrt(var))


def test_accelerometer_sigma_of_a_stack_is_each_stations_own() -> None:
    rng = np.random.default_rng(4)
    for n in range(1, 13):
        gradient = rng.normal(0, 1, (30, n, 3)) * 10.0 ** rng.integers(-3, 3, (30, n, 3))
        acc = rng.normal(0, 10, (30, n, 3))
        weights = rng.uniform(0, 1, (30, n)) * 10.0 ** rng.integers(-3, 6, (30, n))
        stacked = accelerometer_sigma(gradient, acc, weights, TOOL)
        for j in range(30):
            one = one_sigma(gradient[j], acc[j], weights[j])
            np.testing.assert_array_max_ulp(stacked[j], one, maxulp=ULP)


def record(rng: np.random.Generator, axes: str) -> pa.Table:
    """Stations of 1–12 positions at 61° N: inclined, near vertical, exactly vertical (no
    horizontal gravity), a wrong |g|, a NaN reading, a frame angle off its toolface."""
    lat = np.radians(61.0)
    w_ned = OMEGA_DEG_H * np.array([np.cos(lat), 0.0, -np.sin(lat)])
    columns: dict[str, list[float]] = {}
    for s in range(60):
        n, kind = int(rng.integers(1, 13)), s % 6
        inc = (rng.uniform(5, 100), rng.uniform(0, 2.5), 0.0, rng.uniform(5, 100))[min(kind, 3)]
        steps = np.arange(n) * 90.0
        c_bn = body_to_ned(np.radians(rng.uniform(0, 360)), np.radians(inc), np.radians(steps))
        acc = to_body(c_bn, np.array([0.0, 0.0, 9.81])) + rng.normal(0, 1e-3, (n, 3))
        frame = steps % 360.0
        if kind == 2:
            acc[:, :2] = 0.0
        elif kind == 3:
            frame[-1] += 5.0
        elif kind == 4 and s % 12 == 4:
            acc *= 0.1
        elif kind == 5 and s % 12 == 5:
            acc[-1, 0] = np.nan
        gyro = to_body(c_bn, w_ned) + rng.normal(0, 0.05, (n, 3))
        values = {
            "station": [s] * n,
            "md": [30.0 * s] * n,
            "position": list(range(n)),
            "t": (1000.0 * s + 43.0 * np.arange(n)).tolist(),
            "frame_angle": frame.tolist(),
            "n": [3900] * n,
        }
        for i, a in enumerate("xyz"):
            values[f"acc_{a}"] = acc[:, i].tolist()
            values[f"acc_{a}_std"] = rng.uniform(0.05, 0.1, n).tolist()
            if a in axes:
                values[f"gyro_{a}"] = gyro[:, i].tolist()
                values[f"gyro_{a}_std"] = rng.uniform(0.5, 2.0, n).tolist()
        for name, v in values.items():
            columns.setdefault(name, []).extend(v)
    return pa.table(columns)


def test_each_station_of_a_mixed_record_is_compassed_as_alone() -> None:
    """Rows and rejects of every station (every flag, angle, σ and reason) are those of the
    station's readings compassed alone, whatever the sizes of the others —
    but an inclined station's σ_azi and σ_toolface: the azimuth solve of the record's
    inclined stations together (:func:`~pipeline.gyrocompass.azimuth.solve_azimuth`, not
    the tilts) moves them by a few ulp with the others (as before the tilts were stacked);
    and the fewer_positions flag, which compares a station with the record's others (a
    station alone has the usual number of positions)."""
    rng = np.random.default_rng(6)
    options = CompassOptions(
        acc_bias=TOOL.acc_bias,
        acc_misalignment=TOOL.acc_misalignment,
        acc_scale_factor=TOOL.acc_scale_factor,
        g_sensitivity=TOOL.g_sensitivity,
    )
    outcomes: set[str] = set()
    for axes in ("x", "xy", "xyz"):
        readings = record(rng, axes)
        stations, rejects = compass(readings, 61.0, options)
        together = {row["station"]: row for row in stations.to_pylist() + rejects.to_pylist()}
        for s in np.unique(readings.column("station").to_numpy()):
            one = readings.filter(pc.equal(readings.column("station"), s))
            alone_stations, alone_rejects = compass(one, 61.0, options)
            (alone,) = alone_stations.to_pylist() + alone_rejects.to_pylist()
            row = together[s]
            if "flags" in row:
                flags = row["flags"].split(",")
                sizes = np.unique(readings.column("station").to_numpy(), return_counts=True)[1]
                values, count = np.unique(sizes, return_counts=True)
                fewer = row["positions"] < values[count == count.max()].max()
                assert ("fewer_positions" in flags) == fewer
                row["flags"] = ",".join(f for f in flags if f != "fewer_positions")
            if alone.get("mode") == "inclined":
                for name in ("sigma_azi", "sigma_toolface"):
                    assert alone[name] == pytest.approx(row.pop(name), rel=1e-14)
                    del alone[name]
            assert_same_row(alone, row)
            outcomes.update(alone.get("flags", alone.get("reason", "")).split(","))
    assert {"frame_mismatch", "azimuth_from_toolface", "azimuth_undefined"} <= outcomes
    assert "accelerometer readings give no inclination" in outcomes
    assert any("not gravity" in outcome for outcome in outcomes)

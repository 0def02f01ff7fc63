"""Acceptance gates of a gyro survey: the in-run compared with the out-run.

Each station of the in-run is paired with the out-run station nearest in MD (each out-run
station used once, pairs at most ``pair_window`` apart). A pair compares inclination and
azimuth (wrapped to ±180°) and the two depths. The gates, each pass, fail or not evaluated:

    stations     pairs compared ≥ ``min_stations`` (default 10)
    inclination  every |Δinc| ≤ ``inc_tolerance`` (0.23°)
    azimuth      every |ΔA| ≤ ``azi_tolerance`` (1.0°) where the mean inclination is at
                 least ``low_inclination`` (10°) …
    azimuth_low  … and ≤ ``azi_tolerance_low`` (5.0°) below it (undefined azimuths at
                 vertical are not compared)
    depth        every |ΔMD| ≤ ``depth_tolerance`` (0.5 m): the two runs' depths agree
    tie_in       a free gyro's in/out QC only: |ΔA| of its tie-in pair ≤ ``azi_tolerance``
                 at any inclination (a tie-in error shifts every corrected azimuth)
    coverage     every MD gap between consecutive stations compared ≤ ``max_gap`` (100 m):
                 a depth left unsurveyed by either run is not accepted
    td           when a total depth ``td`` is stated: the deepest station compared is at
                 most ``td_tolerance`` (0.5 m) above it (no ``td``: no such gate)

The angular defaults are the in-run/out-run tolerances of industry gyro-survey practice;
every limit is a parameter, so a client's own acceptance criteria are a configuration.
Angles in degrees, depths in metres.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.qc.tables import RunComparison
from pipeline.tables import AcceptanceGates

__all__ = [
    "GateOptions",
    "acceptance_gates",
    "acceptance_lines",
    "compare_runs",
    "failed_gates",
    "pair_stations",
]

PASS, FAIL, NOT_EVALUATED = "pass", "fail", "not evaluated"


class GateOptions(BaseModel):
    """Acceptance criteria of an in-run/out-run comparison (angles deg, depths m)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)
    inc_tolerance: float = Field(0.23, gt=0, description="largest |Δ inclination|, deg")
    azi_tolerance: float = Field(1.0, gt=0, description="largest |Δ azimuth|, deg, at or above…")
    low_inclination: float = Field(10.0, ge=0, description="…this mean inclination, deg")
    azi_tolerance_low: float = Field(5.0, gt=0, description="largest |Δ azimuth| below it, deg")
    min_stations: int = Field(10, ge=1, description="fewest stations compared")
    depth_tolerance: float = Field(0.5, gt=0, description="largest |Δ MD| of a pair, m")
    pair_window: float = Field(
        5.0, gt=0, description="an out-run station this close in MD (m) can pair an in-run one"
    )
    max_gap: float = Field(
        100.0, gt=0, description="largest MD gap between consecutive stations compared, m"
    )
    td: float | None = Field(
        None, gt=0, description="stated (planned) total depth the runs must reach, m MD"
    )
    td_tolerance: float = Field(
        0.5, gt=0, description="the deepest station compared this far above td reaches it, m"
    )


def pair_stations(md_in: np.ndarray, md_out: np.ndarray, window: float) -> np.ndarray:
    """(k, 2) row indices of in-run and out-run stations paired by nearest MD, closest pairs
    first, each station in one pair at most, |ΔMD| ≤ ``window``; sorted by in-run row. Only
    the pairs within the window are considered (a few per station), so long runs pair in
    O(n log n)."""
    order = np.argsort(md_out, kind="stable")
    sorted_out = md_out[order]
    lo = np.searchsorted(sorted_out, md_in - window, side="left")
    hi = np.searchsorted(sorted_out, md_in + window, side="right")
    count = np.maximum(hi - lo, 0)
    i = np.repeat(np.arange(md_in.size), count)
    start = np.repeat(lo - np.cumsum(count) + count, count)
    o = order[start + np.arange(i.size)]
    dist = np.abs(md_in[i] - md_out[o])
    used_in = np.zeros(md_in.size, dtype=bool)
    used_out = np.zeros(md_out.size, dtype=bool)
    pairs = []
    for k in np.argsort(dist, kind="stable"):
        a, b = i[k], o[k]
        if not used_in[a] and not used_out[b]:
            used_in[a] = used_out[b] = True
            pairs.append((a, b))
    return np.array(sorted(pairs), dtype=np.intp).reshape(-1, 2)


def compare_runs(inrun: pa.Table, outrun: pa.Table, options: GateOptions) -> pa.Table:
    """The paired stations of two runs of one tool as a :class:`RunComparison`; azimuths in
    the in-run's north reference (the out-run must use the same)."""
    md_in = inrun.column("md").to_numpy().astype(float)
    md_out = outrun.column("md").to_numpy().astype(float)
    pairs = pair_stations(md_in, md_out, options.pair_window)
    i, o = pairs[:, 0], pairs[:, 1]
    inc_in = inrun.column("inc").to_numpy().astype(float)[i]
    inc_out = outrun.column("inc").to_numpy().astype(float)[o]
    azi_in = inrun.column("azi").to_numpy().astype(float)[i]
    azi_out = outrun.column("azi").to_numpy().astype(float)[o]
    inc_diff = inc_in - inc_out
    azi_diff = (azi_in - azi_out + 180.0) % 360.0 - 180.0
    low = (inc_in + inc_out) / 2 < options.low_inclination
    azi_tol = np.where(low, options.azi_tolerance_low, options.azi_tolerance)
    md_diff = md_in[i] - md_out[o]
    azi_ok = np.isnan(azi_diff) | (np.abs(azi_diff) <= azi_tol)
    passed = (
        (np.abs(inc_diff) <= options.inc_tolerance)
        & azi_ok
        & (np.abs(md_diff) <= options.depth_tolerance)
    )
    return RunComparison.compiled().make_table(
        {
            "station": i.astype(np.int64),
            "md": md_in[i],
            "md_out": md_out[o],
            "md_diff": md_diff,
            "inc_in": inc_in,
            "inc_out": inc_out,
            "inc_diff": inc_diff,
            "azi_in": azi_in,
            "azi_out": azi_out,
            "azi_diff": azi_diff,
            "inc_tolerance": np.full(i.size, options.inc_tolerance),
            "azi_tolerance": azi_tol,
            "passed": passed,
        }
    )


def _worst(values: np.ndarray) -> float:
    finite = np.abs(values[~np.isnan(values)])
    return float(finite.max()) if finite.size else float("nan")


def _gate(gate: str, worst: float, limit: float, unit: str, text: str) -> tuple[Any, ...]:
    """A gate's row: ``worst`` against ``limit`` (NaN: not evaluated)."""
    status = NOT_EVALUATED if np.isnan(worst) else PASS if worst <= limit else FAIL
    return (gate, worst, limit, unit, status, text)


def _coverage(md: np.ndarray, options: GateOptions) -> list[tuple[Any, ...]]:
    """The coverage gate of the stations compared at ``md`` (m, sorted): their largest MD
    gap and where; and when ``options.td`` states a total depth, the TD gate: how far the
    deepest of them is above it."""
    text = "largest MD gap between consecutive stations compared"
    if md.size < 2:
        rows = [_gate("coverage", float("nan"), options.max_gap, "m", f"{text} (fewer than two)")]
    else:
        k = int(np.argmax(np.diff(md)))
        where = f"{text}: {md[k]:.1f} to {md[k + 1]:.1f} m MD"
        rows = [_gate("coverage", float(md[k + 1] - md[k]), options.max_gap, "m", where)]
    if options.td is not None:
        text = f"depth short of the stated TD {options.td:g} m MD: deepest station compared"
        if md.size:
            short, deepest = max(options.td - float(md[-1]), 0.0), f"{md[-1]:.1f} m MD"
        else:
            short, deepest = float("nan"), "none"
        rows.append(_gate("td", short, options.td_tolerance, "m", f"{text} {deepest}"))
    return rows


def acceptance_gates(comparison: pa.Table, options: GateOptions) -> pa.Table:
    """The gates of a :class:`RunComparison` (or a free gyro's in/out QC, which has no
    out-run depths: its depth gate is not evaluated; its tie-in pair is the ``tie_in`` gate,
    not an azimuth one) as an :class:`AcceptanceGates` table."""
    n = comparison.num_rows
    inc_diff = comparison.column("inc_diff").to_numpy(zero_copy_only=False).astype(float)
    azi_diff = comparison.column("azi_diff").to_numpy(zero_copy_only=False).astype(float)
    mean_inc = (
        comparison.column("inc_in").to_numpy(zero_copy_only=False)
        + comparison.column("inc_out").to_numpy(zero_copy_only=False)
    ) / 2
    tie = (
        comparison.column("tie_in").to_numpy(zero_copy_only=False).astype(bool)
        if "tie_in" in comparison.column_names
        else np.zeros(n, dtype=bool)
    )
    low = mean_inc < options.low_inclination
    md_diff = (
        comparison.column("md_diff").to_numpy(zero_copy_only=False).astype(float)
        if "md_diff" in comparison.column_names
        else np.full(n, np.nan)
    )
    rows = [
        (
            "stations",
            float(n),
            float(options.min_stations),
            "stations",
            PASS if n >= options.min_stations else FAIL,
            "stations compared on both runs (at least the limit)",
        )
    ]
    for gate, values, limit, unit, text in (
        ("inclination", inc_diff, options.inc_tolerance, "deg", "largest |in − out| inclination"),
        (
            "azimuth",
            azi_diff[~low & ~tie],
            options.azi_tolerance,
            "deg",
            f"largest |in − out| azimuth at inclination ≥ {options.low_inclination:g}°",
        ),
        (
            "azimuth_low",
            azi_diff[low & ~tie],
            options.azi_tolerance_low,
            "deg",
            f"largest |in − out| azimuth at inclination < {options.low_inclination:g}°",
        ),
        ("depth", md_diff, options.depth_tolerance, "m", "largest |in − out| depth of a pair"),
    ):
        rows.append(_gate(gate, _worst(values), limit, unit, text))
    if "tie_in" in comparison.column_names:
        text = "|in − out| azimuth at the tie-in, at any inclination (it shifts every azimuth)"
        rows.append(_gate("tie_in", _worst(azi_diff[tie]), options.azi_tolerance, "deg", text))
    md = np.sort(comparison.column("md").to_numpy(zero_copy_only=False).astype(float))
    rows.extend(_coverage(md, options))
    names = ("gate", "value", "limit", "unit", "status", "description")
    return AcceptanceGates.compiled().make_table(
        {name: [r[k] for r in rows] for k, name in enumerate(names)}
    )


def acceptance_lines(manifest: Mapping[str, Any]) -> list[str]:
    """What the command line prints of a run's acceptance gates (``run.json``'s
    ``acceptance``): the verdict, then one line per gate."""
    acceptance = manifest.get("acceptance")
    if not acceptance:
        return []
    lines = [f"acceptance: {acceptance['status'].upper()}"]
    for g in acceptance["gates"]:
        value = "—" if g["value"] is None else f"{g['value']:.4g}"
        lines.append(
            f"  {g['stage']}.{g['gate']:<12} {g['status']:<14} {value} (limit {g['limit']:g} "
            f"{g['unit']})"
        )
    return lines


def failed_gates(manifest: Mapping[str, Any]) -> list[str]:
    """``stage.gate`` of every failed gate ``run.json``'s ``acceptance`` records."""
    gates = (manifest.get("acceptance") or {}).get("gates", [])
    return [f"{g['stage']}.{g['gate']}" for g in gates if g["status"] == FAIL]

"""Error-budget study: a West Siberian continuous gyro survey, Monte Carlo, end to end.

Run from the repository root::

    .venv/bin/python benchmarks/study_error_budget.py [--runs N] [--out docs/]

Each run simulates ``examples/plans/west-siberia-700m.yaml`` with the gyro and accelerometer
biases drawn afresh (gyro 0.1 °/h 3σ, accelerometer 4.4e-4 g 3σ, per axis; every other error
term and the servo/torsion model as in the plan's ``mems-vrg`` preset), writes the raw samples
to Parquet and processes them with ``pipelines/continuous-gyro.yaml`` through the runner, the
code ``gyropipe run`` uses. If that pipeline has no ``position_uncertainty`` stage, one is
appended on its trajectory (the model named in the doc). Errors are taken against the
simulator's truth at each output station's time; position errors are relative to the first
station (the survey's tie-in point). Predicted uncertainties are read from the pipeline's own
outputs (``sigma_azi``, ``sigma_inc`` of the continuous stations; NEV covariance of the
uncertainty stage), never recomputed here, so a better model shows up on the next run.

A breakdown repeats the first ``--breakdown-runs`` draws with one group of error terms at a
time (the rest zero) to show where the budget comes from.

Outputs: PNG figures in ``OUT/figures/`` and the numbers section of ``OUT/error-budget.md``
(between the markers; the file is created if missing). Work files go to a temporary directory
unless ``--work`` is given.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
import time
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import matplotlib as mpl

mpl.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pyarrow as pa
import yaml
from matplotlib.patches import Ellipse
from numpy.typing import NDArray

from pipeline.atomic import atomic_path, atomic_write_bytes
from pipeline.earth.frames import OMEGA_EARTH
from pipeline.earth.gravity import STANDARD_GRAVITY
from pipeline.graph import Plan, PlannedStage, build_plan
from pipeline.plugins import load_registry
from pipeline.registry import Registry
from pipeline.runner import run_plan
from pipeline.sim.sensors import (
    PRESETS,
    AccelerometerErrors,
    GyroErrors,
    OdometerErrors,
    TriadErrors,
)
from pipeline.sim.spec import SimulationSpec, ToolChoice, load_simulation
from pipeline.spec import parse_spec
from pipeline.stages.simulation import simulation_tables, well_of_simulation
from pipeline.uncertainty.engine import model_files

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/ is not a package
from error_budget_sets import (
    ACC_BIAS_3SIGMA,
    ERROR_SETS,
    GYRO_BIAS_3SIGMA,
    ErrorSet,
)

Floats = NDArray[np.float64]

ROOT = Path(__file__).resolve().parents[1]
PIPELINE = ROOT / "pipelines" / "continuous-gyro.yaml"
BEGIN = "<!-- BEGIN numbers: written by benchmarks/study_error_budget.py -->"
END = "<!-- END numbers -->"

CONFIDENCE = 0.95
CONTINUOUS_MODEL = "GYRO-NS-CT"  # used when the uncertainty stage is appended and it exists
READS = ("integrate_continuous", "position_uncertainty")  # stages whose outputs the study reads
Z95 = 1.959963984540054  # two-sided 95 % quantile of the normal distribution
K95 = -2.0 * np.log(1.0 - CONFIDENCE)  # χ² quantile, 2 degrees of freedom (closed form)
REPORT_MDS = (200.0, 300.0, 400.0, 500.0, 600.0)  # m, plus the first station and TD
BREAKDOWN_MD = 400.0  # m, the breakdown's mid-run depth (nearest grid point), and TD
GRID_STEP = 5.0  # m, common MD grid the runs are interpolated onto
FIGURE_DPI = 100

ALL = "all terms"
GROUPS = ("gyro bias", "accelerometer bias", "gyro noise", "other terms")
"""Breakdown groups; every error field of the preset belongs to one (see ``group_of``)."""


def group_of(sensor: str, name: str) -> str:
    """The breakdown group of one error field of the tool model."""
    if name == "bias" and sensor in ("gyro", "accelerometer"):
        return f"{sensor} bias"
    if sensor == "gyro" and name in ("noise_density", "bias_instability"):
        return "gyro noise"
    return "other terms"


SENSOR_MODELS: dict[str, type[TriadErrors]] = {
    "gyro": GyroErrors,
    "accelerometer": AccelerometerErrors,
}


@dataclass(frozen=True)
class Draw:
    """The per-run random constants: gyro bias (deg/h) and accelerometer bias (m/s²)."""

    gyro_bias: tuple[float, float, float]
    acc_bias: tuple[float, float, float]

    @classmethod
    def of(cls, seed: int, run: int, errors: ErrorSet) -> Draw:
        rng = np.random.default_rng([seed, run])
        gx, gy, gz = rng.normal(0.0, errors.gyro_bias_3sigma / 3.0, 3)
        ax, ay, az = rng.normal(0.0, errors.acc_bias_3sigma / 3.0 * STANDARD_GRAVITY, 3)
        return cls((float(gx), float(gy), float(gz)), (float(ax), float(ay), float(az)))


def tool_overrides(spec: SimulationSpec, draw: Draw, group: str) -> dict[str, Any]:
    """Overrides of the plan's preset: the drawn biases, and with a breakdown ``group`` every
    error field outside that group set to its zero default."""
    preset = PRESETS[spec.tool.preset].model_dump()
    out: dict[str, Any] = dict(spec.tool.overrides)
    for sensor, model in SENSOR_MODELS.items():
        values = {**preset[sensor], **spec.tool.overrides.get(sensor, {})}
        values["bias"] = draw.gyro_bias if sensor == "gyro" else draw.acc_bias
        for name in list(values):
            if name == "correlation_time" or group in (ALL, group_of(sensor, name)):
                continue
            values[name] = model.model_fields[name].default
        out[sensor] = values
    if group not in (ALL, "other terms"):
        out["odometer"] = OdometerErrors().model_dump()
    return out


def pipeline_plan(
    pipeline: Path, registry: Registry, stage_params: dict[str, dict[str, Any]]
) -> tuple[Plan, str]:
    """The public pipeline cut to the stages the study reads and their upstream (exports and
    reports are sinks that cannot change the numbers, and a PDF report costs seconds per run),
    with a ``position_uncertainty`` stage appended on its trajectory if it has none and the
    error set's ``stage_params`` (by stage kind) set; returns the plan and a note saying
    which."""
    raw = yaml.safe_load(pipeline.read_text(encoding="utf-8"))
    stages: list[dict[str, Any]] = raw["stages"]
    note = f"`{rel(pipeline)}`"
    for stage in stages:
        changed = stage_params.get(stage.get("uses", ""), {})
        if changed:
            stage["with"] = {**(stage.get("with") or {}), **changed}
            shown = {k: v for k, v in changed.items() if not k.startswith(("gyro_", "acc_", "odo"))}
            note += f" with {stage['id']}: {shown or ''}".rstrip(": ")
            if len(shown) < len(changed):
                note += " and the tool's error magnitudes for its predicted σ"
    if not any(stage.get("uses") == "position_uncertainty" for stage in stages):
        model = CONTINUOUS_MODEL if CONTINUOUS_MODEL in model_files() else "GYRO-NS"
        mc = [stage for stage in stages if stage.get("uses") == "minimum_curvature"]
        if len(mc) != 1:
            sys.exit(f"{pipeline}: expected one minimum_curvature stage for the uncertainty")
        stages.append(
            {
                "id": "uncertainty",
                "uses": "position_uncertainty",
                "inputs": {"trajectory": f"{mc[0]['id']}.trajectory"},
                "with": {"confidence": CONFIDENCE, "model": model},
            }
        )
        note += (
            f" plus a `position_uncertainty` stage (model {model}, confidence {CONFIDENCE}, "
            "other parameters default) on its trajectory, since the pipeline has none yet"
        )
    targets = [s["id"] for s in stages if s.get("uses") in READS]
    keep = upstream(stages, targets)
    raw["stages"] = [stage for stage in stages if stage["id"] in keep]
    skipped = [stage["id"] for stage in stages if stage["id"] not in keep]
    if skipped:
        note += f"; its output-only stages ({', '.join(skipped)}) are skipped"
    text = yaml.safe_dump(raw, sort_keys=False, allow_unicode=True)
    return build_plan(parse_spec(text, f"{pipeline} (study subset)"), registry), note


def upstream(stages: Sequence[dict[str, Any]], targets: Iterable[str]) -> set[str]:
    """Ids of the ``targets`` and of every stage they take inputs from, transitively."""
    by_id = {stage["id"]: stage for stage in stages}
    keep: set[str] = set()
    todo = list(targets)
    while todo:
        sid = todo.pop()
        if sid not in keep:
            keep.add(sid)
            todo += [str(src).split(".")[0] for src in (by_id[sid].get("inputs") or {}).values()]
    return keep


def rel(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def stage_using(plan: Plan, uses: str) -> PlannedStage:
    found = [s for s in plan.stages if s.uses == uses]
    if len(found) != 1:
        sys.exit(f"pipeline {plan.file}: expected one {uses!r} stage, found {len(found)}")
    return found[0]


def col(table: pa.Table, name: str) -> Floats:
    return np.asarray(table.column(name).to_numpy(zero_copy_only=False), dtype=np.float64)


def wrap180(angle: Floats) -> Floats:
    wrapped: Floats = (angle + 180.0) % 360.0 - 180.0
    return wrapped


@dataclass
class RunErrors:
    """One run at its output stations: MD (m), errors and the pipeline's predictions."""

    md: Floats
    azi_err: Floats  # deg
    inc_err: Floats  # deg
    horiz: Floats  # (n, 2) m, north and east error relative to the first station
    sigma_azi: Floats  # deg, predicted 1σ
    sigma_inc: Floats  # deg, predicted 1σ
    cov: Floats  # (n, 2, 2) m², predicted horizontal covariance


def run_once(
    spec: SimulationSpec, plan: Plan, registry: Registry, work: Path
) -> tuple[RunErrors, float]:
    """Simulate, write the samples, run the pipeline; errors against the truth and the
    pipeline's end-stop misclosure (deg)."""
    tables = simulation_tables(spec)
    writer = registry.writers["parquet"][0]
    samples = work / "samples.parquet"
    with atomic_path(samples) as tmp:
        writer.write(tables["samples"], tmp, well_of_simulation(spec))
    result = run_plan(plan, registry, inputs={"samples": samples}, out_dir=work / "out")
    cont = stage_using(plan, "integrate_continuous").id
    unc = stage_using(plan, "position_uncertainty").id
    stations = result.tables[(cont, "stations")]
    traj = result.tables[(unc, "trajectory")]
    truth = tables["truth"]
    t_true = col(truth, "time")
    t = col(stations, "time")
    if not np.allclose(col(stations, "md"), col(traj, "md")):
        sys.exit("trajectory stations differ from the continuous stations")

    def true_at(name: str) -> Floats:
        values: Floats = np.interp(t, t_true, col(truth, name))
        return values

    est = np.stack([col(traj, "north"), col(traj, "east")], axis=-1)
    ref = np.stack([true_at("north"), true_at("east")], axis=-1)
    cov = np.empty((t.size, 2, 2))
    cov[:, 0, 0], cov[:, 1, 1] = col(traj, "cov_nn"), col(traj, "cov_ee")
    cov[:, 0, 1] = cov[:, 1, 0] = col(traj, "cov_ne")
    misclosure = float((stations.schema.metadata or {}).get(b"misclosure_deg", b"nan"))
    return RunErrors(
        md=col(stations, "md"),
        azi_err=wrap180(col(stations, "azi") - true_at("azi")),
        inc_err=col(stations, "inc") - true_at("inc"),
        horiz=(est - est[0]) - (ref - ref[0]),
        sigma_azi=col(stations, "sigma_azi"),
        sigma_inc=col(stations, "sigma_inc"),
        cov=cov,
    ), misclosure


@dataclass
class Ensemble:
    """Runs of one configuration on a common MD grid; the last grid point is TD (each run's
    last station, the end stop)."""

    label: str
    grid: Floats
    azi_err: list[Floats] = field(default_factory=list)
    inc_err: list[Floats] = field(default_factory=list)
    horiz: list[Floats] = field(default_factory=list)
    sigma_azi: list[Floats] = field(default_factory=list)
    sigma_inc: list[Floats] = field(default_factory=list)
    cov: list[Floats] = field(default_factory=list)
    misclosure: list[float] = field(default_factory=list)
    td: list[float] = field(default_factory=list)

    def add(self, run: RunErrors, misclosure: float) -> None:
        x = self.grid[:-1]

        def on_grid(values: Floats) -> Floats:
            flat = values.reshape(values.shape[0], -1)
            inner = np.stack([np.interp(x, run.md, v) for v in flat.T], axis=-1)
            out: Floats = np.concatenate([inner, flat[-1:]]).reshape(
                (self.grid.size, *values.shape[1:])
            )
            return out

        self.azi_err.append(on_grid(run.azi_err))
        self.inc_err.append(on_grid(run.inc_err))
        self.horiz.append(on_grid(run.horiz))
        self.sigma_azi.append(on_grid(run.sigma_azi))
        self.sigma_inc.append(on_grid(run.sigma_inc))
        self.cov.append(on_grid(run.cov))
        self.misclosure.append(misclosure)
        self.td.append(float(run.md[-1]))

    def arrays(self) -> dict[str, Floats]:
        return {
            "azi": np.array(self.azi_err),
            "inc": np.array(self.inc_err),
            "horiz": np.array(self.horiz),
            "sigma_azi": np.array(self.sigma_azi),
            "sigma_inc": np.array(self.sigma_inc),
            "cov": np.array(self.cov),
        }


def rms(x: Floats, axis: int = 0) -> Floats:
    out: Floats = np.sqrt(np.mean(np.square(x), axis=axis))
    return out


def p95(x: Floats, axis: int = 0) -> Floats:
    out: Floats = np.percentile(np.abs(x), 95.0, axis=axis)
    return out


def mahalanobis2(horiz: Floats, cov: Floats) -> Floats:
    """d² = eᵀ C⁻¹ e per run and grid point (NaN where C is singular, e.g. the tie-in)."""
    det = cov[..., 0, 0] * cov[..., 1, 1] - cov[..., 0, 1] ** 2
    n, e = horiz[..., 0], horiz[..., 1]
    num = cov[..., 1, 1] * n * n - 2 * cov[..., 0, 1] * n * e + cov[..., 0, 0] * e * e
    with np.errstate(divide="ignore", invalid="ignore"):
        d2: Floats = np.where(det > 0, num / det, np.nan)
    return d2


def simulate_ensemble(
    label: str,
    group: str,
    runs: int,
    seed: int,
    error_set: ErrorSet,
    pipeline: Path,
    grid: Floats,
    work: Path,
    jobs: int = 1,
) -> Ensemble:
    """``runs`` runs of one error set (and breakdown ``group``), in ``jobs`` processes; the
    results do not depend on ``jobs`` (each run has its own draws and seed)."""
    base = load_simulation(error_set.plan)
    ensemble = Ensemble(label, grid)
    started = time.perf_counter()
    tasks = []
    for k in range(runs):
        draw = Draw.of(seed, k, error_set)
        tool = ToolChoice(preset=base.tool.preset, overrides=tool_overrides(base, draw, group))
        spec = base.model_copy(update={"tool": tool, "seed": seed * 100_000 + k})
        tasks.append((spec, pipeline, error_set.stage_params, work / f"run-{k % max(jobs, 1)}"))
    with ProcessPoolExecutor(jobs) if jobs > 1 else nullcontext() as pool:
        done = pool.map(processed_run, tasks) if pool is not None else map(processed_run, tasks)
        for k, (errors, misclosure) in enumerate(done):
            ensemble.add(errors, misclosure)
            if (k + 1) % 10 == 0 or k + 1 == runs:
                rate = (time.perf_counter() - started) / (k + 1)
                print(f"  {label}: {k + 1}/{runs} runs ({rate:.1f} s/run)", flush=True)
    return ensemble


_PLANS: dict[str, tuple[Plan, Registry]] = {}
"""Per process: the study's pipeline plan of each (pipeline, stage parameters)."""


def processed_run(
    task: tuple[SimulationSpec, Path, dict[str, Any], Path],
) -> tuple[RunErrors, float]:
    """One run (:func:`run_once`) with this process's plan of the pipeline."""
    spec, pipeline, stage_params, work = task
    key = f"{pipeline}|{sorted(stage_params.items())}"
    if key not in _PLANS:
        registry = load_registry()
        _PLANS[key] = (pipeline_plan(pipeline, registry, stage_params)[0], registry)
    plan, registry = _PLANS[key]
    work.mkdir(parents=True, exist_ok=True)
    return run_once(spec, plan, registry, work)


def stop_sanity(latitude: float) -> dict[str, float]:
    """The analytic magnitudes quoted in the doc (deg)."""
    horiz_rate = np.degrees(OMEGA_EARTH) * 3600.0 * np.cos(np.radians(latitude))  # deg/h
    return {
        "earth_h": horiz_rate,
        "azi_3s": np.degrees(np.radians(GYRO_BIAS_3SIGMA) / np.radians(horiz_rate)),
        "azi_1s": np.degrees(np.radians(GYRO_BIAS_3SIGMA / 3) / np.radians(horiz_rate)),
        "inc_3s": np.degrees(ACC_BIAS_3SIGMA),
        "inc_1s": np.degrees(ACC_BIAS_3SIGMA / 3),
    }


def drift_expectation(spec: SimulationSpec, errors: ErrorSet, md_to: float) -> dict[str, float]:
    """1σ errors at ``md_to`` of a run integrated from its start stop with no closure, from
    the two constant errors alone (the paper's Eq. 20, constant speed, start stop exact):
    the gyro bias σ_b integrated as ΔȦ = −b/sin I, and the accelerometer bias σ_a across the
    apsidal plane, whose toolface error b/(g sin I) times İ gives ΔA = σ_a (cot I₀ − cot I).
    Azimuth in deg, lateral position in m, the integral ∫dt/sin I in h."""
    survey = spec.survey
    start = getattr(survey, "start_md", None) or spec.path().start_md
    md = np.linspace(start, md_to, 4001)
    inc = spec.path().evaluate(md).inc
    hours = np.concatenate(
        [[0.0], np.cumsum(np.diff(md) * 0.5 * (1 / np.sin(inc[1:]) + 1 / np.sin(inc[:-1])))]
    )
    hours /= getattr(survey, "speed", 1.0) * 3600.0
    gyro = np.radians(errors.gyro_bias_3sigma / 3.0) * hours  # rad
    acc = errors.acc_bias_3sigma / 3.0 * (1 / np.tan(inc[0]) - 1 / np.tan(inc))  # rad

    def lateral(azi: Floats) -> float:
        f = azi * np.sin(inc)
        return float(np.sum(np.diff(md) * 0.5 * (f[1:] + f[:-1])))

    out = {
        "hours": float(hours[-1]),
        "azi_gyro": float(np.degrees(gyro[-1])),
        "azi_acc": float(np.degrees(acc[-1])),
        "lat_gyro": lateral(gyro),
        "lat_acc": lateral(acc),
    }
    out["azi"] = float(np.hypot(out["azi_gyro"], out["azi_acc"]))
    out["lat"] = float(np.hypot(out["lat_gyro"], out["lat_acc"]))
    return out


def expectation_text(res: SetResult) -> str:
    """The analytic expectation of an error set a paper reports, beside its bound."""
    bound = res.errors.bound
    assert bound is not None
    md = min(bound.md, float(res.ens.grid[-1]))
    x = drift_expectation(res.spec, res.errors, md)
    return (
        f"Analytic expectation at {md:g} m (constant errors only, no closure, 1σ): the gyro "
        f"bias ({res.errors.gyro_bias_3sigma / 3:.3f} °/h) integrated over ∫dt/sin I = "
        f"{x['hours']:.3f} h gives {x['azi_gyro']:.3f}° and {x['lat_gyro']:.2f} m; the "
        f"accelerometer bias ({res.errors.acc_bias_3sigma / 3:.2e} g) across the apsidal plane, "
        f"(cot I₀ − cot I)·b/g, gives {x['azi_acc']:.3f}° and {x['lat_acc']:.2f} m; together "
        f"{x['azi']:.3f}° and {x['lat']:.2f} m, 3σ {3 * x['azi']:.2f}° and {3 * x['lat']:.2f} m. "
        f"The paper reports at most {bound.azimuth:g}° and {bound.horizontal:g} m ({bound.source})."
    )


# ---------------------------------------------------------------- figures


def figure_azimuth(ens: Ensemble, sanity: dict[str, float], path: Path) -> None:
    a = ens.arrays()
    x, err, sig = ens.grid, a["azi"], np.mean(a["sigma_azi"], axis=0)
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for run in err[:50]:
        ax.plot(x, run, color="0.75", lw=0.6)
    ax.fill_between(x, -sig, sig, color="tab:blue", alpha=0.15, label="predicted ±1σ (sigma_azi)")
    ax.plot(x, 1.96 * sig, "--", color="tab:blue", lw=1, label="predicted ±1.96σ")
    ax.plot(x, -1.96 * sig, "--", color="tab:blue", lw=1)
    ax.plot(x, rms(err), color="k", lw=1.8, label="measured RMS")
    ax.plot(x, p95(err), ":", color="k", lw=1.8, label="measured 95th pct of |error|")
    ax.axhline(sanity["azi_1s"], color="tab:red", lw=0.8)
    ax.axhline(-sanity["azi_1s"], color="tab:red", lw=0.8)
    ax.text(
        x[1],
        sanity["azi_1s"],
        " b/(Ω cos φ), b = 0.033 °/h (1σ): unremoved-bias stop error",
        color="tab:red",
        fontsize=7,
        va="bottom",
    )
    ax.set(
        xlabel="MD, m",
        ylabel="azimuth error, deg (true north)",
        title=f"Azimuth error, {len(err)} runs (grey: first 50)",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower left", ncol=2)
    save(fig, path)


def figure_horizontal(ens: Ensemble, path: Path) -> None:
    a = ens.arrays()
    x = ens.grid
    dist = np.hypot(a["horiz"][..., 0], a["horiz"][..., 1])
    cov = np.mean(a["cov"], axis=0)
    sigma_h = np.sqrt(cov[:, 0, 0] + cov[:, 1, 1])
    major95 = np.sqrt(K95 * np.linalg.eigvalsh(cov)[:, 1])
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    for run in dist[:50]:
        ax.plot(x, run, color="0.75", lw=0.6)
    ax.plot(x, rms(dist), color="k", lw=1.8, label="measured RMS")
    ax.plot(x, p95(dist), ":", color="k", lw=1.8, label="measured 95th pct")
    ax.plot(x, sigma_h, color="tab:blue", lw=1.5, label="predicted RMS √(σN² + σE²)")
    ax.plot(x, major95, "--", color="tab:blue", lw=1.2, label="predicted 95 % semi-major axis")
    ax.set(
        xlabel="MD, m",
        ylabel="horizontal position error, m",
        title=f"Horizontal position error from the tie-in, {len(dist)} runs (grey: first 50)",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    save(fig, path)


def figure_td_scatter(ens: Ensemble, path: Path) -> None:
    a = ens.arrays()
    e = a["horiz"][:, -1, :]  # (runs, 2) north, east at TD
    cov_pred = np.mean(a["cov"][:, -1], axis=0)
    fig, ax = plt.subplots(figsize=(5.2, 5.0))
    ax.scatter(e[:, 1], e[:, 0], s=9, color="k", label="runs (east, north)")
    scale = np.sqrt(K95)
    for cov, colour, label in (
        (cov_pred, "tab:blue", "predicted 95 %"),
        (np.cov(e.T) if len(e) > 2 else None, "tab:orange", "sample covariance 95 %"),
    ):
        if cov is None:
            continue
        vals, vecs = np.linalg.eigh(cov[::-1, ::-1])  # (east, north) order for the plot
        angle = np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1]))
        w, h = 2 * scale * np.sqrt(np.maximum(vals[::-1], 0.0))
        ax.add_patch(
            Ellipse((0, 0), w, h, angle=angle, fill=False, color=colour, lw=1.5, label=label)
        )
    lim = 1.15 * max(np.abs(e).max(), scale * np.sqrt(np.linalg.eigvalsh(cov_pred)[-1]))
    ax.set(xlim=(-lim, lim), ylim=(-lim, lim), aspect="equal")
    ax.set(xlabel="east error, m", ylabel="north error, m")
    ax.set_title(f"Horizontal error at TD ({np.mean(ens.td):.0f} m), {len(e)} runs")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    save(fig, path)


def figure_breakdown(all_terms: Ensemble, groups: Sequence[Ensemble], path: Path) -> None:
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.0, 3.8))
    for ens in (all_terms, *groups):
        a = ens.arrays()
        style = {"color": "k", "lw": 2.0} if ens is all_terms else {"lw": 1.2}
        ax1.plot(ens.grid, rms(a["azi"]), label=ens.label, **style)
        dist = np.hypot(a["horiz"][..., 0], a["horiz"][..., 1])
        ax2.plot(ens.grid, rms(dist), label=ens.label, **style)
    ax1.set(xlabel="MD, m", ylabel="RMS azimuth error, deg", title="Azimuth")
    ax2.set(xlabel="MD, m", ylabel="RMS horizontal error, m", title="Horizontal position")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.set_yscale("log")
        ax.set_ylim(bottom=1e-3)  # noise-free groups are exactly 0 at the stops
    ax1.legend(fontsize=7)
    fig.tight_layout()
    save(fig, path)


def save(fig: Any, path: Path) -> None:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=FIGURE_DPI, bbox_inches="tight", format="png")
    plt.close(fig)


# ---------------------------------------------------------------- numbers


def md_rows(ens: Ensemble) -> list[tuple[str, int]]:
    """(label, grid index) of the reported depths: first station, REPORT_MDS, TD."""
    rows = [(f"{ens.grid[0]:.0f} (start stop)", 0)]
    inner = ens.grid[:-1]
    rows += [
        (f"{md:.0f}", int(np.argmin(np.abs(inner - md))))
        for md in REPORT_MDS
        if inner[0] < md < inner[-1]
    ]
    rows.append((f"TD {np.mean(ens.td):.1f} (end stop)", ens.grid.size - 1))
    return rows


def table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> list[str]:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return lines


def angle_rows(ens: Ensemble, err: Floats, sig: Floats, digits: int) -> list[list[str]]:
    """Rows of an angle-error table (deg): mean, RMS, 95th pct, predicted σ, share inside."""
    rows = []
    for label, i in md_rows(ens):
        inside = np.mean(np.abs(err[:, i]) <= Z95 * sig[:, i]) * 100
        values = (np.mean(err[:, i]), rms(err[:, i]), p95(err[:, i]), np.mean(sig[:, i]))
        rows.append([label, *(f"{v:+.{digits}f}" for v in values[:1])])
        rows[-1] += [f"{v:.{digits}f}" for v in values[1:]] + [f"{inside:.0f} %"]
    return rows


def horizontal_rows(ens: Ensemble) -> list[list[str]]:
    """Rows of the horizontal-error table (m) at the reported depths after the tie-in."""
    a = ens.arrays()
    dist = np.hypot(a["horiz"][..., 0], a["horiz"][..., 1])
    d2 = mahalanobis2(a["horiz"], a["cov"])
    rows = []
    for label, i in md_rows(ens)[1:]:
        cov = np.mean(a["cov"][:, i], axis=0)
        major = np.sqrt(K95 * np.linalg.eigvalsh(cov)[-1])
        inside = np.mean(d2[:, i] <= K95) * 100
        values = (np.mean(dist[:, i]), rms(dist[:, i]), p95(dist[:, i]))
        rows.append([label, *(f"{v:.2f}" for v in values)])
        rows[-1] += [f"{np.sqrt(cov[0, 0] + cov[1, 1]):.2f}", f"{major:.2f}", f"{inside:.0f} %"]
    return rows


def breakdown_index(ens: Ensemble) -> int:
    return int(np.argmin(np.abs(ens.grid[:-1] - BREAKDOWN_MD)))


def breakdown_rows(ens: Ensemble, groups: Sequence[Ensemble]) -> list[list[str]]:
    """RMS azimuth and horizontal errors at 400 m and TD per group, their root-sum-square
    and the all-terms runs with the same draws."""
    k = len(groups[0].azi_err)
    mid = breakdown_index(ens)

    def rms_at(e: Ensemble) -> Floats:
        a = e.arrays()
        dist = np.hypot(a["horiz"][:k, :, 0], a["horiz"][:k, :, 1])
        return np.array([*rms(a["azi"][:k, [mid, -1]]), *rms(dist[:, [mid, -1]])])

    def row(label: str, v: Floats) -> list[str]:
        return [label, f"{v[0]:.3f}", f"{v[1]:.3f}", f"{v[2]:.2f}", f"{v[3]:.2f}"]

    values = [rms_at(g) for g in groups]
    rows = [row(g.label, v) for g, v in zip(groups, values, strict=True)]
    rows.append(row("root-sum-square of the groups", np.sqrt(np.sum(np.square(values), axis=0))))
    rows.append(row(f"{ALL} (same {k} runs)", rms_at(ens)))
    return rows


def set_section(res: SetResult) -> str:
    """The doc's numbers of one error set."""
    ens, groups, meta, sanity = res.ens, res.groups, res.meta, res.sanity
    a = ens.arrays()
    misc = np.array(ens.misclosure)
    e_td = a["horiz"][:, -1]
    spread = np.sqrt(np.mean(np.sum((e_td - np.mean(e_td, axis=0)) ** 2, axis=1)))
    angle_header = ["MD, m", "mean", "RMS", "95th pct", "predicted σ", "inside 1.96σ"]
    closed = res.errors.stage_params.get("integrate_continuous", {}).get("closure", True)
    out = [
        "",
        f"### Error set `{res.errors.name}`: {res.errors.title}",
        "",
        f"Runs: {len(ens.azi_err)} (seed {meta['seed']}), plan `{meta['plan']}`, pipeline "
        f"{meta['pipeline']}. Predicted σ_A and σ_I: {meta['sigma_model']}. Predicted position "
        f"covariance: {meta['cov_model']}.",
        "",
        f"Analytic check at φ = {meta['latitude']}°: Ω cos φ = {sanity['earth_h']:.2f} °/h, so a "
        f"gyro bias left in a compassing stop gives b/(Ω cos φ) = {sanity['azi_3s']:.2f}° "
        f"(3σ, 0.1 °/h) or {sanity['azi_1s']:.2f}° (1σ); the accelerometer bias gives "
        f"≈ {sanity['inc_3s']:.3f}° (3σ) / {sanity['inc_1s']:.4f}° (1σ) of inclination.",
        "",
        f"End-stop misclosure of the integrated azimuth "
        f"({'removed linearly in time' if closed else 'not removed: no closure'}): mean "
        f"{np.nanmean(misc):+.2f}°, RMS {rms(misc[np.isfinite(misc)]):.2f}°.",
        "",
        "**Azimuth error** (deg, estimate − truth; predicted σ: mean over runs of the "
        "continuous stations' `sigma_azi`; inside: share of runs with |error| ≤ 1.96σ):",
        "",
        *table(angle_header, angle_rows(ens, a["azi"], a["sigma_azi"], 3)),
        "",
        "**Inclination error** (deg; predicted σ: the stations' `sigma_inc`):",
        "",
        *table(angle_header, angle_rows(ens, a["inc"], a["sigma_inc"], 4)),
        "",
        "**Horizontal position error** (m, from the tie-in at the first station; predicted: "
        f"√(σN² + σE²) and the {CONFIDENCE:.0%} ellipse's semi-major axis, from the mean "
        f"covariance; inside: share of runs within their predicted {CONFIDENCE:.0%} ellipse, "
        f"d² ≤ {K95:.2f}):",
        "",
        *table(
            (
                "MD, m",
                "mean",
                "RMS",
                "95th pct",
                "predicted RMS",
                "predicted 95 % semi-major",
                "inside",
            ),
            horizontal_rows(ens),
        ),
        "",
        f"At TD the mean error vector is N {np.mean(e_td[:, 0]):+.2f} m, "
        f"E {np.mean(e_td[:, 1]):+.2f} m, with a spread (RMS about the mean) of {spread:.2f} m.",
    ]
    if groups:
        mid_md = ens.grid[breakdown_index(ens)]
        out += [
            "",
            f"**Breakdown** ({len(groups[0].azi_err)} runs each with the draws and seeds of the "
            "first runs above, one group of error terms on at a time; RMS values):",
            "",
            *table(
                (
                    "error terms",
                    f"azimuth @ {mid_md:.0f} m, °",
                    "azimuth @ TD, °",
                    f"horiz. @ {mid_md:.0f} m, m",
                    "horiz. @ TD, m",
                ),
                breakdown_rows(ens, groups),
            ),
        ]
    if res.errors.bound is not None:
        out += ["", expectation_text(res)]
    return "\n".join(out)


def comparison_section(results: Sequence[SetResult]) -> str:
    """Side by side at the paper's depth: RMS, largest over runs and 3σ of each error set,
    and the bound the paper reports."""
    bound = next((r.errors.bound for r in results if r.errors.bound is not None), None)
    target = bound.md if bound is not None else float(results[0].ens.grid[-1])
    rows = []
    for res in results:
        a = res.ens.arrays()
        i = int(np.argmin(np.abs(res.ens.grid - target)))
        azi, inc, e = a["azi"][:, i], a["inc"][:, i], a["horiz"][:, i]
        dist = np.hypot(e[:, 0], e[:, 1])
        major = (
            np.sqrt(np.linalg.eigvalsh(np.atleast_2d(np.cov(e.T)))[-1]) if len(e) > 2 else np.nan
        )
        rows.append(
            [
                f"`{res.errors.name}` ({len(azi)} runs, {res.ens.grid[i]:.0f} m)",
                f"{rms(azi):.3f}",
                f"{np.max(np.abs(azi)):.3f}",
                f"{3 * rms(azi):.3f}",
                f"{rms(dist):.2f}",
                f"{np.max(dist):.2f}",
                f"{3 * major:.2f}",
                f"{rms(inc):.4f}",
                f"{np.max(np.abs(inc)):.4f}",
            ]
        )
    if bound is not None:
        rows.append(
            [
                "paper (reported bound)",
                *("", f"≤ {bound.azimuth:g}", ""),
                *("", f"≤ {bound.horizontal:g}", ""),
                *("", ""),
            ]
        )
    header = (
        "error set",
        "azimuth RMS, °",
        "azimuth max, °",
        "azimuth 3σ, °",
        "horiz. RMS, m",
        "horiz. max, m",
        "horiz. 3σ (major axis), m",
        "incl. RMS, °",
        "incl. max, °",
    )
    return "\n".join(
        [
            "",
            f"### Side by side at {target:g} m",
            "",
            "**Error sets compared** (estimate − truth at the station nearest "
            f"{target:g} m; max: largest |error| over the runs; 3σ: three times the RMS, and for "
            "the horizontal error three times the σ of the sample covariance's major axis):",
            "",
            *table(header, rows),
        ]
    )


def write_doc(doc: Path, section: str) -> None:
    text = (
        doc.read_text(encoding="utf-8") if doc.exists() else f"# Error budget\n\n{BEGIN}\n{END}\n"
    )
    start, stop = text.find(BEGIN), text.find(END)
    if start < 0 or stop < start:
        sys.exit(f"{doc}: the markers {BEGIN!r} … {END!r} are missing")
    new = text[:start] + section + text[stop + len(END) :]
    atomic_write_bytes(doc, new.encode("utf-8"))


def sigma_model_note() -> str:
    """Which code produced the continuous stations' sigma_azi (the module named in the doc)."""
    if importlib.util.find_spec("pipeline.continuous.sigma") is not None:
        import pipeline.continuous.sigma as sigma

        first = (sigma.__doc__ or "").strip().splitlines()[0] if sigma.__doc__ else ""
        return f"`pipeline.continuous.sigma` ({first.rstrip('.')})"
    return (
        "`pipeline.continuous.integrate` (the two stops' σ interpolated linearly in time and "
        "combined in quadrature; no gyro drift or random walk during the run)"
    )


@dataclass
class SetResult:
    """One error set's ensembles and what the doc says about them."""

    errors: ErrorSet
    spec: SimulationSpec
    ens: Ensemble
    groups: list[Ensemble]
    meta: dict[str, str]
    sanity: dict[str, float]


def run_set(
    errors: ErrorSet, args: argparse.Namespace, registry: Registry, work: Path
) -> SetResult:
    """Simulate and process one error set's runs (and its breakdown, if it has one)."""
    plan, pipeline_note = pipeline_plan(args.pipeline, registry, errors.stage_params)
    spec = load_simulation(errors.plan)
    survey = spec.survey
    start = getattr(survey, "start_md", None) or spec.path().start_md
    end = getattr(survey, "end_md", None)
    if end is None:
        sys.exit(f"{errors.plan}: the study needs a continuous survey with an end_md")
    grid = np.append(np.arange(start, end, GRID_STEP), end)
    unc = stage_using(plan, "position_uncertainty")
    params = unc.params.model_dump()
    meta = {
        "seed": str(args.seed),
        "plan": rel(errors.plan),
        "pipeline": pipeline_note,
        "latitude": f"{spec.site.latitude:g}",
        "sigma_model": sigma_model_note(),
        "cov_model": f"stage `{unc.id}` (`position_uncertainty`), model {params.get('model')}, "
        f"basis {params.get('basis')}",
    }
    print(f"{errors.name} ({spec.name}): {args.runs} runs, pipeline {pipeline_note}")
    common = (args.seed, errors, args.pipeline, grid, work, args.jobs)
    ens = simulate_ensemble(ALL, ALL, args.runs, *common)
    breakdown = GROUPS if errors.breakdown and args.breakdown_runs else ()
    groups = [simulate_ensemble(g, g, args.breakdown_runs, *common) for g in breakdown]
    return SetResult(errors, spec, ens, groups, meta, stop_sanity(spec.site.latitude))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=100, help="Monte Carlo runs (all terms)")
    parser.add_argument(
        "--breakdown-runs",
        type=int,
        default=30,
        help="runs per error-term group for the breakdown (0: none; at most --runs)",
    )
    parser.add_argument(
        "--sets",
        default=",".join(ERROR_SETS),
        help=f"comma-separated error sets (error_budget_sets.py): {', '.join(ERROR_SETS)}",
    )
    parser.add_argument("--out", type=Path, default=ROOT / "docs", help="docs directory")
    parser.add_argument(
        "--plan", type=Path, default=None, help="simulation plan replacing every set's own"
    )
    parser.add_argument("--pipeline", type=Path, default=PIPELINE, help="pipeline YAML")
    parser.add_argument("--seed", type=int, default=1, help="base seed of the draws")
    parser.add_argument("--work", type=Path, default=None, help="keep work files here")
    parser.add_argument("--jobs", type=int, default=1, help="processes running the runs")
    args = parser.parse_args(argv)
    if args.runs < 1 or not 0 <= args.breakdown_runs <= args.runs:
        parser.error("need --runs ≥ 1 and 0 ≤ --breakdown-runs ≤ --runs")
    names = [n.strip() for n in args.sets.split(",") if n.strip()]
    unknown = [n for n in names if n not in ERROR_SETS]
    if unknown or not names:
        parser.error(f"unknown error set(s) {unknown}; known: {', '.join(ERROR_SETS)}")
    chosen = [ERROR_SETS[n] for n in names]
    if args.plan is not None:
        chosen = [replace(e, plan=args.plan) for e in chosen]

    registry = load_registry()
    with tempfile.TemporaryDirectory(prefix="error-budget-") as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        results = [run_set(errors, args, registry, work) for errors in chosen]

    figures = args.out / "figures"
    for res in results:
        prefix = (
            "error-budget" if res.errors.name == "realistic" else f"error-budget-{res.errors.name}"
        )
        figure_azimuth(res.ens, res.sanity, figures / f"{prefix}-azimuth.png")
        figure_horizontal(res.ens, figures / f"{prefix}-horizontal.png")
        if res.errors.name == "realistic":
            figure_td_scatter(res.ens, figures / f"{prefix}-td-scatter.png")
        if res.groups:
            figure_breakdown(res.ens, res.groups, figures / f"{prefix}-breakdown.png")
    section = "\n".join(
        [
            BEGIN,
            *(set_section(res) for res in results),
            *([comparison_section(results)] if len(results) > 1 or results[0].errors.bound else []),
            "",
            END,
        ]
    )
    write_doc(args.out / "error-budget.md", section)
    print(section)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""An empty table is a legal stage output (fuzz finding: when compassing rejected every
station the run stopped in minimum_curvature with ``IndexError: index 0 is out of bounds``).
Every built-in stage given 0-row tables returns valid empty outputs or raises a
GyropipeError saying which table is empty — never another exception."""

from __future__ import annotations

import datetime as dt
import textwrap
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pyarrow as pa
import pytest

from pipeline.contracts import TableContract
from pipeline.errors import GyropipeError, StageError
from pipeline.graph import build_plan
from pipeline.plugins import load_registry
from pipeline.registry import CheckDef, PluginInfo, Provenance, Registry, StageDef, WriterDef
from pipeline.reporting import ReportDef
from pipeline.runner import run_plan
from pipeline.spec import load_spec
from pipeline.streams import Port, TableStream, as_table
from pipeline.tables import CompassRejects, PositionReadings, RawSamples, Stations, Trajectory
from pipeline.well import WellMetadata
from tests_support import gyropipe_cli

REGISTRY = load_registry()
WELL = WellMetadata(
    well="E-1",
    latitude=61.25,
    longitude=73.4,
    elevation=50.0,
    survey_date="2026-11-21",
    north_reference="true",
    tool_serial="IG50-0417",
)
PARAMS: dict[str, list[dict[str, Any]]] = {  # required params, and variants worth trying
    "check": [{"check": name} for name in sorted(REGISTRY.checks)],
    "write": [{"writer": name} for name in sorted(REGISTRY.writers)],
    "export": [
        {"writer": name} for name, (w, _) in sorted(REGISTRY.writers.items()) if w.write_tables
    ],
    "interpolate_md": [{"spacing": 10.0}, {"md": [5.0]}, {"include_stations": True}],
    "interpolate_tvd": [{"tvd": [100.0]}],
    "north_reference": [{"target": "grid", "convergence": 1.0, "declination": 2.0}],
    "correct_drift": [{}, {"source": "given", "drift_rate": 1.0}],
    "clearance": [{"reference_hole_diameter": 0.3}],
}
ANY_TABLE: dict[tuple[str, str], type[TableContract]] = {
    ("export", "readings"): PositionReadings,
    ("export", "series"): RawSamples,
    ("export", "rejects"): CompassRejects,
}
"""What an ``AnyTable`` port is given (``write`` and ``check``: a trajectory; raw samples
for the mcap writer, which writes time series only)."""


class Context:
    """A StageContext writing into ``out``."""

    def __init__(self, out: Path) -> None:
        self.stage_id = "stage"
        self.well = WELL
        self.out = out
        self.provenance = Provenance(
            "p", "1", "p.yaml", "0" * 64, "0", {}, {}, dt.datetime.now(dt.UTC), ()
        )

    def input_path(self, name: str) -> Path:
        raise KeyError(name)

    def output_path(self, filename: str) -> Path:
        return self.out / filename

    def update_well(self, found: WellMetadata) -> None:
        pass

    def well_for(self, header: WellMetadata | None) -> WellMetadata:
        return self.well if header is None else self.well.merged(header)

    def read(self, *args: Any, **kwargs: Any) -> Any:
        raise AssertionError("no stage with inputs reads files")

    def writer(self, name: str) -> WriterDef:
        return REGISTRY.writers[name][0]

    def check(self, name: str) -> CheckDef:
        return REGISTRY.checks[name][0]

    def report_parts(self) -> list[tuple[ReportDef, PluginInfo]]:
        return REGISTRY.report_parts()


def empty(contract: type[TableContract]) -> pa.Table:
    """A 0-row table with the contract's full schema (azimuths true north)."""
    return contract.compiled().schema(north_reference="true").empty_table()


def cases() -> list[Any]:
    found = []
    for name, (definition, _) in sorted(REGISTRY.stages.items()):
        if not definition.inputs:
            continue  # readers and simulators: nothing to be empty
        for params in PARAMS.get(name, [{}]):
            label = ",".join(f"{k}={v}" for k, v in params.items())
            found.append(pytest.param(name, params, id=f"{name}[{label}]" if label else name))
    return found


def given(stage: str, port: str, params: dict[str, Any], contract: type[TableContract]) -> pa.Table:
    if stage in ("write", "check"):
        return empty(RawSamples if params.get("writer") == "mcap" else Trajectory)
    return empty(ANY_TABLE.get((stage, port), contract))


def assert_empty_handled(
    definition: StageDef, inputs: Mapping[str, Port], params: dict[str, Any], out: Path
) -> None:
    model = definition.params.model_validate(params, context={"registry": REGISTRY})
    try:
        outputs = definition.func(inputs, model, Context(out))
    except GyropipeError as exc:
        refused: GyropipeError | None = exc
    else:
        refused = None
    if refused is not None:
        assert "has no rows (the stage that produced it gave none)" in str(refused)
        return
    assert set(outputs) == set(definition.outputs)
    for port, table in outputs.items():
        definition.outputs[port].validate_table(as_table(table))


@pytest.mark.parametrize(("stage", "params"), cases())
def test_every_stage_handles_empty_inputs(tmp_path: Path, stage: str, params: dict[str, Any]):
    definition = REGISTRY.stages[stage][0]
    required = {p: c for p, c in definition.inputs.items() if p not in definition.optional_inputs}
    for ports in (required, definition.inputs):
        if not ports:
            continue
        inputs = {port: given(stage, port, params, c) for port, c in ports.items()}
        assert_empty_handled(definition, as_ports(definition, inputs), params, tmp_path)


def as_ports(definition: StageDef, tables: Mapping[str, pa.Table]) -> dict[str, Port]:
    """The tables as the engine gives them: a stream on each streamed input port."""
    return {
        port: TableStream.from_table(t) if port in definition.streamed_inputs else t
        for port, t in tables.items()
    }


def run_stage(name: str, inputs: Mapping[str, pa.Table], **params: Any) -> Mapping[str, pa.Table]:
    definition = REGISTRY.stages[name][0]
    model = definition.params.model_validate(params, context={"registry": REGISTRY})
    outputs = definition.func(as_ports(definition, inputs), model, Context(Path("/nonexistent")))
    return {port: as_table(value) for port, value in outputs.items()}


def test_reports_take_empty_optional_tables(tmp_path: Path):
    """The report's trajectory is real, every optional table wired but empty."""
    from pipeline.sim.calibration import CalibrationPlan, simulate_calibration

    stations = Stations.compiled().make_table(
        {"md": [0.0, 100.0, 200.0], "inc": [0.0, 2.0, 4.0], "azi": [0.0, 30.0, 31.0]},
        north_reference="true",
    )
    trajectory = run_stage("minimum_curvature", {"stations": stations})["trajectory"]
    report = REGISTRY.stages["report"][0]
    inputs = {port: empty(c) for port, c in report.inputs.items()} | {"trajectory": trajectory}
    assert_empty_handled(report, inputs, {"formats": ["html"]}, tmp_path)
    assert (tmp_path / "stage.html").exists()

    readings = simulate_calibration(CalibrationPlan(seed=1))
    calibrated = run_stage("calibrate_drift", {"readings": readings})
    calibration_report = REGISTRY.stages["calibration_report"][0]
    inputs = {**calibrated, "readings": readings.slice(0, 0)}
    assert_empty_handled(calibration_report, inputs, {"formats": ["html"]}, tmp_path)


def empty_stations(inputs: Any, params: Any, ctx: Any) -> dict[str, pa.Table]:
    return {"stations": empty(Stations)}


def test_an_empty_table_flows_down_a_pipeline_until_a_stage_needs_rows(
    tmp_path: Path, registry: Registry, add_stage: Callable[[StageDef], None], write_yaml: Any
):
    add_stage(
        StageDef("tests.nothing", empty_stations, "no stations", outputs={"stations": Stations})
    )
    head = """
        name: empty
        version: "1"
        well: {latitude: 61.25, north_reference: "true"}
        stages:
          - {id: make, uses: tests.nothing}
          - {id: trajectory, uses: minimum_curvature, inputs: {stations: make}}
          - {id: uncertainty, uses: position_uncertainty, inputs: {trajectory: trajectory}}
          - {id: points, uses: interpolate_md, inputs: {trajectory: trajectory},
             with: {spacing: 10}}
          - {id: csv, uses: write, inputs: {table: uncertainty}, with: {writer: csv}}
        """
    path = write_yaml(head)
    result = run_plan(
        build_plan(load_spec(path), registry), registry, inputs={}, out_dir=tmp_path / "ok"
    )
    assert result.tables[("uncertainty", "trajectory")].num_rows == 0
    assert (tmp_path / "ok" / "csv.csv").exists()

    path = write_yaml(
        head + "  - {id: summary, uses: export, inputs: {trajectory: uncertainty}, "
        "with: {writer: json_summary}}\n"
    )
    with pytest.raises(StageError) as caught:
        run_plan(
            build_plan(load_spec(path), registry), registry, inputs={}, out_dir=tmp_path / "bad"
        )
    assert "stage 'summary'" in str(caught.value)
    assert "the trajectory table has no rows (the stage that produced it gave none)" in str(
        caught.value
    )


IDEAL_PLAN = """
    name: ideal
    seed: 1
    site:
      latitude: 61.25
      longitude: 73.4
      elevation: 54.3
      date: 2026-11-21
      magnetic: {total_field: 59731, dip: 78.29, declination: 17.0}
    well:
      sections:
        - {kind: vertical, length: 100}
        - {kind: build, dls: 3.0, inc: 20, azi: 37}
        - {kind: hold, to_md: 600}
    tool: {preset: ideal}
    survey: {mode: point, every: 100, dwell: 7, speed: 5}
    """


def test_compass_rejecting_every_station_says_why(tmp_path: Path):
    """An ideal (noise-free) tool without ``noise_floor``: every station is rejected. The
    run used to end in ``IndexError`` in minimum_curvature, the reason only in the rejects."""
    plan = tmp_path / "ideal.yaml"
    plan.write_text(textwrap.dedent(IDEAL_PLAN).lstrip())
    sim = tmp_path / "sim"
    gyropipe_cli("simulate", str(plan), "--out", str(sim), check=True)
    out = tmp_path / "out"
    result = gyropipe_cli(
        "run",
        "pipelines/point-gyro.yaml",
        "--input",
        str(sim / "samples.parquet"),
        "--out",
        str(out),
        cwd=Path(__file__).resolve().parents[2],
    )
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr and "IndexError" not in result.stderr
    assert (
        "stage 'compass' (compass from plugin builtin.compass 0.1.0) failed: AllRejectedError: "
        "compass rejected all 7 stations, so its stations table would have no rows: 7× a "
        "position's gyro σ is zero (noise-free data?): set noise_floor"
    ) in result.stderr

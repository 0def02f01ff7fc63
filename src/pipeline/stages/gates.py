"""Built-in plugin: the ``acceptance_gates`` stage — an in-run compared with an out-run of a
gyro survey against a client's acceptance criteria (:mod:`pipeline.qc.gates`)."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import pyarrow as pa

from pipeline.drift.tables import InOutQc
from pipeline.hookspecs import hookimpl
from pipeline.provenance import StageSetup
from pipeline.qc.gates import GateOptions, acceptance_gates, compare_runs
from pipeline.qc.tables import RunComparison
from pipeline.registry import StageContext, StageDef
from pipeline.reporting import MethodNote, ReportContext, ReportDef
from pipeline.survey.stations import north_reference_of, survey_offsets
from pipeline.tables import AcceptanceGates, Stations
from pipeline.well import one_well


def gates_stage(
    inputs: Mapping[str, pa.Table], params: GateOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """In-run and out-run stations (of one well, one survey each) → the pairs compared and
    the gates."""
    one_well(inputs)
    for port in ("inrun", "outrun"):
        offsets = survey_offsets(inputs[port])
        if len(offsets) > 2:  # paired by MD alone, stations of two holes would be compared
            names = inputs[port].column("survey").take(offsets[:-1]).to_pylist()
            raise ValueError(
                f"{port}: the table holds {len(names)} surveys ({', '.join(map(repr, names))}); "
                "the gates compare one run with one run: give one survey per port"
            )
    north_in = north_reference_of(inputs["inrun"], "azi")
    north_out = north_reference_of(inputs["outrun"], "azi")
    if north_in != north_out:
        raise ValueError(
            f"the in-run's azimuths are {north_in} north, the out-run's {north_out}: "
            "convert one (north_reference stage) before comparing"
        )
    comparison = compare_runs(inputs["inrun"], inputs["outrun"], params)
    return {"comparison": comparison, "gates": acceptance_gates(comparison, params)}


def free_gyro_gates(
    inputs: Mapping[str, pa.Table], params: GateOptions, ctx: StageContext
) -> dict[str, pa.Table]:
    """A free gyro's in/out QC → the gates (no out-run depths: depth not evaluated)."""
    return {"gates": acceptance_gates(inputs["inout"], params)}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="acceptance_gates",
            func=gates_stage,
            description="Acceptance gates of a gyro survey, in-run against out-run: stations "
            "compared, inclination, azimuth (above and below a low inclination) and depth "
            "agreement, depth coverage (the largest gap) and a stated TD reached, each pass "
            "or fail against configurable limits.",
            inputs={"inrun": Stations, "outrun": Stations},
            outputs={"comparison": RunComparison, "gates": AcceptanceGates},
            params=GateOptions,
        )
    )
    register(
        StageDef(
            name="free_gyro_gates",
            func=free_gyro_gates,
            description="The acceptance gates of a free gyro's drift-corrected in-run/out-run "
            "QC (correct_drift's qc); its depth gate is not evaluated.",
            inputs={"inout": InOutQc},
            outputs={"gates": AcceptanceGates},
            params=GateOptions,
        )
    )


def gates_method(stage: StageSetup, ctx: ReportContext) -> MethodNote:
    """The acceptance criteria in the report."""
    p = dict(stage.params)
    criteria = (
        f"in-run against out-run: inclination within {p.get('inc_tolerance', '?')}°, "
        f"azimuth within {p.get('azi_tolerance', '?')}° at inclination ≥ "
        f"{p.get('low_inclination', '?')}° and {p.get('azi_tolerance_low', '?')}° below, "
        f"depth within {p.get('depth_tolerance', '?')} m, at least "
        f"{p.get('min_stations', '?')} stations, no gap between stations compared over "
        f"{p.get('max_gap', '?')} m"
    )
    if p.get("td") is not None:
        criteria += (
            f", the deepest station compared within {p.get('td_tolerance', '?')} m of the "
            f"stated TD {p['td']} m"
        )
    return MethodNote("Acceptance", criteria)


@hookimpl
def gyropipe_register_report_parts(register: Callable[[ReportDef], None]) -> None:
    register(ReportDef("acceptance_gates", method=gates_method))

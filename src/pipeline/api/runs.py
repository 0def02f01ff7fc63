"""Python API functions over several runs of one well: the definitive survey and the
in-run/out-run acceptance gates (``import pipeline as gp``)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from pipeline.api import stages
from pipeline.api.frames import TableLike, WellLike, like
from pipeline.api.functions import Tables
from pipeline.errors import ParameterError


def definitive_survey(
    runs: Mapping[str, TableLike],
    *,
    run_options: Mapping[str, Mapping[str, Any]] | None = None,
    well: WellLike = None,
    **params: Any,
) -> Tables:
    """One survey of a well from several runs: ``runs`` maps each run's id to its stations
    (top down, at most six); ``run_options`` maps a run id to its ``model`` (error model,
    default GYRO-NS), ``tool`` overrides, ``priority`` (higher wins an overlap) and depth
    range ``md_from``/``md_to`` (m). ``params`` are the stage's: ``overlap`` (priority, upper
    or lower), ``latitude``, ``magnetic``, ``basis``, ``surface_tie``, ``well_by_well``,
    ``confidence``… Returns ``survey`` (stations, positions, NEV covariance m², ellipses,
    run, tool model and source file per station) and ``overlap`` (the stations not listed)."""
    if not isinstance(runs, Mapping):
        raise ParameterError(
            f"definitive_survey: runs: expected a mapping of run id to stations, got {runs!r}"
        )
    options = dict(run_options or {})
    unknown = sorted(set(options) - set(runs))
    if unknown:
        raise ParameterError(f"definitive_survey: run_options for unknown runs {unknown}")
    if not 1 <= len(runs) <= 6:
        raise ParameterError(f"definitive_survey: give 1 to 6 runs; got {len(runs)}")
    ports = {f"run{k}": name for k, name in enumerate(runs, start=1)}
    inputs = {port: runs[name] for port, name in ports.items()}
    specs = {port: {"name": name, **options.get(name, {})} for port, name in ports.items()}
    outs, _, _ = stages.call("definitive_survey", inputs, {**params, "runs": specs}, well=well)
    template = next(iter(runs.values()))
    return Tables({port: like(template, table) for port, table in outs.items()})


def acceptance_gates(
    inrun: TableLike, outrun: TableLike, *, well: WellLike = None, **params: Any
) -> Tables:
    """An in-run against an out-run of one gyro (stations, same north reference):
    ``comparison`` (one row per paired station) and ``gates`` (stations compared,
    inclination, azimuth, low-inclination azimuth and depth, each pass, fail or not
    evaluated). ``params``: ``inc_tolerance`` (0.23°), ``azi_tolerance`` (1.0°),
    ``low_inclination`` (10°), ``azi_tolerance_low`` (5.0°), ``min_stations`` (10),
    ``depth_tolerance`` (0.5 m), ``pair_window`` (5 m)."""
    inputs = {"inrun": inrun, "outrun": outrun}
    outs, _, _ = stages.call("acceptance_gates", inputs, params, well=well)
    return Tables({port: like(inrun, table) for port, table in outs.items()})

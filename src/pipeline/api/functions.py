"""The functions of the Python API (``import pipeline as gp``).

Every function takes pandas DataFrames or Arrow tables (:mod:`pipeline.api.frames`: units
in ``attrs`` or field metadata, canonical units when none are declared) and returns the same
kind. Each runs the registered stage of the same name, with the same parameters, contracts
and plugins as a pipeline. Lengths are in m, angles in degrees, angular rates in °/h,
accelerations in m/s², magnetic fields in nT, times in s; azimuths are clockwise from the
north reference the table names (``true``, ``grid`` or ``magnetic``); positions are north,
east and TVD (down) from the wellhead.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
from pydantic import ValidationError

from pipeline.api import stages
from pipeline.api.frames import (
    TableLike,
    WellLike,
    as_stated,
    describe,
    like,
    to_frame,
    to_table,
    well_metadata,
    well_of_data,
)
from pipeline.atomic import atomic_path, fsync_file
from pipeline.convert import read_any, writer_for
from pipeline.errors import InputFileError, ParameterError
from pipeline.sim.spec import SimulationSpec, load_simulation
from pipeline.stages.simulation import simulation_tables
from pipeline.well import attach


class Tables(Mapping[str, TableLike]):
    """Several tables a function returns, by name; also as attributes (``result.stations``)."""

    def __init__(self, tables: Mapping[str, TableLike]) -> None:
        self._tables = dict(tables)

    def __getitem__(self, name: str) -> TableLike:
        return self._tables[name]

    def __getattr__(self, name: str) -> TableLike:
        try:
            return self._tables[name]
        except KeyError:
            raise AttributeError(f"no table {name!r} (tables: {', '.join(self._tables)})") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._tables)

    def __len__(self) -> int:
        return len(self._tables)

    def __repr__(self) -> str:
        rows = ", ".join(f"{name}: {len(t)} rows" for name, t in self._tables.items())
        return f"Tables({rows})"


# ------------------------------------------------------------------------------ files


def read(
    path: str | Path,
    *,
    kind: str = "auto",
    reader: str = "auto",
    well: WellLike = None,
    **options: Any,
) -> pd.DataFrame:
    """Read a file as a DataFrame in canonical units (``attrs``: ``units``,
    ``north_reference``, ``well``). ``kind``: ``stations``, ``samples``, ``readings``,
    ``log`` (any LAS log: every curve as logged, units kept) or ``auto`` (a survey kind if
    the file is one, else a log); ``reader``: a reader's name or ``auto`` (the engine's
    choice among the installed readers, plugins included, as in pipelines); ``options``: the
    reader's options; ``well``: metadata that fills what the file leaves out (e.g. the north
    reference of azimuths the file does not name). A file whose pandas metadata is unusable
    is an :class:`InputFileError`."""
    table = read_table(path, kind=kind, reader=reader, well=well, **options)
    try:
        return to_frame(table)
    except ParameterError as exc:  # the file's own pandas metadata (Parquet)
        raise InputFileError(Path(path), str(exc)) from None


def read_table(
    path: str | Path,
    *,
    kind: str = "auto",
    reader: str = "auto",
    well: WellLike = None,
    **options: Any,
) -> pa.Table:
    """:func:`read`, returning the Arrow table (units in the field metadata, the well
    metadata in the schema metadata)."""
    if not isinstance(path, str | os.PathLike):
        raise ParameterError(f"read: expected a file path, got {path!r}")
    given = well_metadata(well)
    table, header = read_any(
        stages.registry(), Path(path), kind=kind, reader=reader, options=options, well=given
    )
    return attach(table, header.merged(given) if well is not None else header)


def write(data: TableLike, path: str | Path, *, writer: str | None = None) -> Path:
    """Write a table to ``path`` atomically, with the writer named or the one whose
    extension ``path`` has (``.parquet``, ``.csv``, ``.las``, ``.xml``, ``.mcap``…); units
    (a canonical column declaring none: its canonical unit), north reference (a DataFrame's
    ``attrs['north_reference']``: its ``azi``'s) and well metadata go with it."""
    target = Path(path)
    reg = stages.registry()
    if writer is None:
        try:
            chosen = writer_for(reg, target)
        except ValueError as exc:  # an extension no writer has
            raise ParameterError(str(exc)) from None
    elif writer in reg.writers:
        chosen = reg.writers[writer][0]
    else:
        raise ParameterError(f"no writer named {writer!r} (installed: {', '.join(reg.writers)})")
    table = as_stated(to_table(data, what="table to write"))
    well = well_of_data(table)  # with a frame's attrs["north_reference"]
    try:
        with atomic_path(target) as tmp:
            chosen.write(attach(table, well), tmp, well)
    except ValueError as exc:  # a table the format cannot hold
        raise ParameterError(
            f"{target}: writer {chosen.name!r} cannot hold the table: {exc}"
        ) from None
    return target


# ------------------------------------------------------------------- survey geometry


def minimum_curvature(stations: TableLike, *, well: WellLike = None, **params: Any) -> TableLike:
    """Trajectory of surveyed stations (md m, inc, azi deg) by minimum curvature: north, east,
    tvd (m, from the wellhead), dls (deg/30 m), vertical section and closure. ``params``:
    ``vs_azimuth`` (deg, same north as the azimuths), ``tie_north``, ``tie_east``,
    ``tie_tvd`` (m; default: the TVD, north and east the stations list at each survey's
    first station, else TVD = MD, N = E = 0)."""
    return _one("minimum_curvature", stations, {"stations": stations}, params, well)


def survey_method(stations: TableLike, *, well: WellLike = None, **params: Any) -> TableLike:
    """Trajectory by another station method: ``method`` = ``tangential``,
    ``balanced_tangential``, ``average_angle``, ``radius_of_curvature`` or
    ``minimum_curvature`` (other params as :func:`minimum_curvature`)."""
    return _one("survey_method", stations, {"stations": stations}, params, well)


def interpolate(
    trajectory: TableLike,
    *,
    md: float | list[float] | None = None,
    tvd: float | list[float] | None = None,
    well: WellLike = None,
    **params: Any,
) -> TableLike:
    """Points of a trajectory at given MDs (m; or every ``spacing`` m) along the minimum-
    curvature arcs, or every crossing of given TVDs (m): position, inclination, azimuth."""
    if (md is None) == (tvd is None) and "spacing" not in params:
        raise ParameterError("interpolate: give md=… (or spacing=…) or tvd=…, not both")
    if tvd is not None:
        at = {"tvd": _listed(tvd)}
        return _one("interpolate_tvd", trajectory, {"trajectory": trajectory}, at, well)
    at = {"md": _listed(md)} if md is not None else {}
    return _one("interpolate_md", trajectory, {"trajectory": trajectory}, {**at, **params}, well)


def position_uncertainty(
    trajectory: TableLike,
    *,
    stops: TableLike | None = None,
    well: WellLike = None,
    **params: Any,
) -> TableLike:
    """Position covariance (NEV, m²) and error ellipses of a trajectory by an ISCWSA error
    model (``model``: a tool model's name — shipped or an installed plugin's, as ``gyropipe
    models`` lists them; default the stage's — or a model file; ``confidence``; ``latitude``
    deg or the well's; ``outside_validity``: ``"refuse"`` a station outside the model's range,
    the default, or ``"flag"`` it: NaN σ from it down and an ``outside_validity`` column).
    ``stops``: compassed stops of a continuous survey."""
    inputs = {"trajectory": trajectory, "stops": stops}
    return _one("position_uncertainty", trajectory, inputs, params, well)


# ------------------------------------------------------------------ sensors → stations


def position_readings(samples: TableLike, *, well: WellLike = None, **params: Any) -> TableLike:
    """Raw samples of a point survey (tool frame, deg/h, m/s², nT) averaged per station and
    frame position, the transients trimmed."""
    return _one("position_readings", samples, {"samples": samples}, params, well)


def validity_checks(
    readings: TableLike,
    *,
    samples: TableLike | None = None,
    well: WellLike = None,
    **params: Any,
) -> Tables:
    """Validity checks of every station × frame position against the Earth's rate, gravity
    and magnetic field at the site (the well's latitude, longitude, date): ``qc`` (one row per
    check), ``summary`` (per station verdict) and ``readings`` (stations that pass)."""
    inputs = {"readings": readings, "samples": samples}
    return _many("validity_checks", readings, inputs, params, well)


def compass(
    readings: TableLike,
    *,
    latitude: float | None = None,
    well: WellLike = None,
    **params: Any,
) -> Tables:
    """Multi-position gyrocompassing of position readings: ``stations`` (inclination, true
    azimuth, toolfaces, predicted σ) and ``rejects`` (stations not solved, with why).
    ``latitude`` (deg) or the well's is needed."""
    return _many("compass", readings, {"readings": readings}, _with(params, latitude), well)


def integrate_continuous(
    samples: TableLike,
    stops: TableLike,
    *,
    latitude: float | None = None,
    well: WellLike = None,
    **params: Any,
) -> Tables:
    """Continuous-mode survey between two compassed stops: ``stations`` (every ``spacing``
    m) and ``series`` (full rate), the misclosure on the end stop removed linearly in time."""
    inputs = {"samples": samples, "stops": stops}
    return _many("integrate_continuous", samples, inputs, _with(params, latitude), well)


def calibrate_drift(readings: TableLike, *, well: WellLike = None, **params: Any) -> Tables:
    """Drift calibration of free gyros from calibration readings: ``result`` (estimates with
    σ and the linearity verdict) and ``series`` (the series means)."""
    return _many("calibrate_drift", readings, {"readings": readings}, params, well)


def correct_drift(
    readings: TableLike,
    *,
    calibration: TableLike | None = None,
    well: WellLike = None,
    **params: Any,
) -> Tables:
    """Drift correction of a free-gyro survey from a calibration (or the tie-in closure):
    corrected ``readings``, ``stations`` and the in/out-run ``qc``."""
    inputs = {"readings": readings, "calibration": calibration}
    return _many("correct_drift", readings, inputs, params, well)


# -------------------------------------------------------------------- simulator


def simulate(plan: str | Path | Mapping[str, Any], *, seed: int | None = None) -> Tables:
    """Simulate a survey from a plan (a YAML file or its mapping: site, well, tool, survey;
    see docs/simulator.md): raw ``samples`` (tool frame), the ``truth`` and the true
    ``stations`` — or, for a free-gyro survey, its ``readings``."""
    read = _stations_reader
    if isinstance(plan, Mapping):
        try:
            spec = SimulationSpec.model_validate(
                {**plan, **({} if seed is None else {"seed": seed})}
            )
        except ValidationError as exc:
            raise ParameterError(f"simulate: plan: {describe(exc)}") from None
        if hasattr(spec.well, "load"):
            spec.well.load(read)
    else:
        spec = load_simulation(plan, seed, read_stations=read)
    return Tables({name: to_frame(table) for name, table in simulation_tables(spec).items()})


def _stations_reader(path: Path, reader: str) -> pa.Table:
    return stages.registry().read(path, "stations", reader=reader)[0]


# ---------------------------------------------------------------------- reports


def report(
    trajectory: TableLike,
    path: str | Path,
    *,
    well: WellLike = None,
    stations: TableLike | None = None,
    qc: TableLike | None = None,
    qc_summary: TableLike | None = None,
    checks: TableLike | None = None,
    **params: Any,
) -> list[Path]:
    """Write the survey report of a trajectory: ``path`` is the base name, and
    ``<path>.html`` and ``<path>.pdf`` (``formats``) are written atomically; returns them."""
    target = Path(path)
    inputs = {
        "trajectory": trajectory,
        "stations": stations,
        "qc": qc,
        "qc_summary": qc_summary,
        "checks": checks,
    }
    params = {**params, "filename": target.name}
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".gyropipe-report-") as tmp:
        _, _, files = stages.call("report", inputs, params, well=well, out_dir=Path(tmp))
        written = []
        for file in files:
            fsync_file(file)
            final = target.parent / file.name
            file.replace(final)
            written.append(final)
    return written


# ------------------------------------------------------------------------ helpers


def _listed(values: float | list[float]) -> list[float]:
    return [values] if isinstance(values, int | float) else list(values)


def _with(params: dict[str, Any], latitude: float | None) -> dict[str, Any]:
    return params if latitude is None else {**params, "latitude": latitude}


def _one(
    uses: str,
    template: TableLike,
    inputs: Mapping[str, TableLike | None],
    params: Mapping[str, Any],
    well: WellLike,
) -> TableLike:
    outs, _, _ = stages.call(uses, inputs, params, well=well)
    (table,) = outs.values()
    return like(template, table)


def _many(
    uses: str,
    template: TableLike,
    inputs: Mapping[str, TableLike | None],
    params: Mapping[str, Any],
    well: WellLike,
) -> Tables:
    outs, _, _ = stages.call(uses, inputs, params, well=well)
    return Tables({port: like(template, table) for port, table in outs.items()})

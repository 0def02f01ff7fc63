"""Simulation plans: a YAML file naming the site, the well, the tool and the survey.

Angles in degrees, lengths in metres, times in seconds, speeds in m/s, dogleg severity in
°/30 m. Errors name the field and its ``file:line:column``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, Literal

import pyarrow as pa
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    PrivateAttr,
    Tag,
    field_validator,
    model_validator,
)

from pipeline.contracts import SOURCE_LINE
from pipeline.earth.site import Site
from pipeline.errors import GyropipeError, Location, Problem, SpecError
from pipeline.gyrocompass.positions import DEFAULT_POSITIONS
from pipeline.hashing import regular_bytes
from pipeline.sim.plan import StationProblem, WellPath, WellPlan, build_path
from pipeline.sim.sensors import PRESETS, ToolSensors, tool_preset
from pipeline.yamlsource import load_mapping, validate_located


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Torsion(Strict):
    """Rotation of the tool housing about its axis while it moves (cable torsion): a smooth
    random spin rate plus an oscillation, scaled by the tool's speed (zero at rest)."""

    spin_sigma: float = Field(20.0, ge=0, description="σ of the random spin rate, deg/s")
    spin_correlation: float = Field(20.0, gt=0, description="correlation time of the spin, s")
    oscillation: float = Field(10.0, ge=0, description="amplitude of the roll oscillation, deg")
    oscillation_period: float = Field(8.0, gt=0, description="period of the roll oscillation, s")


class StopScheme(Strict):
    """How the frame is turned at a compassing stop."""

    positions: list[float] = Field(
        default_factory=lambda: list(DEFAULT_POSITIONS),
        min_length=1,
        description="frame angles of the successive positions, deg (relative to the housing)",
    )
    dwell: float = Field(40.0, gt=0, description="time at each position, s")
    move_time: float = Field(3.0, gt=0, description="duration of each frame move, s")
    settle_time: float = Field(
        2.0, ge=0, description="rest before the first position after arriving, s"
    )


class PointSurvey(StopScheme):
    """Stop-and-go survey: compassing stops at stations, travel between them."""

    mode: Literal["point"] = "point"
    stations: list[float] | None = Field(None, description="station MDs, m")
    every: float | None = Field(None, gt=0, description="station spacing from the plan start, m")
    speed: float = Field(1.0, gt=0, description="mean travel speed between stations, m/s")
    torsion: Torsion = Field(default_factory=Torsion)
    start_roll: float = Field(
        0.0, description="initial north-referenced roll of the housing (A + ψ), deg"
    )

    @model_validator(mode="after")
    def _stations_given(self) -> PointSurvey:
        if (self.stations is None) == (self.every is None):
            raise ValueError("give exactly one of 'stations' (MD list) or 'every' (spacing)")
        if self.stations is not None and any(
            b <= a for a, b in zip(self.stations, self.stations[1:], strict=False)
        ):
            raise ValueError("stations: MDs must increase")
        return self


class Stabilisation(Strict):
    """Frame servo keeping the gyro (frame x) axis near the high side while moving; its
    error grows in with the speed, so the frame rate is continuous where it engages."""

    enabled: bool = Field(
        True,
        description="false: no servo, the frame stays at the stop's last position and rolls "
        "with the housing (a free-rotating two- or three-axis tool)",
    )
    residual: float = Field(2.0, ge=0, description="σ of the residual toolface error, deg")
    correlation: float = Field(5.0, gt=0, description="correlation time of the residual, s")


class ContinuousSurvey(Strict):
    """Continuous survey: compassing stop at the start and end, moving survey between."""

    mode: Literal["continuous"] = "continuous"
    start_md: float | None = Field(None, ge=0, description="start MD, m (default plan start)")
    end_md: float | None = Field(None, ge=0, description="end MD, m (default plan end)")
    speed: float = Field(1.0, gt=0, description="logging speed, m/s")
    ramp_time: float = Field(5.0, gt=0, description="acceleration and braking time, s")
    stop: StopScheme = Field(default_factory=StopScheme)
    torsion: Torsion = Field(default_factory=Torsion)
    stabilisation: Stabilisation = Field(default_factory=Stabilisation)
    start_roll: float = Field(0.0, description="initial north-referenced housing roll, deg")


class Drift(Strict):
    """Azimuth drift of a free gyro: ΔA(t) = offset + rate·t + curvature·t²."""

    offset: float = Field(0.0, description="azimuth error at the start, deg")
    rate: float = Field(2.0, description="drift rate, deg/h")
    curvature: float = Field(0.0, description="non-linear drift term, deg/h²")


class FreeGyroSurvey(Strict):
    """Free (directional) gyro survey: azimuth readings that drift in time; in-run down the
    stations and, optionally, out-run back up."""

    mode: Literal["free_gyro"] = "free_gyro"
    every: float = Field(30.0, gt=0, description="station spacing, m")
    dwell: float = Field(30.0, gt=0, description="time per reading, s")
    speed: float = Field(1.0, gt=0, description="travel speed, m/s")
    drift: Drift = Field(default_factory=Drift)
    reading_noise: float = Field(0.2, ge=0, description="σ of a reading's azimuth error, deg")
    inclination_noise: float = Field(0.05, ge=0, description="σ of a reading's inclination, deg")
    out_run: bool = Field(True, description="also survey on the way out")


Survey = Annotated[PointSurvey | ContinuousSurvey | FreeGyroSurvey, Field(discriminator="mode")]


class ToolChoice(Strict):
    """A tool preset with optional overrides of any of its fields."""

    preset: str = Field(description=f"tool preset: {', '.join(PRESETS)}")
    overrides: dict[str, Any] = Field(default_factory=dict, description="fields to override")

    @field_validator("preset")
    @classmethod
    def _known(cls, name: str) -> str:
        if name not in PRESETS:
            raise ValueError(f"unknown tool preset {name!r} (presets: {', '.join(PRESETS)})")
        return name

    def model(self) -> ToolSensors:
        return tool_preset(self.preset, **self.overrides)


ReadStations = Callable[[Path, str], pa.Table]
"""Reads a stations file with the named reader (``auto``: the engine's choice)."""


class StationsWell(Strict):
    """A well given by a stations file (MD, inclination, azimuth true north), joined by
    minimum-curvature arcs; read by any installed stations reader (CSV, Parquet, …)."""

    stations: Path = Field(description="stations file; a relative path is from the plan file")
    reader: str = Field("auto", description="reader name, or 'auto' to sniff the file")
    start_north: float = Field(0.0, description="northing of the first station, m")
    start_east: float = Field(0.0, description="easting of the first station, m")
    start_tvd: float | None = Field(None, description="TVD of the first station, m (default MD)")
    _table: pa.Table | None = PrivateAttr(None)

    def load(self, read: ReadStations, where: Location | None = None) -> None:
        """Read the stations file (``read(path, reader name)``, the engine's reader choice)
        and check a path runs through its stations. With ``where`` (the plan's ``stations:``
        entry) a problem is a :class:`SpecError` there, giving the stations file's own
        location (its line, or the station's row)."""
        try:
            self._table = read(self.stations, self.reader)
            self.path()
        except (GyropipeError, ValueError) as exc:
            if where is None:
                raise
            inner = str(exc) if isinstance(exc, GyropipeError) else self._located(exc)
            raise SpecError([Problem(where, f"well.stations: {inner}")]) from None

    def _located(self, exc: ValueError) -> str:
        """A path problem, at the station's line of the stations file (or its row)."""
        table = self._table
        if not isinstance(exc, StationProblem) or table is None:
            return f"{self.stations}: {exc}" if str(self.stations) not in str(exc) else str(exc)
        if SOURCE_LINE in table.column_names:
            return f"{self.stations}:{table.column(SOURCE_LINE)[exc.station].as_py()}: {exc}"
        return f"{self.stations}: row {exc.station + 1}: {exc}"

    def path(self) -> WellPath:
        table = self._table
        if table is None:
            raise ValueError(
                f"{self.stations}: the stations file was not read; "
                "give load_simulation a read_stations function"
            )
        if (table.schema.field("azi").metadata or {}).get(b"north_reference") != b"true":
            raise ValueError(f"{self.stations}: the simulator needs true-north azimuths")
        return WellPath.from_stations(
            table.column("md").to_numpy(),
            table.column("inc").to_numpy(),
            table.column("azi").to_numpy(),
            start_north=self.start_north,
            start_east=self.start_east,
            start_tvd=self.start_tvd,
        )


def _well_kind(value: Any) -> str:
    """The kind of well a plan gives: a stations file if it names one, else sections (its
    problems are then reported against that kind alone)."""
    if isinstance(value, BaseModel):  # an already validated well (model_copy, tests)
        return "stations file" if isinstance(value, StationsWell) else "plan"
    return "stations file" if isinstance(value, dict) and "stations" in value else "plan"


class SimulationSpec(Strict):
    """A whole simulation: where, which well, which tool, which survey, which seed."""

    name: str = Field(description="simulation name")
    seed: int = Field(0, description="random seed: same seed, same output")
    site: Site
    well: Annotated[
        Annotated[WellPlan, Tag("plan")] | Annotated[StationsWell, Tag("stations file")],
        Discriminator(_well_kind),
    ] = Field(description="a plan of sections or a stations file")
    tool: ToolChoice
    survey: Survey

    def path(self) -> WellPath:
        """The well path (NED, m) of the plan's sections or stations file."""
        return build_path(self.well) if isinstance(self.well, WellPlan) else self.well.path()

    @model_validator(mode="after")
    def _tool_builds(self) -> SimulationSpec:
        self.tool.model()  # overrides are validated here, against the preset's models
        return self


def load_simulation(
    path: str | Path, seed: int | None = None, *, read_stations: ReadStations | None = None
) -> SimulationSpec:
    """Read and validate a simulation plan; every problem is located in the file. A plan
    whose well is a stations file needs ``read_stations`` to read it."""
    path = Path(path)
    try:
        text = regular_bytes(path).decode("utf-8")  # a FIFO is refused, never waited on
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError([Problem(Location(str(path)), f"cannot read plan: {exc}")]) from exc
    raw, source, problems = load_mapping(
        text, str(path), "a simulation plan must be a mapping (site, well, tool, survey)"
    )
    if seed is not None:
        raw["seed"] = seed
    well = raw.get("well")
    if isinstance(well, dict) and isinstance(well.get("stations"), str):
        well["stations"] = str(path.parent / well["stations"])
    spec = validate_located(SimulationSpec, raw, source, problems)
    if problems:
        raise SpecError(problems)
    if isinstance(spec.well, StationsWell) and read_stations is not None:
        spec.well.load(read_stations, source.locate(("well", "stations")))
    return spec

"""Built-in plugin: the ``position_uncertainty`` stage (ISCWSA gyro error model)."""

from __future__ import annotations

import itertools
from collections.abc import Callable, Mapping
from typing import Literal

import numpy as np
import pyarrow as pa
from pydantic import BaseModel, ConfigDict, Field

from pipeline.contracts import column
from pipeline.hookspecs import hookimpl
from pipeline.registry import StageContext, StageDef
from pipeline.stages.survey import north_reference_of, survey_offsets
from pipeline.tables import Trajectory
from pipeline.uncertainty.ellipse import ellipses, horizontal_scale, vertical_scale
from pipeline.uncertainty.gyro import GYRO_PRESETS, Survey, gyro_covariance

AREA = "m2"


class PositionUncertainty(Trajectory):
    """A trajectory with each station's NEV position covariance (1σ², m²) and its
    horizontal error ellipse (semi-axes at 1σ and at the stage's confidence) and vertical σ."""

    cov_nn: float = column(unit=AREA, description="north variance")
    cov_ne: float = column(unit=AREA, description="north-east covariance")
    cov_nv: float = column(unit=AREA, description="north-vertical covariance")
    cov_ee: float = column(unit=AREA, description="east variance")
    cov_ev: float = column(unit=AREA, description="east-vertical covariance")
    cov_vv: float = column(unit=AREA, description="vertical variance")
    ellipse_major: float = column(unit="m", ge=0, description="horizontal semi-major axis, 1σ")
    ellipse_minor: float = column(unit="m", ge=0, description="horizontal semi-minor axis, 1σ")
    ellipse_azimuth: float = column(
        unit="deg",
        ge=0,
        lt=180,
        north_reference=True,
        description="azimuth of the semi-major axis, clockwise from north",
    )
    sigma_v: float = column(unit="m", ge=0, description="vertical σ")
    ellipse_major_conf: float = column(
        unit="m", ge=0, description="semi-major axis at the confidence level (χ², 2 dof)"
    )
    ellipse_minor_conf: float = column(
        unit="m", ge=0, description="semi-minor axis at the confidence level (χ², 2 dof)"
    )
    vertical_conf: float = column(
        unit="m", ge=0, description="vertical half-interval at the confidence level"
    )


class UncertaintyParams(BaseModel):
    """Parameters of the position-uncertainty stage."""

    model_config = ConfigDict(extra="forbid")
    model: str = Field("GYRO-NS", description=f"tool preset, one of {sorted(GYRO_PRESETS)}")
    confidence: float = Field(
        0.95, gt=0, lt=1, description="probability content of the *_conf ellipse columns"
    )
    latitude: float | None = Field(
        None, ge=-89.9, le=89.9, description="latitude, deg; default: the well's latitude"
    )
    basis: Literal["min_curve", "balanced_tangent"] = Field(
        "min_curve",
        description="leg Jacobian: exact minimum curvature or the ISCWSA balanced tangent",
    )
    surface_tie: bool = Field(
        False, description="apply the ISCWSA Rev 5 surface tie-on allowance at the first station"
    )
    measured_sigma_azi: float | None = Field(
        None,
        ge=0,
        description="measured 1σ compassing azimuth scatter, deg; sets GXY-RN when given",
    )


def position_uncertainty(
    inputs: Mapping[str, pa.Table], params: UncertaintyParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Trajectory → trajectory with NEV covariance and error ellipses per station."""
    table = inputs["trajectory"]
    latitude = params.latitude if params.latitude is not None else ctx.well.latitude
    if latitude is None:
        raise ValueError("position_uncertainty needs a latitude: set it or the well's latitude")
    if params.model not in GYRO_PRESETS:
        raise ValueError(f"unknown model {params.model!r}; expected one of {sorted(GYRO_PRESETS)}")
    tool = GYRO_PRESETS[params.model]
    if params.measured_sigma_azi is not None:
        tool = tool.with_measured_noise(params.measured_sigma_azi, latitude)
    md = table.column("md").to_numpy()
    inc = np.radians(table.column("inc").to_numpy())
    azi = np.radians(table.column("azi").to_numpy())
    tvd = table.column("tvd").to_numpy()
    cov = np.zeros((md.size, 3, 3))
    offsets = survey_offsets(table)
    for lo, hi in itertools.pairwise(offsets):
        survey = Survey.of(md[lo:hi], inc[lo:hi], azi[lo:hi], tvd[lo:hi])
        _, per_term = gyro_covariance(
            survey, latitude, tool, basis=params.basis, surface_tie=params.surface_tie
        )
        cov[lo:hi] = per_term.sum(axis=0)
    ell = ellipses(cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1], cov[:, 2, 2])
    k2 = horizontal_scale(params.confidence)
    k1 = vertical_scale(params.confidence)
    columns: dict[str, object] = {name: table.column(name) for name in table.column_names}
    columns.update(
        cov_nn=cov[:, 0, 0],
        cov_ne=cov[:, 0, 1],
        cov_nv=cov[:, 0, 2],
        cov_ee=cov[:, 1, 1],
        cov_ev=cov[:, 1, 2],
        cov_vv=cov[:, 2, 2],
        ellipse_major=ell.semi_major,
        ellipse_minor=ell.semi_minor,
        ellipse_azimuth=np.degrees(ell.azimuth) % 180.0,
        sigma_v=ell.sigma_v,
        ellipse_major_conf=k2 * ell.semi_major,
        ellipse_minor_conf=k2 * ell.semi_minor,
        vertical_conf=k1 * ell.sigma_v,
    )
    out = PositionUncertainty.compiled().make_table(
        columns, north_reference=north_reference_of(table, "azi")
    )
    return {"trajectory": out}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="position_uncertainty",
            func=position_uncertainty,
            description="Propagate the ISCWSA gyro error model (GYRO-NS) into NEV covariance "
            "and error ellipses per station.",
            inputs={"trajectory": Trajectory},
            outputs={"trajectory": PositionUncertainty},
            params=UncertaintyParams,
        )
    )

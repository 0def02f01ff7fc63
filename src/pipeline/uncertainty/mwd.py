"""The ISCWSA MWD error models (magnetic MWD, SPE 67616 and the ISCWSA Rev 4/Rev 5 documents)
through their tool-model files, with the earlier Python API.

The models are data (``models/iscwsa-mwd-*.yaml``: Rev 4, the Rev 5 example workbook's
magnitudes and Rev 5.11's), evaluated by :mod:`pipeline.uncertainty.engine`; the weighting
functions (toolface-independent xy sensor terms, declination, axial interference, sag,
misalignments, XCLA/XCLH in position) are in :mod:`pipeline.uncertainty.weightfns`.

Frames and inputs: true azimuth A (rad) in :class:`~pipeline.uncertainty.terms.Survey`, the
magnetic azimuth Am = A − D (D the declination, east positive); total field B (nT), dip Θ
and gravity G (m/s²) of the site.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from pipeline.earth.site import MagneticReference
from pipeline.uncertainty.engine import configure, find_model, term_covariances
from pipeline.uncertainty.quantities import ModelSite, Quantities
from pipeline.uncertainty.terms import STANDARD_G, Survey, Term
from pipeline.uncertainty.toolmodel import ToolModel

__all__ = [
    "MWD_PRESETS",
    "MwdTool",
    "mwd_covariance",
    "mwd_terms",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MwdTool:
    """An MWD tool model: a model file (``model``, default ISCWSA MWD Rev 5.11) with term
    magnitudes overriding the file's where given (the sheet's units: m, -, 1/m, m/s², nT,
    deg, deg·nT; None keeps the file's), by field name (``abz`` is ABZ, ``dec_u`` DEC-U)."""

    model: str = "ISCWSA-MWD-REV5.11"
    drfr: float | None = None
    dsfs: float | None = None
    dstg: float | None = None
    abxy_ti1s: float | None = None
    abxy_ti2s: float | None = None
    abz: float | None = None
    asxy_ti1s: float | None = None
    asxy_ti2s: float | None = None
    asxy_ti3s: float | None = None
    asz: float | None = None
    mbxy_ti1s: float | None = None
    mbxy_ti2s: float | None = None
    mbz: float | None = None
    msxy_ti1s: float | None = None
    msxy_ti2s: float | None = None
    msxy_ti3s: float | None = None
    msz: float | None = None
    dec_u: float | None = None
    dec_os: float | None = None
    dec_oh: float | None = None
    dec_oi: float | None = None
    decr: float | None = None
    dbh_u: float | None = None
    dbh_os: float | None = None
    dbh_oh: float | None = None
    dbh_oi: float | None = None
    dbhr: float | None = None
    amil: float | None = None
    sage: float | None = None
    xym1: float | None = None
    xym2: float | None = None
    xym3e: float | None = None
    xym4e: float | None = None
    xcla: float | None = None
    xclh: float | None = None
    xcl_tortuosity: float | None = None  # rad/m

    def tool_model(self) -> ToolModel:
        """The model file with this tool's magnitudes."""
        changed = {
            f.name: float(getattr(self, f.name))
            for f in fields(self)
            if f.name != "model" and getattr(self, f.name) is not None
        }
        return configure(self.model, changed)


MWD_PRESETS: dict[str, MwdTool] = {
    name: MwdTool(model=name)
    for name in ("ISCWSA-MWD-REV4", "ISCWSA-MWD-REV5", "ISCWSA-MWD-REV5.11")
}
"""Named MWD tool models (each a model file)."""


def mwd_terms(
    tool: MwdTool | str | ToolModel, magnetic: MagneticReference, *, g: float = STANDARD_G
) -> list[Term]:
    """The terms of an MWD model at a site's field, magnitudes in SI, in the file's order."""
    model = tool.tool_model() if isinstance(tool, MwdTool) else find_model(tool)
    site = ModelSite(magnetic=magnetic, g=g)
    return model.terms_for(lambda s: Quantities(s, site, model.parameters, model.name))


def mwd_covariance(
    survey: Survey,
    magnetic: MagneticReference,
    tool: MwdTool | str | ToolModel = "ISCWSA-MWD-REV5.11",
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    g: float = STANDARD_G,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) (m²) of a survey and the term names."""
    model = tool.tool_model() if isinstance(tool, MwdTool) else find_model(tool)
    return term_covariances(
        survey, model, ModelSite(magnetic=magnetic, g=g), basis=basis, surface_tie=surface_tie
    )

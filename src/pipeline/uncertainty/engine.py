"""One engine for every tool model: find a model (by name, file or object) and evaluate it
into NEV position covariance.

Models are found, by name (case-insensitive), among the files shipped in
``pipeline/uncertainty/models/`` and those plugins register
(``gyropipe_register_tool_models``), or read from a file path. A file may ``extend`` any
model found so.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from pipeline.errors import Location, Problem, ToolModelError, did_you_mean
from pipeline.uncertainty.quantities import MissingSiteQuantity, ModelSite, Quantities
from pipeline.uncertainty.terms import Survey, term_covariance
from pipeline.uncertainty.toolmodel import ToolModel, read_tool_model

__all__ = [
    "MODELS_DIR",
    "covariance",
    "find_model",
    "model_files",
    "term_covariances",
]

FloatArray = NDArray[np.float64]
MODELS_DIR = Path(__file__).parent / "models"
"""The tool-model files shipped with gyropipe."""


@functools.cache
def _shipped() -> dict[str, Path]:
    """Shipped model files by the model name each declares (upper case)."""
    out: dict[str, Path] = {}
    for path in sorted(MODELS_DIR.glob("*.yaml")):
        out[_declared_name(path)] = path
    return out


def _declared_name(path: Path) -> str:
    """The ``name:`` a model file declares (upper case), read without resolving ``extends``."""
    import yaml

    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    return str(data["name"]).upper()


@functools.cache
def _plugin_files() -> dict[str, Path]:
    """Model files registered by plugins, by name (upper case); loaded on first need."""
    from pipeline.plugins import load_registry

    registry = load_registry()
    return {name.upper(): d.path for name, (d, _) in registry.tool_models.items()}


def model_files(*, plugins: bool = True) -> dict[str, Path]:
    """Every model found by name: shipped files, then plugins' (a shipped name wins)."""
    found = dict(_plugin_files()) if plugins else {}
    found.update(_shipped())
    return found


@functools.cache
def _read(path: Path) -> ToolModel:
    return read_tool_model(path, base=_base)


def _base(name: str, where: Location) -> ToolModel:
    """The model an ``extends:`` names, found as :func:`find_model` finds one."""
    try:
        return find_model(name)
    except KeyError as exc:
        raise ToolModelError([Problem(where, str(exc.args[0]))]) from None


def find_model(model: str | Path | ToolModel) -> ToolModel:
    """A tool model by name (shipped or plugin-registered, case-insensitive), by file path
    (``.yaml``/``.yml``), or as given. An unknown name is a ``KeyError`` listing the known
    ones; a bad file a :class:`~pipeline.errors.ToolModelError`."""
    if isinstance(model, ToolModel):
        return model
    key = str(model).upper()
    shipped = _shipped()
    if key in shipped:
        return _read(shipped[key])
    path = Path(model)
    if path.suffix.lower() in (".yaml", ".yml") or path.is_file():
        if not path.is_file():
            raise ToolModelError([Problem(Location(str(path)), "no such tool-model file")])
        return _read(path.resolve())
    plugins = _plugin_files()
    if key in plugins:
        return _read(plugins[key])
    known = sorted({**plugins, **shipped})
    raise KeyError(
        f"unknown tool model {str(model)!r}{did_you_mean(key, known)} "
        f"(known: {', '.join(known)}; or give a .yaml file)"
    )


def term_covariances(
    survey: Survey,
    model: str | Path | ToolModel,
    site: ModelSite | None = None,
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) (m²) of a survey under a tool model, and the term
    names. ``survey`` azimuths are true (rad); ``site`` gives what the model needs
    (:attr:`ToolModel.needs`: latitude, geomagnetic field); ``basis`` and ``surface_tie`` as
    in :func:`pipeline.uncertainty.model.station_jacobians` (the ISCWSA conventions by
    default)."""
    tool = find_model(model)
    where = site or ModelSite()
    missing = sorted(
        need
        for need, value in (("latitude", where.latitude), ("magnetic", where.magnetic))
        if need in tool.needs and value is None
    )
    if missing:
        raise MissingSiteQuantity(
            f"tool model {tool.name} needs the site's {' and '.join(missing)}"
        )
    shared = Quantities(survey, where, tool.parameters, tool.name)  # derived ones cached

    def q(s: Survey) -> Quantities:
        return shared if s is survey else Quantities(s, where, tool.parameters, tool.name)

    return term_covariance(survey, tool.terms_for(q), basis=basis, surface_tie=surface_tie)


def covariance(
    survey: Survey,
    model: str | Path | ToolModel,
    site: ModelSite | None = None,
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
) -> FloatArray:
    """Total NEV covariance (n, 3, 3) (m², north/east/vertical-down) of each station of a
    survey under a tool model (see :func:`term_covariances`)."""
    total: FloatArray = term_covariances(survey, model, site, basis=basis, surface_tie=surface_tie)[
        1
    ].sum(axis=0)
    return total

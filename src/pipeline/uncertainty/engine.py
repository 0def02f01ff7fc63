"""One engine for every tool model: find a model (by name, file or object) and evaluate it
into NEV position covariance.

Models are found, by name (case-insensitive), in a :class:`ModelCatalogue`: the files shipped
in ``pipeline/uncertainty/models/`` and those it is given — the files plugins register
(``gyropipe_register_tool_models``), which the registry of the run hands down (the domain
never loads plugins). A model may also be read from a file path; a file may ``extend`` any
model found so.

A model holds over its inclination range (:attr:`ToolModel.inclination_range_deg`). A station
outside it has no σ: by default it is refused (:class:`OutsideValidityError`, naming the
model, the station and the range); with ``outside_validity="flag"`` it and every station
below it (whose positions it moves) get NaN covariance. A σ above :data:`PHYSICAL_BOUND_M`
plus twice the station's MD — farther than the hole reaches — is treated the same way: a
finite number is not a result when the linear model no longer holds.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from pipeline.errors import GyropipeError, Location, Problem, ToolModelError, did_you_mean
from pipeline.uncertainty.quantities import MissingSiteQuantity, ModelSite, Quantities
from pipeline.uncertainty.terms import Survey, Term, term_covariance
from pipeline.uncertainty.toolmodel import ToolModel, read_tool_model

__all__ = [
    "MODELS_DIR",
    "SHIPPED",
    "ModelCatalogue",
    "OutsideValidity",
    "OutsideValidityError",
    "SurveyValueError",
    "bounded_covariance",
    "configure",
    "covariance",
    "find_model",
    "model_files",
    "model_terms",
    "term_covariances",
    "term_for",
    "within_bound",
    "within_range",
]

FloatArray = NDArray[np.float64]
MODELS_DIR = Path(__file__).parent / "models"
"""The tool-model files shipped with gyropipe."""


class SurveyValueError(GyropipeError, ValueError):
    """A survey given to an error model has a non-finite MD, inclination, azimuth or TVD."""


class OutsideValidityError(GyropipeError, ValueError):
    """A station lies outside the range a tool model holds for (its inclination range, or a
    σ beyond the physical bound): no σ is given there."""


OutsideValidity = Literal["refuse", "flag"]
"""What a station outside its model's range gets: ``refuse`` (an error) or ``flag`` (NaN
covariance from it on, and a flag)."""

PHYSICAL_BOUND_M = 10.0
"""A station's σ (√ of the covariance's trace, m) beyond 2·|MD| + this is not physical: both
the true and the computed position lie within the hole's length of the wellhead (10 m for
the depth reference and the tie-on)."""


@functools.cache
def _shipped() -> dict[str, Path]:
    """Shipped model files (``models/`` and its family folders, ``models/owsg/``) by the
    model name each declares."""
    return {_declared_name(path): path for path in sorted(MODELS_DIR.rglob("*.yaml"))}


def _declared_name(path: Path) -> str:
    """The ``name:`` a shipped model file declares, read without resolving ``extends`` (by
    libyaml's safe loader when PyYAML has it: these files are ours, no location needed)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    data = yaml.load(path.read_text(encoding="utf-8"), Loader=loader)
    return str(data["name"])


@dataclass(frozen=True)
class ModelCatalogue:
    """The tool models a name can select: the shipped files and ``added`` ones (name, file)
    — the files the run's plugins registered; a shipped name wins. Build it with
    :meth:`of`; :data:`SHIPPED` holds the shipped files alone."""

    added: tuple[tuple[str, Path], ...] = ()

    @classmethod
    def of(cls, files: Mapping[str, Path]) -> ModelCatalogue:
        """The shipped models and the model files ``files`` (name → YAML file)."""
        return cls(tuple(sorted((name, Path(path)) for name, path in files.items())))

    def files(self) -> dict[str, Path]:
        """Every model found by name → its file: shipped files, then the added ones."""
        shipped = _shipped()
        taken = {name.upper() for name in shipped}
        return {**shipped, **{n: p for n, p in self.added if n.upper() not in taken}}


SHIPPED = ModelCatalogue()
"""The shipped tool models only (what a caller without a registry finds)."""


def model_files(catalogue: ModelCatalogue = SHIPPED) -> dict[str, Path]:
    """Every model ``catalogue`` finds by name → its file (a shipped name wins)."""
    return catalogue.files()


def _named(files: Mapping[str, Path], key: str) -> Path | None:
    """The file of the model called ``key`` (case-insensitive), if any."""
    return next((p for n, p in files.items() if n.upper() == key.upper()), None)


class _Reading(threading.local):
    """The files this thread is reading (outermost first: a file met again extends itself)
    and, per file, the bytes of the files its model is made of (Dask runs wells in threads)."""

    def __init__(self) -> None:
        self.files: list[Path] = []
        self.sources: list[dict[Path, bytes]] = []


_READING = _Reading()
_MODELS: dict[tuple[Path, ModelCatalogue], tuple[dict[Path, bytes], ToolModel]] = {}
"""(file, catalogue) → the bytes of every file its model was read from, and the model."""


def _read(path: Path, catalogue: ModelCatalogue) -> ToolModel:
    """The model of a file and catalogue its ``extends:`` is resolved in, read again only
    when the bytes of that file, or of a file it extends, are not those it was read from (a
    file replaced by one of the same size and times, or a base file edited, is read anew)."""
    try:
        data = path.read_bytes()
    except OSError:  # reports the file as unreadable
        return read_tool_model(path, base=functools.partial(_base, catalogue=catalogue))
    cached = _MODELS.get((path, catalogue))
    if cached is not None and all(
        (data if file == path else _bytes(file)) == read for file, read in cached[0].items()
    ):
        sources, model = cached
    else:
        sources = {path: data}  # taken before it is parsed: a change meanwhile reads anew
        _READING.files.append(path)
        _READING.sources.append(sources)
        try:
            model = read_tool_model(path, functools.partial(_base, catalogue=catalogue), data)
        finally:
            _READING.files.pop()
            _READING.sources.pop()
        _MODELS[(path, catalogue)] = (sources, model)
    if _READING.sources:  # the file being read extends this one: made of these too
        _READING.sources[-1].update(sources)
    return model


def _bytes(path: Path) -> bytes | None:
    """The bytes of ``path``; None if it cannot be read."""
    try:
        return path.read_bytes()
    except OSError:
        return None


def _base(name: str, where: Location, *, catalogue: ModelCatalogue) -> ToolModel:
    """The model an ``extends:`` names, found as :func:`find_model` finds one (a relative
    file path is relative to the extending file)."""
    path = Path(name)
    if path.suffix.lower() in (".yaml", ".yml") and not path.is_absolute():
        path = Path(where.file).parent / path
        name = str(path)
    if path.suffix.lower() in (".yaml", ".yml") and path.resolve() in _READING.files:
        chain = " → ".join(p.name for p in _READING.files)
        raise ToolModelError([Problem(where, f"{name} extends itself ({chain} → {path.name})")])
    try:
        return find_model(name, catalogue)
    except KeyError as exc:
        raise ToolModelError([Problem(where, str(exc.args[0]))]) from None


def find_model(model: str | Path | ToolModel, catalogue: ModelCatalogue = SHIPPED) -> ToolModel:
    """A tool model by name (in ``catalogue``, case-insensitive: shipped first), by file path
    (``.yaml``/``.yml``), or as given. An unknown name is a ``KeyError`` listing the known
    ones; a bad file a :class:`~pipeline.errors.ToolModelError`."""
    if isinstance(model, ToolModel):
        return model
    key = str(model)
    shipped = _named(_shipped(), key)
    if shipped is not None:
        return _read(shipped, SHIPPED)  # shipped files extend shipped models only
    path = Path(model)
    if path.suffix.lower() in (".yaml", ".yml") or path.is_file():
        if not path.is_file():
            raise ToolModelError([Problem(Location(str(path)), "no such tool-model file")])
        return _read(path.resolve(), catalogue)
    added = _named(dict(catalogue.added), key)
    if added is not None:
        return _read(added.resolve(), catalogue)
    known = sorted(catalogue.files(), key=str.upper)
    close = did_you_mean(key.upper(), [k.upper() for k in known])
    for name in known:  # say the names as their files write them
        close = close.replace(f"'{name.upper()}'", f"'{name}'")
    listing = (
        f"known: {', '.join(known)}"
        if len(known) <= 12
        else f"{len(known)} known: `gyropipe models` lists them"
    )
    raise KeyError(f"unknown tool model {key!r}{close} ({listing}; or give a .yaml file)")


def model_terms(model: ToolModel, site: ModelSite) -> list[Term]:
    """The terms of a model at a site, magnitudes in SI (m, rad, rad/h…), in the file's order."""
    return model.terms_for(lambda s: Quantities(s, site, model.parameters, model.name))


def term_covariances(
    survey: Survey,
    model: str | Path | ToolModel,
    site: ModelSite | None = None,
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    outside_validity: OutsideValidity = "refuse",
) -> tuple[list[str], FloatArray]:
    """Per-term NEV covariance (m, n, 3, 3) (m²) of a survey under a tool model (a
    :class:`ToolModel`, or a shipped model's name or a file, :func:`find_model`), and the
    term names. ``survey`` azimuths are true (rad); ``site`` gives what the model needs
    (:attr:`ToolModel.needs`: latitude, geomagnetic field); ``basis`` and ``surface_tie`` as
    in :func:`pipeline.uncertainty.model.station_jacobians` (the ISCWSA conventions by
    default). A station outside the model's range (see the module) is refused
    (:class:`OutsideValidityError`) or, ``outside_validity="flag"``, it and those below it
    get NaN."""
    tool = find_model(model)
    if outside_validity not in ("refuse", "flag"):
        raise ValueError(f"outside_validity must be 'refuse' or 'flag', not {outside_validity!r}")
    for label, values in (
        ("md", survey.md),
        ("inc", survey.inc),
        ("azi", survey.azi),
        ("tvd", survey.tvd),
    ):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise SurveyValueError(
                f"survey {label} is not finite at station(s) {bad[:5].tolist()}: an error model "
                "needs every station's MD, inclination, azimuth (true) and TVD"
            )
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
    n = within_range(survey, tool, outside_validity)
    if n == 0:
        return [t.name for t in tool.terms], np.full((len(tool.terms), survey.size, 3, 3), np.nan)
    head = _head(survey, n)
    shared = Quantities(head, where, tool.parameters, tool.name)  # derived ones cached

    def q(s: Survey) -> Quantities:
        return shared if s is head else Quantities(s, where, tool.parameters, tool.name)

    names, cov = term_covariance(head, tool.terms_for(q), basis=basis, surface_tie=surface_tie)
    n = within_bound(head, cov.sum(axis=0), tool.name, outside_validity)
    out = np.full((len(names), survey.size, 3, 3), np.nan)
    out[:, :n] = cov[:, :n]
    return names, out


def within_range(survey: Survey, tool: ToolModel, outside_validity: OutsideValidity) -> int:
    """How many leading stations of ``survey`` lie inside the model's inclination range (a
    station written at a limit is inside); one outside is an :class:`OutsideValidityError`
    naming it unless ``outside_validity`` is ``"flag"``."""
    lo, hi = np.radians(tool.inclination_range_deg)
    tol = 1e-9  # rad
    outside = np.flatnonzero((survey.inc < lo - tol) | (survey.inc > hi + tol))
    if outside.size == 0:
        return survey.size
    k = int(outside[0])
    if outside_validity == "refuse":
        lo_deg, hi_deg = tool.inclination_range_deg
        raise OutsideValidityError(
            f"tool model {tool.name} holds for inclinations {lo_deg:g}–{hi_deg:g}°: the station "
            f"at MD {survey.md[k]:g} m has {np.degrees(survey.inc[k]):g}° ({outside.size} "
            "station(s) outside the range); use a model that covers them, or "
            "outside_validity: flag for NaN σ there"
        )
    return k


def within_bound(
    survey: Survey, cov: FloatArray, model: str, outside_validity: OutsideValidity
) -> int:
    """How many leading stations have a σ (√ trace of their covariance ``cov`` (n, 3, 3),
    m²) within :data:`PHYSICAL_BOUND_M` + 2·|MD|; one beyond is an
    :class:`OutsideValidityError` unless ``outside_validity`` is ``"flag"``."""
    sigma = np.sqrt(np.abs(np.trace(cov, axis1=1, axis2=2)))
    beyond = np.flatnonzero(~(sigma <= 2.0 * np.abs(survey.md) + PHYSICAL_BOUND_M))
    if beyond.size == 0:
        return survey.size
    k = int(beyond[0])
    if outside_validity == "refuse":
        raise OutsideValidityError(
            f"tool model {model}: σ {sigma[k]:.4g} m at MD {survey.md[k]:g} m (inclination "
            f"{np.degrees(survey.inc[k]):g}°) is beyond any physical position error (2·MD + "
            f"{PHYSICAL_BOUND_M:g} m): the model does not hold there; outside_validity: flag "
            "gives such stations NaN σ"
        )
    return k


def bounded_covariance(
    survey: Survey,
    inside: int,
    compute: Callable[[Survey], FloatArray],
    model: str,
    outside_validity: OutsideValidity,
) -> FloatArray:
    """NEV covariance (n, 3, 3), m², of a survey: ``compute`` over its first ``inside``
    stations (those within their models' ranges, :func:`within_range`), NaN below them and
    from the first station beyond the physical bound (:func:`within_bound`, ``model`` naming
    the model(s) in its error)."""
    out: FloatArray = np.full((survey.size, 3, 3), np.nan)
    if inside == 0:
        return out
    head = _head(survey, inside)
    cov = compute(head)
    good = within_bound(head, cov, model, outside_validity)
    out[:good] = cov[:good]
    return out


def _head(survey: Survey, n: int) -> Survey:
    """The first ``n`` stations of a survey."""
    if n == survey.size:
        return survey
    return Survey.of(survey.md[:n], survey.inc[:n], survey.azi[:n], survey.tvd[:n])


def covariance(
    survey: Survey,
    model: str | Path | ToolModel,
    site: ModelSite | None = None,
    *,
    basis: str = "balanced_tangent",
    surface_tie: bool = True,
    outside_validity: OutsideValidity = "refuse",
) -> FloatArray:
    """Total NEV covariance (n, 3, 3) (m², north/east/vertical-down) of each station of a
    survey under a tool model (see :func:`term_covariances`; NaN at flagged stations)."""
    _, terms = term_covariances(
        survey, model, site, basis=basis, surface_tie=surface_tie, outside_validity=outside_validity
    )
    total: FloatArray = terms.sum(axis=0)
    return total


#: Field names of the earlier tool dataclasses that name a parameter of the model file.
PARAMETER_ALIASES = {"xcl_tortuosity": "tortuosity"}


def configure(
    model: str | Path | ToolModel,
    overrides: Mapping[str, float],
    catalogue: ModelCatalogue = SHIPPED,
) -> ToolModel:
    """A model (found in ``catalogue``, :func:`find_model`) with ``overrides``: term
    magnitudes (by term name, or a field name such as ``gxy_gd``, :func:`term_for`) and
    parameters (by name), each in the unit its file gives it. An unknown key is a
    ``KeyError`` naming the model's terms."""
    tool = find_model(model, catalogue)
    magnitudes: dict[str, float] = {}
    params: dict[str, float] = {}
    for key, value in overrides.items():
        param = PARAMETER_ALIASES.get(key, key)
        if param in tool.parameters:
            params[param] = value
        else:
            magnitudes[term_for(tool, key)] = value
    return tool.with_magnitudes(magnitudes).with_parameters(params)


def term_for(model: ToolModel, key: str) -> str:
    """The term a magnitude key names: a term name, or a field name (``gxy_b1``: lower
    case, ``_`` for ``-``; the term's trailing R/S mode letter may be left out)."""
    names = [t.name for t in model.terms]
    if key in names:
        return key
    wanted = key.upper().replace("_", "-")
    for name in names:
        if name == wanted or (name[:-1] == wanted and name[-1] in "RS"):
            return name
    raise KeyError(
        f"{model.name} has no term or parameter {key!r} (terms: {', '.join(names)}; "
        f"parameters: {', '.join(model.parameters) or 'none'})"
    )

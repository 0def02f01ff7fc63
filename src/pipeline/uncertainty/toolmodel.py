"""Tool-model files: ISCWSA/OWSG error models as data (YAML), read into a :class:`ToolModel`.

A file lists the model's terms in the ISCWSA/OWSG tool-model form — per term its name, the
measurements it acts on, propagation mode, 1σ magnitude and unit, and its weighting
function: a published one by code (:data:`~pipeline.uncertainty.weightfns.WEIGHT_FUNCTIONS`)
or formulas over named survey quantities (:mod:`pipeline.uncertainty.quantities`,
:mod:`pipeline.uncertainty.formula`). A model may extend another (``extends:``), changing
magnitudes, parameters and terms. A model states the inclinations it holds for
(``validity:``, the published sheet's range; a child inherits its parent's) and a term may
switch at an inclination (``switch:``: its weight frozen at the value it has there, or zero,
above or below it; SPE 90408's stationary terms above a continuous gyro's static end
inclination). The format is described in ``docs/tool-models.md``.

Every problem of a file is a :class:`~pipeline.errors.ToolModelError` naming the file, line
and column.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from pipeline.errors import Location, Problem, SpecError, ToolModelError, did_you_mean
from pipeline.uncertainty.formula import Formula, FormulaError
from pipeline.uncertainty.model import Propagation
from pipeline.uncertainty.quantities import (
    LATITUDE_NAMES,
    MAGNETIC_NAMES,
    SITE_NAMES,
    SURVEY_NAMES,
    Quantities,
)
from pipeline.uncertainty.terms import STANDARD_G, Frame, Survey, Term, stack
from pipeline.uncertainty.weightfns import WEIGHT_FUNCTIONS, WeightFunction
from pipeline.yamlsource import SourceMap, load_mapping, validate_located

__all__ = ["UNITS", "FormulaWeight", "Switch", "ToolModel", "ToolTerm", "parse_tool_model"]

FloatArray = NDArray[np.float64]
FORMAT = "gyropipe-tool-model/1"
_DEG = np.pi / 180.0

UNITS: dict[str, tuple[str, float]] = {
    "m": ("m", 1.0),
    "ft": ("m", 0.3048),
    "mm": ("m", 1e-3),
    "-": ("-", 1.0),
    "ppm": ("-", 1e-6),
    "%": ("-", 1e-2),
    "1/m": ("1/m", 1.0),
    "1/ft": ("1/m", 1.0 / 0.3048),
    "rad": ("rad", 1.0),
    "mrad": ("rad", 1e-3),
    "deg": ("rad", _DEG),
    "rad/h": ("rad/h", 1.0),
    "deg/h": ("rad/h", _DEG),
    "rad/h/g": ("rad/h/g", 1.0),
    "deg/h/g": ("rad/h/g", _DEG),
    "rad/sqrt(h)": ("rad/sqrt(h)", 1.0),
    "deg/sqrt(h)": ("rad/sqrt(h)", _DEG),
    "deg/√h": ("rad/sqrt(h)", _DEG),
    "nT": ("nT", 1.0),
    "m/s2": ("m/s2", 1.0),
    "m/s²": ("m/s2", 1.0),
    "mg": ("m/s2", 1e-3 * STANDARD_G),
    "ug": ("m/s2", 1e-6 * STANDARD_G),
    "µg": ("m/s2", 1e-6 * STANDARD_G),
    "rad.nT": ("rad.nT", 1.0),
    "deg.nT": ("rad.nT", _DEG),
    "deg·nT": ("rad.nT", _DEG),
    "m/h": ("m/h", 1.0),
    "ft/h": ("m/h", 0.3048),
    "rad/m": ("rad/m", 1.0),
    "deg/30m": ("rad/m", _DEG / 30.0),
    "deg/100ft": ("rad/m", _DEG / 30.48),
}
"""Units a magnitude or parameter may be given in: unit → (SI dimension, factor to it)."""

MEASUREMENTS = ("depth", "inc", "azi", "nev")
_DIA_KEYS = ("depth", "inc", "azi", "azi_sin_inc")
_NEV_KEYS = ("north", "east", "vertical")


# ------------------------------------------------------------------ the file, as written


class _Parameter(BaseModel):
    model_config = ConfigDict(extra="forbid")
    value: float
    unit: str = "-"
    description: str = ""


class _Formulas(BaseModel):
    """Weights as formulas: ∂MD, ∂I and ∂A (or ∂A·sin I) per unit ε, or the NEV error."""

    model_config = ConfigDict(extra="forbid")
    depth: str | float | None = None
    inc: str | float | None = None
    azi: str | float | None = None
    azi_sin_inc: str | float | None = None
    north: str | float | None = None
    east: str | float | None = None
    vertical: str | float | None = None


class _Switch(BaseModel):
    """A weight that switches at an inclination (a parameter's name): ``above`` it live,
    frozen at its value at the switch, or zero; ``below`` (at or under) it live or zero."""

    model_config = ConfigDict(extra="forbid")
    at: str = Field(min_length=1)
    above: Literal["live", "freeze", "zero"] = "live"
    below: Literal["live", "zero"] = "live"


class _Term(BaseModel):
    model_config = ConfigDict(extra="forbid")
    name: str = Field(min_length=1)
    acts_on: list[Literal["depth", "inc", "azi", "nev"]] = Field(min_length=1)
    mode: Propagation
    magnitude: float = Field(ge=0, allow_inf_nan=False)
    unit: str
    weight: str | _Formulas
    switch: _Switch | None = None
    description: str = ""


class _Validity(BaseModel):
    """Where a model holds (the published sheet's range): inclination limits in degrees."""

    model_config = ConfigDict(extra="forbid")
    inclination_deg: tuple[float, float] = (0.0, 180.0)


class _File(BaseModel):
    model_config = ConfigDict(extra="forbid")
    format: Literal["gyropipe-tool-model/1"]
    name: str = Field(min_length=1)
    title: str = ""
    source: str = ""
    revision: str = ""
    extends: str | None = None
    validity: _Validity | None = None
    parameters: dict[str, _Parameter] = Field(default_factory=dict)
    magnitudes: dict[str, float] = Field(default_factory=dict)
    remove: list[str] = Field(default_factory=list)
    terms: list[_Term] = Field(default_factory=list)


# ------------------------------------------------------------------ the model, as evaluated


@dataclass(frozen=True)
class FormulaWeight:
    """Weights given as formulas (``frame="dia"``: depth, inc, azi or azi_sin_inc; ``"nev"``:
    north, east, vertical), each a :class:`Formula` (absent components are 0)."""

    frame: Frame
    formulas: Mapping[str, Formula]

    @property
    def names(self) -> frozenset[str]:
        out: frozenset[str] = frozenset()
        for f in self.formulas.values():
            out |= f.names
        return out

    def __call__(self, q: Quantities) -> FloatArray:
        values = {name: q[name] for name in self.names}

        def col(key: str) -> FloatArray | float:
            f = self.formulas.get(key)
            return 0.0 if f is None else f.evaluate(values)

        if self.frame == "nev":
            return stack(col("north"), col("east"), col("vertical"), q.n)
        alpha = col("azi_sin_inc") if "azi_sin_inc" in self.formulas else col("azi")
        if "azi" in self.formulas:
            alpha = np.multiply(alpha, np.sin(q.inc))
        return stack(col("depth"), col("inc"), alpha, q.n)


@dataclass(frozen=True)
class Switch:
    """A term's weight switching at the inclination of parameter ``at`` (rad): at stations
    above it ``live``, ``freeze`` or ``zero``; at and below it ``live`` or ``zero``. A frozen
    weight holds the measurement error the term has at the switch — ∂MD, ∂I and ∂A (so the
    horizontal tilt ∂A·sin I follows the station's inclination) — interpolated linearly
    between the two stations across which the survey rises through the switch, and again
    at every rise after a drop back below it."""

    at: str
    above: Literal["live", "freeze", "zero"] = "live"
    below: Literal["live", "zero"] = "live"

    def apply(self, w: FloatArray, inc: FloatArray, gate: float, frame: Frame) -> FloatArray:
        """Weights ``w`` (n, 3) in ``frame`` at inclinations ``inc`` (rad) switched at
        ``gate`` (rad)."""
        above = inc > gate
        out = w.copy()
        if self.below == "zero":
            out[~above] = 0.0
        if self.above == "zero":
            out[above] = 0.0
        elif self.above == "freeze":
            under = np.flatnonzero(~above)
            for j in np.flatnonzero(above & ~np.concatenate(([False], above[:-1]))):
                later = under[under > j]
                rows = slice(j, later[0] if later.size else inc.size)
                frozen, sin_at = self._at_switch(w, inc, int(j), gate)
                out[rows] = frozen
                if frame == "dia":  # ∂A held: the tilt α = ∂A·sin I of each station
                    out[rows, 2] = frozen[2] / sin_at * np.sin(inc[rows])
        return out

    @staticmethod
    def _at_switch(w: FloatArray, inc: FloatArray, j: int, gate: float) -> tuple[Any, float]:
        """The weight row at the switch inclination the survey rises through into station
        ``j``, and the sine of that inclination."""
        if j == 0:
            return w[0], float(np.sin(inc[0]))
        if inc[j - 1] >= gate:  # the station before is at the switch
            return w[j - 1], float(np.sin(inc[j - 1]))
        f = (gate - inc[j - 1]) / (inc[j] - inc[j - 1])
        return w[j - 1] + f * (w[j] - w[j - 1]), float(np.sin(gate))


@dataclass(frozen=True)
class ToolTerm:
    """One term of a tool model: magnitude in ``unit`` (``sigma`` in SI), its weights and
    the inclination switch they follow (None: none)."""

    name: str
    acts_on: tuple[str, ...]
    mode: Propagation
    magnitude: float
    unit: str
    weight: WeightFunction | FormulaWeight
    location: Location
    description: str = ""
    switch: Switch | None = None

    @property
    def sigma(self) -> float:
        """1σ magnitude in SI."""
        return self.magnitude * UNITS[self.unit][1]

    @property
    def frame(self) -> Frame:
        return self.weight.frame

    @property
    def code(self) -> str:
        """The weighting function's code, or ``formula``."""
        return self.weight.code if isinstance(self.weight, WeightFunction) else "formula"

    def weights(self, q: Quantities) -> FloatArray:
        """Weights (n, 3) per unit ε (SI) over the quantities ``q``; a non-finite weight is a
        :class:`ToolModelError` naming the term's place in its file."""
        fn: Callable[[Quantities], FloatArray] = (
            self.weight.fn if isinstance(self.weight, WeightFunction) else self.weight
        )
        with np.errstate(all="ignore"):
            w = fn(q)
            if self.switch is not None:
                w = self.switch.apply(w, q.inc, q.parameter(self.switch.at), self.frame)
        bad = ~np.isfinite(w).all(axis=1)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            raise ToolModelError(
                [
                    Problem(
                        self.location,
                        f"term {self.name}: weight not finite at station {k} "
                        f"(MD {q.md[k]:g} m, inc {np.degrees(q.inc[k]):g}°) and "
                        f"{int(bad.sum()) - 1} more",
                    )
                ]
            )
        return w


@dataclass(frozen=True)
class ToolModel:
    """An error model: its terms and parameters (SI values; ``units`` as written) and the
    inclinations it holds for, ``inclination_range_deg`` (deg, inclusive)."""

    name: str
    terms: tuple[ToolTerm, ...]
    parameters: Mapping[str, float] = field(default_factory=dict)
    units: Mapping[str, str] = field(default_factory=dict)
    title: str = ""
    source: str = ""
    revision: str = ""
    file: str = ""
    inclination_range_deg: tuple[float, float] = (0.0, 180.0)
    files: tuple[str, ...] = ()
    """the model's file and the files it extends, outermost first"""
    file_sha256: Mapping[str, str] = field(default_factory=dict)
    """file of :attr:`files` → SHA-256 of the bytes it was parsed from (a file whose model
    was parsed from text, :func:`parse_tool_model`, has none)"""

    @property
    def needs(self) -> frozenset[str]:
        """The site quantities the model reads: ``latitude`` and/or ``magnetic``."""
        names: set[str] = set()
        out: set[str] = set()
        for t in self.terms:
            if isinstance(t.weight, FormulaWeight):
                names |= t.weight.names
            else:
                out |= t.weight.site
        if names & LATITUDE_NAMES:
            out.add("latitude")
        if names & MAGNETIC_NAMES:
            out.add("magnetic")
        return frozenset(out)

    def term(self, name: str) -> ToolTerm:
        for t in self.terms:
            if t.name == name:
                return t
        raise KeyError(name)

    def with_magnitudes(self, values: Mapping[str, float]) -> ToolModel:
        """A copy with term magnitudes replaced (each in its term's unit)."""
        unknown = sorted(set(values) - {t.name for t in self.terms})
        if unknown:
            raise KeyError(f"{self.name} has no term(s) {unknown}")
        terms = tuple(
            replace(t, magnitude=float(values[t.name])) if t.name in values else t
            for t in self.terms
        )
        return replace(self, terms=terms)

    def with_parameters(self, values: Mapping[str, float]) -> ToolModel:
        """A copy with parameters replaced (each in the unit the file gives it)."""
        unknown = sorted(set(values) - set(self.parameters))
        if unknown:
            raise KeyError(f"{self.name} has no parameter(s) {unknown}")
        params = dict(self.parameters)
        for k, v in values.items():
            params[k] = float(v) * UNITS[self.units[k]][1]
        return replace(self, parameters=params)

    def terms_for(self, q: Callable[[Survey], Quantities]) -> list[Term]:
        """The model's terms as :class:`~pipeline.uncertainty.terms.Term` objects whose
        weights read the quantities ``q(survey)`` of each survey."""
        return [Term(t.name, t.mode, t.sigma, _bound(t, q), frame=t.frame) for t in self.terms]


def _bound(t: ToolTerm, q: Callable[[Survey], Quantities]) -> Callable[[Survey], FloatArray]:
    return lambda s: t.weights(q(s))


# ------------------------------------------------------------------ reading a file


def parse_tool_model(
    text: str, file: str, base: Callable[[str, Location], ToolModel] | None = None
) -> ToolModel:
    """The model of a tool-model file's ``text`` (``file`` names it in errors).
    ``base(name, where)`` resolves the model an ``extends:`` names."""
    try:
        raw, source, problems = load_mapping(text, file, "a tool model file must be a mapping")
        spec = validate_located(_File, raw, source, problems)
    except SpecError as exc:
        raise ToolModelError(exc.problems) from None
    if problems:
        raise ToolModelError(problems)
    return _build(spec, source, base)


def _build(
    spec: _File, source: SourceMap, base: Callable[[str, Location], ToolModel] | None
) -> ToolModel:
    problems: list[Problem] = []
    parent: ToolModel | None = None
    if spec.extends is not None:
        if base is None:
            raise ToolModelError(
                [Problem(source.locate(("extends",)), "extends: no catalogue to look it up in")]
            )
        parent = base(spec.extends, source.locate(("extends",)))
    params = dict(parent.parameters) if parent else {}
    units = dict(parent.units) if parent else {}
    for name, p in spec.parameters.items():
        where = source.locate(("parameters", name))
        if not name.isidentifier() or name in SURVEY_NAMES | SITE_NAMES:
            problems.append(
                Problem(
                    source.locate(("parameters", name), key=True),
                    f"parameter name {name!r} must be an identifier and not a survey or site "
                    "quantity's name",
                )
            )
            continue
        if p.unit not in UNITS:
            problems.append(_unit_problem(source.locate(("parameters", name, "unit")), p.unit))
            continue
        if not math.isfinite(p.value):
            problems.append(Problem(where, f"parameter {name}: value must be finite"))
            continue
        params[name], units[name] = p.value * UNITS[p.unit][1], p.unit
    names = set(params) | SURVEY_NAMES | SITE_NAMES
    terms: list[ToolTerm] = list(parent.terms) if parent else []
    have = {t.name for t in terms}
    for i, name in enumerate(spec.remove):
        if name not in have:
            problems.append(Problem(source.locate(("remove", i)), f"no term {name!r} to remove"))
    terms = [t for t in terms if t.name not in spec.remove]
    for name, value in spec.magnitudes.items():
        where = source.locate(("magnitudes", name), key=True)
        if name not in {t.name for t in terms}:
            problems.append(Problem(where, f"no term {name!r} to set the magnitude of"))
        elif not (math.isfinite(value) and value >= 0):
            problems.append(Problem(where, f"magnitude of {name} must be finite and ≥ 0"))
    terms = [
        replace(t, magnitude=float(spec.magnitudes[t.name])) if t.name in spec.magnitudes else t
        for t in terms
    ]
    for i, raw in enumerate(spec.terms):
        term = _term(raw, ("terms", i), source, names, problems)
        if term is None:
            continue
        if term.name in {t.name for t in terms}:
            problems.append(Problem(term.location, f"duplicate term {term.name!r}"))
            continue
        terms.append(term)
    for t in terms:
        if t.switch is not None and t.switch.at not in params:
            problems.append(
                Problem(t.location, f"term {t.name}: switch at {t.switch.at!r}, not a parameter")
            )
        if isinstance(t.weight, WeightFunction):
            missing = [p for p in t.weight.parameters if p not in params]
            if missing:
                problems.append(
                    Problem(t.location, f"term {t.name} ({t.code}) needs parameter(s) {missing}")
                )
    if not terms:
        problems.append(Problem(source.locate(("terms",)), "a tool model needs terms"))
    validity = parent.inclination_range_deg if parent else (0.0, 180.0)
    if spec.validity is not None:
        lo, hi = validity = spec.validity.inclination_deg
        if not 0.0 <= lo < hi <= 180.0:
            problems.append(
                Problem(
                    source.locate(("validity", "inclination_deg")),
                    f"inclination range [{lo:g}, {hi:g}]° must rise within 0–180°",
                )
            )
    if problems:
        raise ToolModelError(problems)
    return ToolModel(
        name=spec.name,
        terms=tuple(terms),
        parameters=params,
        units=units,
        title=spec.title,  # not the parent's: a changed model is another tool
        source=spec.source or (parent.source if parent else ""),
        revision=spec.revision,
        file=source.file,
        inclination_range_deg=(float(validity[0]), float(validity[1])),
        files=(source.file, *(parent.files if parent else ())),
        file_sha256=dict(parent.file_sha256) if parent else {},
    )


def _unit_problem(where: Location, unit: str) -> Problem:
    return Problem(where, f"unknown unit {unit!r}; known: {', '.join(UNITS)}")


def _term(
    raw: _Term, path: tuple[str | int, ...], source: SourceMap, names: set[str], out: list[Problem]
) -> ToolTerm | None:
    where = source.locate(path)
    if raw.unit not in UNITS:
        out.append(_unit_problem(source.locate((*path, "unit")), raw.unit))
        return None
    acts_on = tuple(dict.fromkeys(raw.acts_on))
    if "nev" in acts_on and len(acts_on) > 1:
        out.append(Problem(source.locate((*path, "acts_on")), "nev cannot be mixed with D/I/A"))
        return None
    weight: WeightFunction | FormulaWeight
    if isinstance(raw.weight, str):
        code = raw.weight
        wf = WEIGHT_FUNCTIONS.get(code)
        wloc = source.locate((*path, "weight"))
        if wf is None:
            out.append(
                Problem(
                    wloc,
                    f"unknown weighting function {code!r}{did_you_mean(code, WEIGHT_FUNCTIONS)}",
                )
            )
            return None
        if set(acts_on) != set(wf.acts_on):
            out.append(
                Problem(
                    source.locate((*path, "acts_on")),
                    f"{code} acts on {sorted(wf.acts_on)}, not {sorted(acts_on)}",
                )
            )
            return None
        dim = UNITS[raw.unit][0]
        if dim != wf.dimension:
            out.append(
                Problem(
                    source.locate((*path, "unit")),
                    f"{code} takes a magnitude in {wf.dimension} (or a unit of it), "
                    f"not {raw.unit!r}",
                )
            )
            return None
        weight = wf
    else:
        formulas = _formulas(raw.weight, acts_on, (*path, "weight"), source, names, out)
        if formulas is None:
            return None
        weight = formulas
    switch = None if raw.switch is None else Switch(**raw.switch.model_dump())
    return ToolTerm(
        raw.name, acts_on, raw.mode, raw.magnitude, raw.unit, weight, where, raw.description, switch
    )


def _formulas(
    raw: _Formulas,
    acts_on: tuple[str, ...],
    path: tuple[str | int, ...],
    source: SourceMap,
    names: set[str],
    out: list[Problem],
) -> FormulaWeight | None:
    given = {k: v for k, v in raw.model_dump().items() if v is not None}
    frame: Frame = "nev" if "nev" in acts_on else "dia"
    allowed = _NEV_KEYS if frame == "nev" else _DIA_KEYS
    wrong = sorted(set(given) - set(allowed))
    if "azi" in given and "azi_sin_inc" in given:
        wrong.append("azi_sin_inc (with azi)")
    if frame == "dia":
        acted = {"azi" if k == "azi_sin_inc" else k for k in given}
        wrong += sorted(k for k in acted - set(acts_on) if k in _DIA_KEYS)
    if wrong or not given:
        out.append(
            Problem(
                source.locate(path),
                f"weight formulas for {list(acts_on)} take {list(allowed)} (one azimuth form), "
                f"at least one of them: got {sorted(given)}",
            )
        )
        return None
    parsed: dict[str, Formula] = {}
    for key, text in given.items():
        try:
            parsed[key] = Formula.parse(text, frozenset(names))
        except FormulaError as exc:
            loc = source.locate((*path, key))
            column = loc.column + exc.column if exc.column and loc.column else loc.column
            out.append(Problem(Location(loc.file, loc.line, column), f"{key}: {exc}"))
    return FormulaWeight(frame, parsed) if len(parsed) == len(given) else None


def read_tool_model(
    path: Path, base: Callable[[str, Location], ToolModel] | None = None, data: bytes | None = None
) -> ToolModel:
    """The model of the tool-model file at ``path``, with the SHA-256 of the bytes parsed
    (:attr:`ToolModel.file_sha256`). ``data``: the file's bytes where the caller has read
    them, parsed as they are (the file is not read again: the bytes parsed are the bytes
    hashed); else the file is read here."""
    try:
        if data is None:
            data = path.read_bytes()
        text = data.decode("utf-8").replace("\r\n", "\n").replace("\r", "\n")  # as read_text
    except (OSError, UnicodeDecodeError) as exc:
        raise ToolModelError([Problem(Location(str(path)), f"cannot read: {exc}")]) from None
    model = parse_tool_model(text, str(path), base)
    digest = hashlib.sha256(data).hexdigest()
    return replace(model, file_sha256={str(path): digest, **model.file_sha256})


def describe(model: ToolModel) -> dict[str, Any]:
    """A plain summary of a model (name, title, source, needs, terms) for listings."""
    return {
        "name": model.name,
        "title": model.title,
        "source": model.source,
        "file": model.file,
        "needs": sorted(model.needs),
        "inclination_range": list(model.inclination_range_deg),
        "terms": [t.name for t in model.terms],
    }

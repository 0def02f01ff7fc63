"""Weighting-function formulas of tool-model files: a restricted arithmetic over numpy.

A formula is a Python expression parsed with :mod:`ast` and checked before it is evaluated:
only numbers, the names it is given, ``+ - * / ** %``, comparisons, ``and``/``or``/``not``,
``a if c else b`` and calls of the functions in :data:`FUNCTIONS` are allowed; there is no
attribute access, subscript, keyword argument, lambda or comprehension, and nothing is
passed to :func:`eval`. Evaluation is element-wise over station arrays (numpy broadcasting);
``a if c else b`` and the boolean operators are element-wise too (``np.where``,
``np.logical_and``…), so both branches are computed.
"""

from __future__ import annotations

import ast
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["CONSTANTS", "FUNCTIONS", "Formula", "FormulaError"]

FloatArray = NDArray[np.float64]
Value = Any  # a float or a numpy array


def _previous(x: Value) -> Value:
    """Each station's predecessor value (station 0 its own)."""
    a = np.asarray(x, dtype=np.float64)
    return a if a.ndim == 0 else np.concatenate((a[:1], a[:-1]))


def _wrap(x: Value) -> Value:
    """An angle (rad) wrapped to (−π, π]."""
    return np.angle(np.exp(1j * np.asarray(x, dtype=np.float64)))


FUNCTIONS: dict[str, Callable[..., Value]] = {
    "sin": np.sin,
    "cos": np.cos,
    "tan": np.tan,
    "arcsin": np.arcsin,
    "arccos": np.arccos,
    "arctan": np.arctan,
    "arctan2": np.arctan2,
    "sqrt": np.sqrt,
    "abs": np.abs,
    "exp": np.exp,
    "log": np.log,
    "sign": np.sign,
    "radians": np.radians,
    "degrees": np.degrees,
    "maximum": np.maximum,
    "minimum": np.minimum,
    "clip": np.clip,
    "where": np.where,
    "prev": _previous,
    "wrap": _wrap,
    "cumsum": np.cumsum,
}
"""Functions a formula may call (positional arguments only): numpy's element-wise functions,
``prev(x)`` (the previous station's value, station 0 its own), ``wrap(a)`` (angle to
(−π, π]) and ``cumsum(x)`` (running sum down the stations)."""

ARITY: dict[str, int] = {"arctan2": 2, "maximum": 2, "minimum": 2, "clip": 3, "where": 3}
"""Arguments each function takes (1 unless listed)."""

CONSTANTS: dict[str, float] = {"pi": float(np.pi)}
"""Names every formula knows besides its quantities."""

_BINARY: dict[type[ast.operator], Callable[[Value, Value], Value]] = {
    ast.Add: np.add,
    ast.Sub: np.subtract,
    ast.Mult: np.multiply,
    ast.Div: np.true_divide,
    ast.Pow: np.power,
    ast.Mod: np.mod,
}
_UNARY: dict[type[ast.unaryop], Callable[[Value], Value]] = {
    ast.USub: np.negative,
    ast.UAdd: np.positive,
    ast.Not: np.logical_not,
}
_COMPARE: dict[type[ast.cmpop], Callable[[Value, Value], Value]] = {
    ast.Lt: np.less,
    ast.LtE: np.less_equal,
    ast.Gt: np.greater,
    ast.GtE: np.greater_equal,
    ast.Eq: np.equal,
    ast.NotEq: np.not_equal,
}
#: Longest formula text accepted (characters): a guard against pathological input.
MAX_LENGTH = 2000


class FormulaError(ValueError):
    """A formula cannot be parsed or uses something not allowed; ``column`` is 1-based
    within the formula text (0 if unknown)."""

    def __init__(self, message: str, column: int = 0) -> None:
        super().__init__(message)
        self.column = column


@dataclass(frozen=True)
class Formula:
    """A checked formula: its text, parsed tree and the quantity names it reads."""

    text: str
    tree: ast.Expression
    names: frozenset[str]

    @classmethod
    def parse(cls, text: str | float | int, known: frozenset[str] | None = None) -> Formula:
        """Parse and check ``text`` (a number is a constant formula). ``known``: the names
        the formula may read besides :data:`CONSTANTS` (None: any name)."""
        if isinstance(text, bool) or not isinstance(text, str | float | int):
            raise FormulaError(f"a formula must be a number or a string, not {text!r}")
        source = str(text).strip()
        if len(source) > MAX_LENGTH:
            raise FormulaError(f"formula longer than {MAX_LENGTH} characters")
        try:
            with warnings.catch_warnings():  # e.g. "invalid decimal literal" in `1if x else y`
                warnings.simplefilter("ignore")
                tree = ast.parse(source, mode="eval")
        except SyntaxError as exc:
            raise FormulaError(f"not a formula: {exc.msg}", exc.offset or 0) from None
        names: set[str] = set()
        called = {id(n.func) for n in ast.walk(tree) if isinstance(n, ast.Call)}
        for node in ast.walk(tree):
            if id(node) not in called:
                _check(node, names)
        unknown = names - set(CONSTANTS) - (known if known is not None else names)
        if unknown:
            allowed = sorted((known or frozenset()) | set(CONSTANTS))
            raise FormulaError(f"unknown name(s) {sorted(unknown)}; known: {allowed}")
        return cls(source, tree, frozenset(names - set(CONSTANTS)))

    def evaluate(self, values: Mapping[str, Value]) -> Value:
        """The formula's value over ``values`` (floats or station arrays)."""
        with np.errstate(all="ignore"):
            return _eval(self.tree.body, values)


def _check(node: ast.AST, names: set[str]) -> None:
    """Refuse every node kind but the arithmetic ones; collect the names read."""
    col = getattr(node, "col_offset", -1) + 1
    match node:
        case ast.Expression() | ast.Load() | ast.operator() | ast.unaryop() | ast.cmpop():
            return
        case ast.BinOp(op=op) if type(op) not in _BINARY:
            raise FormulaError(f"operator {type(op).__name__} not allowed", col)
        case ast.UnaryOp(op=op) if type(op) not in _UNARY:
            raise FormulaError(f"operator {type(op).__name__} not allowed", col)
        case ast.Compare(ops=ops) if any(type(op) not in _COMPARE for op in ops):
            raise FormulaError("only <, <=, >, >=, == and != comparisons are allowed", col)
        case ast.boolop() | ast.BinOp() | ast.UnaryOp() | ast.Compare() | ast.IfExp():
            return
        case ast.BoolOp():
            return
        case ast.Constant(value=value):
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise FormulaError(f"only numbers may be written in a formula, not {value!r}", col)
            return
        case ast.Name(id=name):
            names.add(name)
            return
        case ast.Call(func=ast.Name(id=fn), args=args, keywords=[]):
            if fn not in FUNCTIONS:
                raise FormulaError(f"unknown function {fn!r}; known: {sorted(FUNCTIONS)}", col)
            if len(args) != ARITY.get(fn, 1):
                raise FormulaError(f"{fn}() takes {ARITY.get(fn, 1)} argument(s)", col)
            return
        case ast.Call():
            raise FormulaError(
                "only the listed functions may be called, by name, positionally", col
            )
    raise FormulaError(f"{type(node).__name__} not allowed in a formula", col)


def _eval(node: ast.expr, values: Mapping[str, Value]) -> Value:
    match node:
        case ast.Constant(value=int() | float() as number):
            return float(number)
        case ast.Name(id=name):
            return CONSTANTS[name] if name in CONSTANTS else values[name]
        case ast.BinOp(left=left, op=op, right=right):
            return _BINARY[type(op)](_eval(left, values), _eval(right, values))
        case ast.UnaryOp(op=op, operand=operand):
            return _UNARY[type(op)](_eval(operand, values))
        case ast.BoolOp(op=op, values=operands):
            combine = np.logical_and if isinstance(op, ast.And) else np.logical_or
            out = _eval(operands[0], values)
            for item in operands[1:]:
                out = combine(out, _eval(item, values))
            return out
        case ast.Compare(left=left, ops=ops, comparators=rights):
            out, a = None, _eval(left, values)
            for cmp, right in zip(ops, rights, strict=True):
                b = _eval(right, values)
                step = _COMPARE[type(cmp)](a, b)
                out = step if out is None else np.logical_and(out, step)
                a = b
            return out
        case ast.IfExp(test=test, body=body, orelse=orelse):
            return np.where(_eval(test, values), _eval(body, values), _eval(orelse, values))
        case ast.Call(func=ast.Name(id=fn), args=args):
            return FUNCTIONS[fn](*(_eval(a, values) for a in args))
    raise FormulaError(f"{type(node).__name__} not allowed in a formula")  # checked at parse

"""Table contracts: a pydantic model per port, compiled once into an Arrow schema and
vectorised checks.

A contract is a subclass of :class:`TableContract` with one field per column::

    class Stations(TableContract):
        md: float = column(unit="m", ge=0, monotonic="strict", description="measured depth")
        inc: float = column(unit="deg", ge=0, le=180, description="inclination")

The field's Python type gives the Arrow type (``float`` → float64, ``int`` → int64, ``str`` →
string, ``bool`` → bool); ``X | None`` makes the column nullable. Units live in each Arrow
field's metadata under ``unit`` and are checked; azimuth columns also carry
``north_reference`` (true, grid or magnetic). Checks run on whole columns with NumPy and
``pyarrow.compute``; rows are pulled out only to describe a failure.
"""

from __future__ import annotations

import types
from collections.abc import Iterator
from dataclasses import dataclass, replace
from functools import cache
from typing import Any, ClassVar, Literal, Union, cast, get_args, get_origin

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
from pydantic import BaseModel, ConfigDict, Field

from pipeline.errors import ContractViolation, RuleFailure
from pipeline.streams import TableStream

UNIT_KEY = b"unit"
SOURCE_KEY = b"gyropipe.source"
"""Schema metadata: the file a table was read from (named in contract violations)."""
SOURCE_LINE = "source_line"
"""Optional column: the 1-based file line of each row (named in contract violations)."""
NORTH_KEY = b"north_reference"
NORTH_REFERENCES = ("true", "grid", "magnetic")
DESCRIPTION_KEY = b"description"
"""Field metadata: a column's description (a log curve's, kept by its reader and its writer)."""
Monotonic = Literal["increasing", "strict"]
EXAMPLES = 5
VERTICAL_TOLERANCE = 1.0
"""deg: a column declared ``undefined_at_vertical`` may hold NaN (an azimuth no inclination
defines) only on rows whose ``inc`` is within this of 0° or 180°."""

_ARROW_TYPES: dict[type, pa.DataType] = {
    float: pa.float64(),
    int: pa.int64(),
    str: pa.string(),
    bool: pa.bool_(),
}


def column(
    *,
    unit: str | None,
    description: str,
    ge: float | None = None,
    le: float | None = None,
    gt: float | None = None,
    lt: float | None = None,
    monotonic: Monotonic | None = None,
    min_step: float | None = None,
    north_reference: bool = False,
    finite: bool = True,
    undefined_at_vertical: bool = False,
    default: Any = ...,
) -> Any:
    """Declare a contract column.

    ``unit`` is the canonical unit string stored in the Arrow field metadata (``None`` for
    dimensionless or text columns). ``monotonic`` is ``"increasing"`` (non-decreasing) or
    ``"strict"`` (strictly increasing), within each group when the contract sets
    ``group_by``; ``min_step`` (with ``"strict"``) is the smallest step allowed between
    consecutive values (in ``unit``). ``north_reference`` requires the field to state its
    north reference.
    ``finite`` forbids NaN and ±inf in float columns; ``undefined_at_vertical`` allows NaN
    (an azimuth that is undefined) on rows whose ``inc`` column is within
    :data:`VERTICAL_TOLERANCE` of vertical, and nowhere else. A ``default`` makes the column
    optional.
    """
    extra: dict[str, Any] = {"x-unit": unit, "x-finite": finite}
    if undefined_at_vertical:
        extra["x-undefined-at-vertical"] = True
    if monotonic:
        extra["x-monotonic"] = monotonic
    if min_step is not None:
        extra["x-min-step"] = min_step
    if north_reference:
        extra["x-north-reference"] = list(NORTH_REFERENCES)
    return Field(
        default,
        description=description,
        ge=ge,
        le=le,
        gt=gt,
        lt=lt,
        json_schema_extra=extra,
    )


class TableContract(BaseModel):
    """Base class of table contracts; a model instance describes one row."""

    model_config = ConfigDict(frozen=True, extra="allow")

    group_by: ClassVar[str | None] = None
    """Column whose equal values delimit independent groups (e.g. many surveys per table)."""
    decides_acceptance: ClassVar[bool] = False
    """Its rows are gates that decide a run's acceptance, each with a ``status`` (``pass``,
    ``fail`` or ``not evaluated``): ``run.json`` records the rows of every output of such a
    contract under ``acceptance`` (a number that is not finite as null), failed if one fails."""
    in_ledger: ClassVar[bool] = False
    """A result made elsewhere that a run uses (a drift calibration): a batch's ledger
    records, per well, what :meth:`ledger_entry` says of every output of such a contract."""

    @classmethod
    def ledger_entry(cls, table: pa.Table) -> dict[str, Any]:
        """What a batch's ledger records of a table of this contract (JSON values), when
        :attr:`in_ledger` is set."""
        return {}

    @classmethod
    def compiled(cls) -> CompiledContract:
        """The Arrow schema and checks of this contract (built once per class)."""
        return _compile(cls)

    @classmethod
    def validate_table(cls, table: pa.Table) -> None:
        """Raise :class:`ContractViolation` listing every rule the table breaks."""
        cls.compiled().validate(table)

    @classmethod
    def validate_stream(cls, stream: TableStream) -> TableStream:
        """``stream`` with its batches checked as they pass (:class:`BatchChecker`): a
        violation is raised when its batch is reached. Once a pass has been checked to its
        end, later passes (the same source read again) are not checked again. A stream that
        already holds this contract (``stream.holds``: its producer checks every batch it
        lets through) is returned as it is: checking it again would prove nothing."""
        if cls in stream.holds:
            return stream
        proven = False

        def checked() -> Iterator[pa.RecordBatch]:
            nonlocal proven
            if proven:
                yield from stream
                return
            checker = BatchChecker(cls.compiled())
            for batch in stream:
                checker.check(batch)
                yield batch
            proven = True

        return TableStream(stream.schema, checked, stream.holds | {cls})


@dataclass(frozen=True)
class ColumnSpec:
    """One compiled column rule set."""

    name: str
    type: pa.DataType
    unit: str | None
    nullable: bool
    required: bool
    finite: bool
    ge: float | None
    le: float | None
    gt: float | None
    lt: float | None
    monotonic: Monotonic | None
    north_reference: bool
    undefined_at_vertical: bool = False
    min_step: float | None = None

    @cache  # noqa: B019  (specs are compiled once and kept: a field per block is ~8 µs)
    def field(self, north_reference: str | None = None) -> pa.Field:
        """The column's Arrow field, with its unit (and north reference) metadata."""
        meta: dict[bytes, bytes] = {}
        if self.unit is not None:
            meta[UNIT_KEY] = self.unit.encode()
        if self.north_reference and north_reference is not None:
            meta[NORTH_KEY] = north_reference.encode()
        return pa.field(self.name, self.type, nullable=self.nullable, metadata=meta or None)


@dataclass(frozen=True)
class CompiledContract:
    """A contract compiled to an Arrow schema and vectorised checks."""

    name: str
    columns: tuple[ColumnSpec, ...]
    group_by: str | None

    def schema(self, north_reference: str | None = None) -> pa.Schema:
        """Arrow schema with unit (and north reference) metadata on each field."""
        return pa.schema([c.field(north_reference) for c in self.columns])

    def make_table(self, data: dict[str, Any], *, north_reference: str | None = None) -> pa.Table:
        """Build a table of this contract from column arrays, attaching units.

        Nulls of an ``undefined_at_vertical`` column (a file's empty azimuth) become NaN.
        Columns of ``data`` not in the contract are kept (without unit metadata unless they
        are already Arrow arrays whose field carries it).
        """
        known = {c.name: c for c in self.columns}
        fields: list[pa.Field] = []
        arrays: list[pa.Array | pa.ChunkedArray] = []
        for name, values in data.items():
            spec = known.get(name)
            if spec is None:
                arr = values if isinstance(values, pa.Array | pa.ChunkedArray) else pa.array(values)
                fields.append(pa.field(name, arr.type))
            else:
                if not isinstance(values, pa.Array | pa.ChunkedArray):
                    arr = pa.array(values, type=spec.type)
                else:  # a cast to its own type is the array (and costs ~10 µs)
                    arr = values if values.type == spec.type else values.cast(spec.type)
                if spec.undefined_at_vertical and arr.null_count:  # a file's null: undefined
                    arr = arr.fill_null(float("nan"))
                fields.append(spec.field(north_reference))
            arrays.append(arr)
        return pa.Table.from_arrays(arrays, schema=pa.schema(fields))

    def validate(self, table: pa.Table) -> None:
        """Raise :class:`ContractViolation` listing every failed rule (all columns)."""
        if self._holds(table):
            return
        failures: list[RuleFailure] = []
        groups = self._group_keys(table)
        present = set(table.column_names)
        for spec in self.columns:
            if spec.name not in present:
                if spec.required:
                    failures.append(RuleFailure(spec.name, "present", "a column of that name"))
                continue
            failures.extend(_check_column(spec, table, groups))
        if failures:
            source = _text((table.schema.metadata or {}).get(SOURCE_KEY, b""))
            if SOURCE_LINE in table.column_names:
                lines = table.column(SOURCE_LINE)
                failures = [
                    replace(f, lines=tuple(int(lines[i].as_py()) for i, _ in f.examples))
                    for f in failures
                ]
            raise ContractViolation(self.name, failures, source=source)

    def _holds(self, table: pa.Table) -> bool:
        """Whether ``table`` plainly keeps every rule, told by the column reductions the rules
        need and little more (:func:`_float_holds`, any other column's numbers
        :func:`_check_numbers`); False where one may be broken: :meth:`validate` then looks
        at every column to name the failures (or finds none)."""
        schema = table.schema
        names = schema.names
        if len(where := {name: i for i, name in enumerate(names)}) < len(names):  # a name twice
            return False
        groups = self._group_keys(table)
        for spec in self.columns:
            if (i := where.get(spec.name)) is None:
                if spec.required:
                    return False
                continue
            field = schema.field(i)
            if not _same_type(field.type, spec.type) or _metadata_failures(spec, field):
                return False
            col = table.column(i)
            if col.null_count and not spec.nullable:
                return False
            is_float = pa.types.is_floating(spec.type)
            if not (is_float or pa.types.is_integer(spec.type)) or not table.num_rows:
                continue
            if not is_float or col.null_count or spec.undefined_at_vertical:
                if _check_numbers(spec, col, groups, _undefined_at_vertical(spec, table)):
                    return False
            elif not _float_holds(spec, col.to_numpy()):
                return False
        return True

    def _group_keys(self, table: pa.Table) -> pa.ChunkedArray | None:
        if self.group_by is None or self.group_by not in table.schema.names:
            return None
        keys: pa.ChunkedArray = table.column(self.group_by)
        return keys


class BatchChecker:
    """Checks one pass of a stream, batch by batch, as :meth:`CompiledContract.validate`
    checks a whole table: each batch alone (zero-copy), then the step from the last row of
    the batch before to its first row (both passed), so order (``monotonic``, within groups)
    is checked across batch boundaries too. The first batch that breaks a rule raises,
    naming its failures; rows count from the start of the stream (file lines, when the
    batches carry ``source_line``, are the rows' own)."""

    def __init__(self, contract: CompiledContract) -> None:
        self.contract = contract
        self.offset = 0
        """rows checked so far"""
        self.last: dict[str, Any] | None = None
        """the ordered columns' values in the last row of the batch before (copies: a slice
        would keep the whole batch alive)"""
        ordered = tuple(c for c in contract.columns if c.monotonic)
        self.steps = replace(contract, columns=ordered) if ordered else None
        """the contract's order rules: all that the step between two batches can break"""

    def check(self, batch: pa.RecordBatch) -> None:
        """Raise :class:`ContractViolation` if ``batch`` (the next one) breaks the contract."""
        table = pa.Table.from_batches([batch])
        self._validate(self.contract, table, self.offset)
        if self.steps is not None and batch.num_rows:
            group = [self.steps.group_by] if self.steps.group_by else []
            names = [*(c.name for c in self.steps.columns), *group, SOURCE_LINE]
            present = set(table.schema.names)  # (column_names: ~6 µs more)
            ordered = table.select([n for n in names if n in present])
            first = {name: ordered.column(name)[0].as_py() for name in ordered.column_names}
            if self.last is not None and not self._step_holds(self.last, first):
                step = pa.Table.from_pylist([self.last, first], schema=ordered.schema)
                self._validate(self.steps, step, self.offset - 1)
            last = batch.num_rows - 1
            self.last = {name: ordered.column(name)[last].as_py() for name in ordered.column_names}
        self.offset += batch.num_rows

    def _step_holds(self, last: dict[str, Any], first: dict[str, Any]) -> bool:
        """Whether the step from row ``last`` to row ``first`` plainly keeps every order rule
        (float columns, no value missing, within one group), by :func:`_steps_hold`, the rule
        a batch's own steps are held to; else it is checked as a table of the two rows."""
        assert self.steps is not None
        group = self.steps.group_by
        if group in first and (first[group] is None or first[group] != last[group]):
            return False
        for spec in self.steps.columns:
            if spec.name not in first:
                continue
            before, after = last[spec.name], first[spec.name]
            if not (isinstance(before, float) and isinstance(after, float)):
                return False
            if not _steps_hold(spec, np.array([before, after])):
                return False
        return True

    def _validate(self, contract: CompiledContract, table: pa.Table, shift: int) -> None:
        try:
            contract.validate(table)
        except ContractViolation as exc:
            failures = [
                replace(f, examples=tuple((i + shift, v) for i, v in f.examples))
                for f in exc.failures
            ]
            raise ContractViolation(exc.contract, failures, source=exc.source) from None


@cache
def implies(stronger: type[TableContract], weaker: type[TableContract]) -> bool:
    """Whether every table that passes ``stronger`` passes ``weaker``, told by their rules:
    each of ``weaker``'s columns is one of ``stronger``'s, of its type, unit and north
    reference, required and complete where ``weaker`` needs it, held to the same or
    narrower rules (finite, bounds, order within the same groups or the whole table). A
    contract with checks of its own (a ``validate_table`` of its own) implies and is
    implied by itself only."""
    if stronger is weaker:
        return True
    own = TableContract.validate_table.__func__  # type: ignore[attr-defined]
    if {stronger.validate_table.__func__, weaker.validate_table.__func__} != {own}:  # type: ignore[attr-defined]
        return False
    strong, weak = stronger.compiled(), weaker.compiled()
    by_name = {c.name: c for c in strong.columns}
    ordered = any(c.monotonic for c in weak.columns)
    if ordered and strong.group_by not in (None, weak.group_by):
        return False
    return all(w.name in by_name and _column_implies(by_name[w.name], w) for w in weak.columns)


def _column_implies(s: ColumnSpec, w: ColumnSpec) -> bool:
    """Whether a column that keeps ``s``'s rules keeps ``w``'s (:func:`implies`)."""
    if s.type != w.type or (w.unit is not None and s.unit != w.unit):
        return False
    if (w.required and not s.required) or (s.nullable and not w.nullable):
        return False
    if w.north_reference and not s.north_reference:
        return False
    if w.finite and not s.finite:
        return False
    if s.undefined_at_vertical and not w.undefined_at_vertical:
        return False
    if w.ge is not None and not (
        (s.ge is not None and s.ge >= w.ge) or (s.gt is not None and s.gt >= w.ge)
    ):
        return False
    if w.gt is not None and not (
        (s.gt is not None and s.gt >= w.gt) or (s.ge is not None and s.ge > w.gt)
    ):
        return False
    if w.le is not None and not (
        (s.le is not None and s.le <= w.le) or (s.lt is not None and s.lt <= w.le)
    ):
        return False
    if w.lt is not None and not (
        (s.lt is not None and s.lt <= w.lt) or (s.le is not None and s.le < w.lt)
    ):
        return False
    if w.monotonic is not None:
        if s.monotonic is None or (w.monotonic == "strict" and s.monotonic != "strict"):
            return False
        if w.min_step is not None and (s.min_step is None or s.min_step < w.min_step):
            return False
    return True


def _check_column(
    spec: ColumnSpec, table: pa.Table, groups: pa.ChunkedArray | None
) -> list[RuleFailure]:
    field = table.schema.field(spec.name)
    col = table.column(spec.name)
    if not _same_type(field.type, spec.type):
        return [RuleFailure(spec.name, "type", str(spec.type) + f", got {field.type}")]
    failures = _metadata_failures(spec, field)
    if not spec.nullable and col.null_count:
        mask = pc.is_null(col).to_numpy(zero_copy_only=False)
        failures.append(rule_failure(spec.name, "not null", "no missing values", mask, col))
    if pa.types.is_floating(spec.type) or pa.types.is_integer(spec.type):
        failures.extend(_check_numbers(spec, col, groups, _undefined_at_vertical(spec, table)))
    return failures


def _metadata_failures(spec: ColumnSpec, field: pa.Field) -> list[RuleFailure]:
    """The rules the metadata of the column's Arrow field breaks: unit, north reference."""
    failures: list[RuleFailure] = []
    meta = field.metadata or {}
    if spec.unit is not None and meta.get(UNIT_KEY) != spec.unit.encode():
        got = meta.get(UNIT_KEY)
        failures.append(
            RuleFailure(
                spec.name,
                "unit",
                f"unit {spec.unit!r} in field metadata, got "
                + (repr(_text(got)) if got is not None else "none"),
            )
        )
    if spec.north_reference and _text(meta.get(NORTH_KEY, b"")) not in NORTH_REFERENCES:
        failures.append(
            RuleFailure(spec.name, "north reference", f"one of {', '.join(NORTH_REFERENCES)}")
        )
    return failures


def _undefined_at_vertical(spec: ColumnSpec, table: pa.Table) -> np.ndarray | None:
    """Rows where ``spec``'s column may be NaN: the column allows it, the value is NaN and
    the row's inclination is within :data:`VERTICAL_TOLERANCE` of vertical (else None)."""
    if not spec.undefined_at_vertical or "inc" not in table.schema.names:
        return None
    values = table.column(spec.name).to_numpy(zero_copy_only=False).astype(float)
    inc = table.column("inc").to_numpy(zero_copy_only=False).astype(float)
    with np.errstate(invalid="ignore"):
        vertical = np.minimum(np.abs(inc), np.abs(180.0 - inc)) <= VERTICAL_TOLERANCE
    allowed = np.isnan(values) & vertical
    return allowed if allowed.any() else None


def _check_numbers(
    spec: ColumnSpec,
    col: pa.ChunkedArray,
    groups: pa.ChunkedArray | None,
    undefined: np.ndarray | None = None,
) -> list[RuleFailure]:
    """Finite, range and monotonic rules; rows in ``undefined`` (allowed NaN) are skipped."""
    if undefined is None and _integers_in_range(spec, col):
        return []
    values = col.to_numpy() if col.null_count == 0 else col.to_numpy(zero_copy_only=False)
    if len(values) == 0:
        return []
    valid = ~pc.is_null(col).to_numpy(zero_copy_only=False) if col.null_count else None
    if undefined is not None:
        valid = ~undefined if valid is None else valid & ~undefined
    failures: list[RuleFailure] = []
    is_float = values.dtype.kind == "f"
    if valid is not None:
        checked = values[valid]
        if len(checked) == 0:
            return []
    else:
        checked = values
    in_order = (
        spec.monotonic is not None and is_float and len(values) > 1 and _steps_hold(spec, values)
    )
    lo, hi, finite = _extremes(spec, checked, in_order and valid is None)
    if is_float and spec.finite and not finite:
        bad = ~np.isfinite(values) if valid is None else (~np.isfinite(values) & valid)
        expected = (
            f"finite numbers (NaN, undefined, only where inc is within {VERTICAL_TOLERANCE:g}° "
            "of vertical)"
            if spec.undefined_at_vertical
            else "finite numbers (no NaN/inf)"
        )
        failures.append(rule_failure(spec.name, "finite", expected, bad, col))
    bounds = (  # (bound, symbol, test of a bad value, extreme that shows any bad value)
        (spec.ge, ">=", np.less, lo),
        (spec.le, "<=", np.greater, hi),
        (spec.gt, ">", np.less_equal, lo),
        (spec.lt, "<", np.greater_equal, hi),
    )
    for bound, symbol, bad_op, extreme in bounds:
        if bound is not None and bad_op(extreme, bound):
            bad = bad_op(values, bound)
            if valid is not None:
                bad &= valid
            failures.append(
                rule_failure(spec.name, "range", f"values {symbol} {bound:g}", bad, col)
            )
    if spec.monotonic and len(values) > 1 and not in_order:
        compare = np.less_equal if spec.monotonic == "strict" else np.less
        bad_step = compare(values[1:], values[:-1])
        if spec.min_step is not None:  # a step past the float range is inf: no warning
            with np.errstate(over="ignore", invalid="ignore"):
                bad_step |= values[1:] - values[:-1] < spec.min_step
        if bad_step.any():
            rows = np.flatnonzero(bad_step) + 1
            if groups is not None:  # a step into a new group is no violation
                same = pc.equal(groups.take(rows), groups.take(rows - 1)).fill_null(True)
                rows = rows[same.to_numpy(zero_copy_only=False)]
            if len(rows):
                bad = np.zeros(len(values), dtype=bool)
                bad[rows] = True
                what = "strictly increasing" if spec.monotonic == "strict" else "non-decreasing"
                scope = " within each group" if groups is not None else ""
                if spec.min_step is not None:
                    scope += f", by at least {spec.min_step:g} {spec.unit or ''}".rstrip()
                failures.append(
                    rule_failure(spec.name, "monotonic", f"{what} values{scope}", bad, col)
                )
    return failures


def _float_holds(spec: ColumnSpec, values: np.ndarray) -> bool:
    """Whether a float column, no value missing, plainly keeps its rules: what
    :func:`_check_numbers` finds no failure in, its steps in order (across groups too)."""
    ordered = spec.monotonic is not None and len(values) > 1
    if ordered and not _steps_hold(spec, values):
        return False
    lo, hi, finite = _extremes(spec, values, ordered)
    return (finite or not spec.finite) and _within(spec, lo, hi)


def _within(spec: ColumnSpec, lo: Any, hi: Any) -> bool:
    """Whether the extremes ``lo`` and ``hi`` of a column keep ``spec``'s bounds."""
    return not (
        (spec.ge is not None and lo < spec.ge)
        or (spec.le is not None and hi > spec.le)
        or (spec.gt is not None and lo <= spec.gt)
        or (spec.lt is not None and hi >= spec.lt)
    )


def _extremes(spec: ColumnSpec, values: np.ndarray, in_order: bool) -> tuple[Any, Any, bool]:
    """The smallest and largest of ``values`` (no missing ones among them) and whether they
    are all finite, in as few passes as the column's rules need: a column whose steps hold
    its order (``in_order``: a NaN would have broken it) has its first and last values for
    extremes, which are finite only if all are; a bounded column takes one pass each for
    min and max (NaN propagates through both, ±inf shows in one); an unbounded one needs
    no extremes, only finiteness: one sum (a NaN or an infinite value makes it NaN or
    infinite, so a finite sum proves every value finite; a sum past the float range of
    finite values is told by looking at them one by one)."""
    if in_order:
        lo, hi = values[0], values[-1]
        return lo, hi, bool(np.isfinite(lo) and np.isfinite(hi))
    if any(bound is not None for bound in (spec.ge, spec.le, spec.gt, spec.lt)):
        lo, hi = values.min(), values.max()
        return lo, hi, bool(np.isfinite(lo) and np.isfinite(hi))
    if values.dtype.kind != "f" or not spec.finite:
        return None, None, True
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.add.reduce(values)
    return None, None, bool(np.isfinite(total) or np.isfinite(values).all())


def _integers_in_range(spec: ColumnSpec, col: pa.ChunkedArray) -> bool:
    """An integer column with missing values (no order rule) whose values all lie within
    the bounds: told by Arrow's ``min_max`` (nulls skipped), without the column converted
    to floats and filtered first."""
    if not (col.null_count and pa.types.is_integer(col.type)) or spec.monotonic:
        return False
    extremes = pc.min_max(col)
    lo, hi = extremes["min"].as_py(), extremes["max"].as_py()
    return lo is None or _within(spec, lo, hi)  # None: every value missing


def _steps_hold(spec: ColumnSpec, values: np.ndarray) -> bool:
    """Every step of a float column keeps its order rule (and ``min_step``), told by the
    smallest step (a NaN or an infinite value makes it NaN or negative: then the rows are
    looked at one by one)."""
    with np.errstate(over="ignore", invalid="ignore"):  # a step past the float range: inf
        smallest = np.diff(values).min()
    floor = 0.0 if spec.min_step is None else spec.min_step
    if spec.monotonic == "strict":
        return bool(smallest > 0.0 and smallest >= floor)
    return bool(smallest >= 0.0 and smallest >= floor)


def rule_failure(
    name: str, rule: str, expected: str, bad: np.ndarray, col: pa.ChunkedArray
) -> RuleFailure:
    """The failure of ``rule`` on column ``name`` at the rows ``bad`` marks (a few shown)."""
    rows = np.flatnonzero(bad)
    examples = tuple((int(i), col[int(i)].as_py()) for i in rows[:EXAMPLES])
    return RuleFailure(name, rule, expected, bad_rows=len(rows), examples=examples)


def _text(raw: bytes) -> str:
    """Metadata bytes as text, bytes that are not UTF-8 as U+FFFD: a file's garbled unit or
    north reference is a rule broken, not a decoding error."""
    return raw.decode("utf-8", errors="replace")


def _same_type(actual: pa.DataType, expected: pa.DataType) -> bool:
    if pa.types.is_string(expected):
        return bool(pa.types.is_string(actual) or pa.types.is_large_string(actual))
    return bool(actual == expected)


def _arrow_type(annotation: Any) -> tuple[pa.DataType, bool]:
    """Arrow type and nullability of a field annotation (``float``, ``float | None``…)."""
    nullable = False
    origin = get_origin(annotation)
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(annotation) if a is not type(None)]
        nullable = len(args) < len(get_args(annotation))
        if len(args) != 1:
            raise TypeError(f"contract column type {annotation!r} must be one type or X | None")
        annotation = args[0]
    try:
        return _ARROW_TYPES[annotation], nullable
    except KeyError:
        raise TypeError(
            f"contract column type {annotation!r} is not one of "
            f"{', '.join(t.__name__ for t in _ARROW_TYPES)}"
        ) from None


@cache
def _compile(model: type[TableContract]) -> CompiledContract:
    specs = []
    for name, info in model.model_fields.items():
        arrow_type, nullable = _arrow_type(info.annotation)
        extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
        bounds: dict[str, float | None] = {"ge": None, "le": None, "gt": None, "lt": None}
        for meta in info.metadata:
            for key in bounds:
                if hasattr(meta, key):
                    bounds[key] = float(getattr(meta, key))
        unit = extra.get("x-unit")
        monotonic = extra.get("x-monotonic")
        min_step = extra.get("x-min-step")
        if monotonic not in (None, "increasing", "strict"):
            raise TypeError(f"column {name!r}: monotonic must be 'increasing' or 'strict'")
        specs.append(
            ColumnSpec(
                name=name,
                type=arrow_type,
                unit=unit if isinstance(unit, str) else None,
                nullable=nullable,
                required=info.is_required(),
                finite=bool(extra.get("x-finite", True)),
                monotonic=cast(Monotonic | None, monotonic),
                north_reference="x-north-reference" in extra,
                undefined_at_vertical=bool(extra.get("x-undefined-at-vertical", False)),
                min_step=float(min_step) if isinstance(min_step, int | float) else None,
                **bounds,
            )
        )
    return CompiledContract(model.__name__, tuple(specs), model.group_by)

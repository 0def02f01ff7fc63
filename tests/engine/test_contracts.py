"""Table contracts: each rule passes on good tables and fails, with rows, on bad ones."""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest

from pipeline.contracts import ColumnSpec, TableContract, column, implies
from pipeline.errors import ContractViolation, RuleFailure
from pipeline.ports import CheckedTables
from pipeline.streams import TableStream
from pipeline.tables import (
    MIN_COURSE_M,
    AnyTable,
    LogTable,
    PositionReadings,
    RawSamples,
    Stations,
    Trajectory,
)
from tests_support import ROOT, gyropipe_cli


class Sample(TableContract):
    group_by = "well"

    well: str | None = column(unit=None, description="group key", default=None)
    md: float = column(unit="m", ge=0, monotonic="strict", description="depth")
    inc: float = column(unit="deg", ge=0, le=180, description="inclination")
    azi: float = column(unit="deg", north_reference=True, description="azimuth")
    t: float = column(unit="s", gt=0, lt=10, monotonic="increasing", description="time")
    gap: float | None = column(unit="m", ge=0, description="nullable")
    n: int = column(unit=None, ge=1, description="count")


def table(**overrides: object) -> pa.Table:
    data: dict[str, object] = {
        "md": [0.0, 10.0, 20.0, 30.0],
        "inc": [0.0, 1.0, 2.0, 3.0],
        "azi": [10.0, 11.0, 12.0, 13.0],
        "t": [1.0, 1.0, 2.0, 3.0],
        "gap": [None, 1.0, None, 2.0],
        "n": [1, 2, 3, 4],
    }
    data.update(overrides)
    return Sample.compiled().make_table(data, north_reference="true")


def failures(t: pa.Table) -> list[RuleFailure]:
    with pytest.raises(ContractViolation) as info:
        Sample.validate_table(t)
    return info.value.failures


def only(t: pa.Table) -> RuleFailure:
    (failure,) = failures(t)
    return failure


def test_valid_table_passes_and_schema_carries_units():
    Sample.validate_table(table())
    schema = Sample.compiled().schema("grid")
    assert schema.field("md").metadata == {b"unit": b"m"}
    assert schema.field("azi").metadata == {b"unit": b"deg", b"north_reference": b"grid"}
    assert schema.field("gap").nullable and not schema.field("md").nullable
    assert schema.field("n").type == pa.int64()


def test_missing_column():
    f = only(table().drop_columns(["inc"]))
    assert (f.column, f.rule) == ("inc", "present")


def test_wrong_type():
    t = table().set_column(5, pa.field("n", pa.float64()), pa.array([1.0, 2, 3, 4]))
    f = only(t)
    assert (f.column, f.rule) == ("n", "type")
    assert "int64, got double" in f.expected


def test_wrong_or_missing_unit():
    t = table()
    i = t.schema.get_field_index("md")
    ft = t.set_column(i, pa.field("md", pa.float64(), metadata={"unit": "ft"}), t.column("md"))
    f = only(ft)
    assert (f.column, f.rule) == ("md", "unit")
    assert "'m'" in f.expected and "'ft'" in f.expected
    bare = t.set_column(i, pa.field("md", pa.float64()), t.column("md"))
    assert "got none" in only(bare).expected


def test_north_reference_required():
    t = table()
    i = t.schema.get_field_index("azi")
    t = t.set_column(i, pa.field("azi", pa.float64(), metadata={"unit": "deg"}), t.column("azi"))
    f = only(t)
    assert (f.column, f.rule) == ("azi", "north reference")


def test_nulls_in_non_nullable_column():
    f = only(table(inc=[0.0, None, 2.0, None]))
    assert (f.column, f.rule, f.bad_rows) == ("inc", "not null", 2)
    assert f.examples == ((1, None), (3, None))


def test_nulls_allowed_in_nullable_column_and_range_skips_them():
    Sample.validate_table(table(gap=[None, None, None, None]))
    f = only(table(gap=[None, -1.0, None, 2.0]))
    assert (f.column, f.rule, f.examples) == ("gap", "range", ((1, -1.0),))


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_values(bad):
    f = only(table(azi=[1.0, 2.0, bad, 4.0]))
    assert (f.column, f.rule, f.bad_rows) == ("azi", "finite", 1)
    assert f.examples[0][0] == 2


@pytest.mark.parametrize(
    ("col", "values", "rows", "expected"),
    [
        ("inc", [0.0, 180.5, -1.0, 3.0], [1], "values <= 180"),
        ("inc", [0.0, 180.5, -1.0, 3.0], [2], "values >= 0"),
        ("t", [0.0, 1.0, 2.0, 3.0], [0], "values > 0"),
        ("t", [1.0, 1.0, 2.0, 10.0], [3], "values < 10"),
        ("n", [1, 0, 3, 4], [1], "values >= 1"),
    ],
)
def test_range_rules(col, values, rows, expected):
    found = [f for f in failures(table(**{col: values})) if f.expected == expected]
    assert len(found) == 1
    assert [i for i, _ in found[0].examples] == rows


def test_strict_and_non_strict_monotonic():
    f = only(table(md=[0.0, 10.0, 10.0, 5.0]))
    assert (f.column, f.rule, f.bad_rows) == ("md", "monotonic", 2)
    assert f.examples == ((2, 10.0), (3, 5.0))
    assert "strictly increasing" in f.expected
    Sample.validate_table(table(t=[1.0, 1.0, 1.0, 2.0]))  # non-decreasing is enough for t
    f = only(table(t=[1.0, 3.0, 2.0, 4.0]))
    assert (f.column, f.rule, f.examples) == ("t", "monotonic", ((2, 2.0),))


def test_monotonic_within_groups():
    grouped = table(well=["a", "a", "b", "b"], md=[5.0, 10.0, 0.0, 3.0])
    Sample.validate_table(grouped)
    f = only(table(well=["a", "a", "b", "b"], md=[5.0, 10.0, 3.0, 0.0]))
    assert f.examples == ((3, 0.0),)
    assert "within each group" in f.expected


def test_every_failure_is_reported_with_location_when_raised_by_engine():
    bad = table(inc=[0.0, 200.0, None, 3.0], azi=[1.0, math.nan, 2.0, 3.0])
    with pytest.raises(ContractViolation) as info:
        Sample.validate_table(bad)
    located = info.value.located(pipeline="p", stage="s", port="stations", direction="input")
    text = str(located)
    assert text.startswith(
        "pipeline 'p' stage 's' input port 'stations': table violates contract Sample"
    )
    assert "column 'inc': not null" in text and "column 'inc': range" in text
    assert "column 'azi': finite" in text and "row 1: nan" in text


def test_empty_table_passes():
    Sample.validate_table(table().slice(0, 0))


def test_builtin_contracts_reject_bad_survey_values():
    good = Stations.compiled().make_table(
        {"md": [0.0, 30.0], "inc": [0.0, 5.0], "azi": [0.0, 359.9]}, north_reference="true"
    )
    Stations.validate_table(good)
    bad = Stations.compiled().make_table(
        {"md": [0.0, 0.0], "inc": [0.0, 181.0], "azi": [0.0, np.inf]}, north_reference="true"
    )
    with pytest.raises(ContractViolation) as info:
        Stations.validate_table(bad)
    rules = {(f.column, f.rule) for f in info.value.failures}
    assert rules == {("md", "monotonic"), ("inc", "range"), ("azi", "finite")}
    assert {c.name for c in Stations.compiled().columns} < {
        c.name for c in Trajectory.compiled().columns
    }


def test_contract_json_schema_carries_units_and_bounds():
    schema = Sample.model_json_schema()
    md = schema["properties"]["md"]
    assert md["x-unit"] == "m" and md["minimum"] == 0 and md["x-monotonic"] == "strict"
    assert schema["properties"]["azi"]["x-north-reference"] == ["true", "grid", "magnetic"]


def test_unsupported_column_type_is_refused():
    class Bad(TableContract):
        x: list[int] = column(unit=None, description="not a scalar")

    with pytest.raises(TypeError, match="not one of"):
        Bad.compiled()


def test_stations_closer_than_the_shortest_course_are_refused():
    """Fuzz finding: MD 0 then 4.9e-324 m made minimum curvature's DLS infinite (and NumPy
    warn of an overflow); a course shorter than MIN_COURSE_M is a repeated station. Steps
    past the float range (-1e308 → 1e308) are long courses, checked without a warning."""
    assert MIN_COURSE_M == 5e-4

    def stations(md: list[float]) -> pa.Table:
        n = len(md)
        data = {"md": md, "inc": [0.0] * n, "azi": [0.0] * n}
        return Stations.compiled().make_table(data, north_reference="true")

    for md in ([0.0, 5e-324, 30.0], [100.0, 100.00009, 130.0]):
        with pytest.raises(ContractViolation) as info:
            Stations.validate_table(stations(md))
        (failure,) = info.value.failures
        assert (failure.column, failure.rule, failure.examples) == (
            "md",
            "monotonic",
            ((1, md[1]),),
        )
        assert failure.expected == "strictly increasing values, by at least 0.0005 m"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Stations.validate_table(stations([100.0, 100.001, 130.0]))
        Stations.validate_table(stations([-1e308, 1e308]))


def test_times_and_durations_a_copy_cannot_hold_are_refused(tmp_path: Path):
    """Fuzz finding (long run): a reading's duration of 4.9e-324 s was accepted, but its CSV
    copy (1 µs steps) held 0.0 and could not be read back; so could two sample times a few
    ulp apart. Durations are at least 1 µs, time steps at least 5 µs."""
    lines = (ROOT / "examples/readings-j-well.csv").read_text().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("station,"))
    lines[header + 2] = lines[header + 2].rsplit(",", 1)[0] + ",4.9e-324"
    path = tmp_path / "readings.csv"
    path.write_text("\n".join(lines[: header + 5]) + "\n")
    result = gyropipe_cli("convert", str(path), str(tmp_path / "copy.csv"), "--kind", "readings")
    assert result.returncode == 1, result.stderr
    assert result.stderr.splitlines() == [
        f"error: {path}:{header + 3}: not valid as readings (reader 'csv'): column 'duration': "
        f"range: expected values >= 1e-06; 1 bad row(s), first: row 1 (line {header + 3}): "
        "5e-324"
    ]
    samples = RawSamples.compiled().make_table(
        {"time": [0.0, 5e-324, 1.0]} | {c: [0.0] * 3 for c in ("gyro_x", "acc_x", "acc_y", "acc_z")}
    )
    with pytest.raises(ContractViolation) as info:
        RawSamples.validate_table(samples)
    (failure,) = info.value.failures
    assert failure.expected == "strictly increasing values, by at least 5e-06 s"


def test_an_integer_column_with_missing_values_is_still_range_checked():
    """Missing values are told apart from the bounds: a count of 0 among them is out of
    range at its row, counts within range leave only the missing ones to report."""
    (missing,) = [f for f in failures(table(n=[1, None, 0, 4])) if f.rule == "not null"]
    (low,) = [f for f in failures(table(n=[1, None, 0, 4])) if f.rule == "range"]
    assert missing.examples == ((1, None),)
    assert (low.expected, low.examples) == ("values >= 1", ((2, 0),))
    f = only(table(n=[1, None, 3, None]))
    assert (f.rule, f.bad_rows) == ("not null", 2)


def test_a_streamed_check_takes_order_across_batches_within_groups():
    """The step from one batch's last row to the next one's first: a new group is no
    violation; a step back within a group is, at its row counted from the stream's start."""
    into_new_group = table(well=["a", "a", "b", "b"], md=[5.0, 10.0, 0.0, 3.0])
    assert len(list(Sample.validate_stream(TableStream.from_table(into_new_group, 2)))) == 2
    back = table(well=["a", "a", "a", "a"], md=[0.0, 10.0, 5.0, 20.0])
    with pytest.raises(ContractViolation) as info:
        list(Sample.validate_stream(TableStream.from_table(back, 2)))
    (f,) = info.value.failures
    assert (f.column, f.rule, f.examples) == ("md", "monotonic", ((2, 5.0),))


def test_an_ordered_column_is_checked_finite_and_in_range_from_its_ends():
    """A column whose steps keep its order has its first and last values for extremes:
    an infinite end is still refused, at its row, and a NaN that breaks the order too."""
    f = only(table(md=[0.0, 10.0, 20.0, math.inf]))
    assert (f.column, f.rule, f.examples) == ("md", "finite", ((3, math.inf),))
    rules = {(f.rule, f.examples[0][0]) for f in failures(table(md=[-math.inf, 1.0, 2.0, 3.0]))}
    assert rules == {("finite", 0), ("range", 0)}
    f = only(table(md=[0.0, math.nan, 20.0, 30.0]))
    assert (f.column, f.rule, f.examples[0][0]) == ("md", "finite", 1)


def test_an_unbounded_column_whose_sum_overflows_is_not_refused():
    """Finiteness of a column without bounds is told by one sum: finite values whose sum
    is past the float range pass; +inf and −inf together (a NaN sum) are both refused."""
    Sample.validate_table(table(azi=[1.7e308, 1.7e308, -1.7e308, -1.7e308]))
    f = only(table(azi=[math.inf, 1.0, -math.inf, 4.0]))
    assert (f.column, f.rule, f.bad_rows) == ("azi", "finite", 2)
    assert [i for i, _ in f.examples] == [0, 2]


def rows_of(n: int, **changes: tuple[int, float]) -> pa.Table:
    """A good :class:`Sample` table of ``n`` rows, ``column=(row, value)`` changed."""
    data: dict[str, object] = {
        "md": np.arange(n) * 10.0,
        "inc": np.linspace(0.0, 3.0, n),
        "azi": np.full(n, 10.0),
        "t": 1.0 + np.arange(n) * (8.0 / n),
        "gap": [None if i % 2 else 1.0 for i in range(n)],
        "n": np.arange(n) + 1,
    }
    for name, (row, value) in changes.items():
        values = list(data[name])  # type: ignore[call-overload]
        values[row] = value
        data[name] = values
    return table(**data)


@pytest.mark.parametrize(
    ("change", "refused"),
    [
        ({"inc": (5, math.nan)}, {("inc", "finite")}),
        ({"azi": (6, math.inf)}, {("azi", "finite")}),
        ({"md": (0, -math.inf)}, {("md", "finite"), ("md", "range")}),
        ({"inc": (3, 180.5)}, {("inc", "range")}),
        ({"t": (0, 0.0)}, {("t", "range")}),
        ({"md": (4, 30.0)}, {("md", "monotonic")}),
        ({"t": (2, 1.0)}, {("t", "monotonic")}),
        ({"gap": (1, -2.0)}, {("gap", "range")}),
    ],
)
def test_a_bad_value_is_refused_by_each_rule_it_breaks_at_its_row(change: dict, refused: set):
    """A table that plainly keeps every rule is passed on its columns' reductions alone;
    one bad value makes it checked column by column, and refused by each rule it breaks."""
    Sample.validate_table(rows_of(40))
    found = failures(rows_of(40, **change))
    assert {(f.column, f.rule) for f in found} == refused
    assert {f.examples[0][0] for f in found} == {row for row, _ in change.values()}


def test_the_plain_pass_knows_every_rule_a_column_may_have():
    """A table is passed on its columns' reductions alone (``CompiledContract._holds``)
    before anything is checked column by column: a rule added to :class:`ColumnSpec` must be
    taught to that pass too, or a table breaking it would pass unseen — this list says
    which rules it knows."""
    assert {f.name for f in dataclasses.fields(ColumnSpec)} == {
        "name",
        "type",
        "unit",
        "nullable",
        "required",
        "finite",
        "ge",
        "le",
        "gt",
        "lt",
        "monotonic",
        "north_reference",
        "undefined_at_vertical",
        "min_step",
    }


class Loose(TableContract):
    x: float = column(unit=None, ge=0, finite=False, description="NaN allowed")


def test_a_column_that_allows_nan_is_still_range_checked():
    values = np.ones(8)
    values[3] = math.nan
    Loose.validate_table(Loose.compiled().make_table({"x": values}))
    values[3] = -1.0
    with pytest.raises(ContractViolation) as info:
        Loose.validate_table(Loose.compiled().make_table({"x": values}))
    (failure,) = info.value.failures
    assert (failure.rule, failure.examples) == ("range", ((3, -1.0),))


def raw_samples(rows: int) -> pa.Table:
    return RawSamples.compiled().make_table(
        {
            "time": np.arange(rows) * 0.01,
            "frame_angle": np.full(rows, 90.0),
            **{c: np.ones(rows) for c in ("gyro_x", "acc_x", "acc_y", "acc_z")},
        }
    )


@pytest.mark.parametrize(
    ("column", "row", "value", "rule"),
    [
        ("gyro_x", 7, math.nan, "finite"),
        ("acc_z", 5, -math.inf, "finite"),
        ("time", 7, math.inf, "finite"),  # the last row of its batch: an ordered column's end
        ("time", 4, math.nan, "finite"),  # the first row of its batch
        ("frame_angle", 6, 360.0, "range"),
        ("frame_angle", 9, -0.5, "range"),
        ("gyro_x", 5, None, "not null"),
    ],
)
def test_a_streamed_check_refuses_each_bad_value_at_its_row(
    column: str, row: int, value: float | None, rule: str
):
    """Each batch of a stream is checked as a whole table is: a NaN, an infinity, a value
    out of range or a missing one is refused naming its column and its row from the start."""
    good = raw_samples(12)
    values = good.column(column).to_pylist()
    values[row] = value
    i = good.schema.get_field_index(column)
    bad = good.set_column(i, good.schema.field(i), pa.array(values, pa.float64()))
    with pytest.raises(ContractViolation) as info:
        list(RawSamples.validate_stream(TableStream.from_table(bad, 4)))
    found = [(f.column, f.rule) for f in info.value.failures]
    assert (column, rule) in found
    (f,) = [f for f in info.value.failures if (f.column, f.rule) == (column, rule)]
    assert f.examples[0][0] == row
    assert len(list(RawSamples.validate_stream(TableStream.from_table(good, 4)))) == 3


@pytest.mark.parametrize(
    ("step", "rule"), [(-0.5, "monotonic"), (1e-6, "monotonic"), (math.nan, "finite")]
)
def test_a_step_across_batches_is_refused_at_its_row_and_line(step: float, rule: str):
    """The step from one batch's last time to the next one's first: backwards, or forwards
    by less than the shortest time step, is refused at its row (and its file line); a NaN
    there is refused as not finite, in its own batch."""
    times = [0.0, 1.0, 2.0, 2.0 + step, 3.0, 4.0]
    samples = (
        RawSamples.compiled()
        .make_table(
            {"time": times, **{c: [0.0] * 6 for c in ("gyro_x", "acc_x", "acc_y", "acc_z")}}
        )
        .append_column("source_line", pa.array(range(10, 16), pa.int64()))
    )
    with pytest.raises(ContractViolation) as info:
        list(RawSamples.validate_stream(TableStream.from_table(samples, 3)))
    (f,) = info.value.failures
    assert (f.column, f.rule, f.examples[0][0], f.lines) == ("time", rule, 3, (13,))


class Narrower(Sample):
    """Sample's rules, narrower: inc ≤ 90, gap complete, md by at least 1 m, an extra
    column."""

    inc: float = column(unit="deg", ge=0, le=90, description="inclination")
    gap: float = column(unit="m", gt=0, description="complete")
    md: float = column(unit="m", ge=0, monotonic="strict", min_step=1.0, description="depth")
    extra: float = column(unit="m", description="not Sample's")


class Looser(Sample):
    inc: float = column(unit="deg", ge=0, le=360, description="inclination")


class Ungrouped(Narrower):
    group_by = "other"


def test_a_contract_implies_another_whose_rules_its_own_imply() -> None:
    """``implies``: each of the weaker contract's columns in the stronger one with the same
    type, unit and north reference and the same or narrower rules; a table that passes the
    stronger passes the weaker (checked here), not the other way round."""
    assert implies(Narrower, Sample) and implies(Sample, Sample)
    assert not implies(Sample, Narrower)  # wider range, gap nullable, no extra column
    assert not implies(Looser, Sample)  # inc up to 360
    assert not implies(Ungrouped, Sample)  # order within other groups than Sample's
    assert implies(Trajectory, Stations) and not implies(Stations, Trajectory)
    assert not implies(RawSamples, Stations)
    good = Narrower.compiled().make_table(
        {**{k: v for k, v in table().to_pydict().items() if k != "gap"}, "gap": [1.0] * 4,
         "extra": [0.0] * 4},
        north_reference="true",
    )  # fmt: skip
    Narrower.validate_table(good)
    Sample.validate_table(good)


def test_a_contract_with_checks_of_its_own_implies_only_itself() -> None:
    """LogTable checks more than its columns' rules (``validate_table`` of its own): no
    other contract implies it, and it implies no other."""

    class Log(LogTable):
        pass

    assert implies(LogTable, LogTable)
    assert not implies(Log, LogTable) and not implies(LogTable, AnyTable)


def test_a_table_is_not_checked_again_against_a_contract_its_checks_imply() -> None:
    """The runner's checked tables: a table that passed Trajectory counts as checked for
    Stations, not for a contract it has not passed (PositionReadings)."""
    checked = CheckedTables()
    t = table()
    assert checked.first(t, Trajectory)
    assert not checked.first(t, Trajectory) and not checked.first(t, Stations)
    assert checked.first(t, PositionReadings)
    assert checked.first(table(), Stations)  # another table

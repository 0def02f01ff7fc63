"""The ``gyropipe`` command line's items: ``NAME=FILE`` inputs, ``--option KEY=VALUE``
reader options and ``--well FIELD=VALUE`` header overrides, each refused with a
``click.BadParameter`` that names the item, and ``--disable-plugin``."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import click

from pipeline.errors import SpecError, did_you_mean

T = TypeVar("T")

if TYPE_CHECKING:
    from pipeline.graph import Plan
    from pipeline.well import WellMetadata

disable_option = click.option(
    "--disable-plugin",
    "disabled",
    multiple=True,
    metavar="NAME",
    help="Do not load the plugin NAME (built-in or third-party). Repeatable.",
)
"""``--disable-plugin NAME``: the plugins a command leaves out."""


def reader_options(items: tuple[str, ...]) -> dict[str, object]:
    """``--option KEY=VALUE`` items as reader options (each value parsed as YAML)."""
    from pipeline.yamlsource import load_value

    values: dict[str, object] = {}
    given: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise click.BadParameter(f"--option {item!r}: expected KEY=VALUE")
        try:
            parsed = load_value(value, f"--option {item}")
        except SpecError as exc:
            raise click.BadParameter("; ".join(map(str, exc.problems))) from None
        _once("--option", key.strip(), parsed, values, given, item)
    return values


def _once(
    flag: str, key: str, value: T, values: dict[str, T], given: dict[str, str], item: str
) -> None:
    """``values[key] = value``, refused when ``key`` was given before with another value
    (``given``: each key's item, for the message)."""
    if key in values and values[key] != value:
        raise click.BadParameter(f"{flag} {item}: {key} given twice (also {flag} {given[key]})")
    values[key], given[key] = value, item


def input_files(plan: Plan, items: tuple[str, ...]) -> dict[str, Path]:
    """``--input NAME=FILE`` items as the plan's input files (a bare FILE when the plan has
    one input)."""
    declared = list(plan.spec.inputs)
    files: dict[str, Path] = {}
    for item in items:
        name, sep, file = item.partition("=")
        if not sep:
            if len(declared) != 1:
                raise click.BadParameter(
                    f"{item!r}: name the input (NAME=FILE); pipeline inputs: "
                    f"{', '.join(declared) or 'none'}"
                )
            name, file = declared[0], item
        if name in files:
            raise click.BadParameter(f"input {name!r} given twice")
        files[name] = Path(file)
    return files


def well_overrides(items: tuple[str, ...]) -> WellMetadata:
    """``--well FIELD=VALUE`` items as well-header overrides (pydantic converts the text to
    each field's type; an unknown field is refused with its closest match)."""
    from pydantic import ValidationError

    from pipeline.well import WellMetadata

    fields = tuple(WellMetadata.model_fields)
    values: dict[str, str | None] = {}
    given: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise click.BadParameter(f"--well {item!r}: expected FIELD=VALUE")
        # pydantic converts text to the field type
        _once("--well", key.strip(), value.strip() or None, values, given, item)
    try:
        return WellMetadata.model_validate(values)
    except ValidationError as exc:
        problems = []
        for err in exc.errors():
            field = str(err["loc"][0]) if err["loc"] else ""
            where = f"--well {given[field]}" if field in given else "--well"  # a model-level error
            if err["type"] == "extra_forbidden":
                problems.append(f"{where}: unknown field {field!r}{did_you_mean(field, fields)}")
            else:
                problems.append(f"{where}: {err['msg'][0].lower()}{err['msg'][1:]}")
        raise click.BadParameter("; ".join(problems)) from None

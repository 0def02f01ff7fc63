"""``gyropipe models``: list the tool (error) models, or show and check one model or file."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from pipeline.cli_args import disable_option
from pipeline.errors import GyropipeError

if TYPE_CHECKING:
    from pipeline.uncertainty.toolmodel import ToolTerm

EXIT_CONFIG = 2


@click.command()
@click.argument("model", required=False, metavar="[NAME|FILE.yaml]")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@disable_option
def models(model: str | None, as_json: bool, disabled: tuple[str, ...]) -> None:
    """List the tool models (shipped, the OWSG library and from the plugins not disabled,
    grouped, with each model's inclination range), or show one model's terms — a model
    file given by path is read and checked (exit 2 and the file:line of each problem if it
    is invalid)."""
    from pipeline.plugins import shared_registry
    from pipeline.stages.toolmodels import disabled_message, of_registry
    from pipeline.uncertainty.engine import find_model
    from pipeline.uncertainty.toolmodel import describe

    registry = shared_registry(disabled)
    catalogue = of_registry(registry)
    try:
        if model is None:
            found = [find_model(path, catalogue) for path in catalogue.files().values()]
            listing = [describe(m) for m in sorted(found, key=lambda m: m.name.upper())]
            if as_json:
                click.echo(json.dumps(listing, indent=2))
                return
            for family, items in _families(listing):
                click.echo(f"# {family}: {len(items)} models")
                for item in items:
                    click.echo(_line(item))
            return
        tool = find_model(model, catalogue)
    except (GyropipeError, KeyError) as exc:
        message = exc.args[0] if isinstance(exc, KeyError) else exc
        click.echo(f"error: {disabled_message(str(model), registry) or message}", err=True)
        sys.exit(EXIT_CONFIG)
    if as_json:
        doc = describe(tool)
        doc["terms"] = [
            {
                "name": t.name,
                "acts_on": list(t.acts_on),
                "mode": t.mode,
                "magnitude": t.magnitude,
                "unit": t.unit,
                "sigma_si": t.sigma,
                "weight": t.code,
            }
            for t in tool.terms
        ]
        doc["parameters"] = dict(tool.parameters)
        click.echo(json.dumps(doc, indent=2))
        return
    click.echo(f"{tool.name}: {tool.title}")
    if tool.source:
        click.echo(f"  {tool.source}")
    click.echo(f"  file: {tool.file}; needs the site's {_needs(sorted(tool.needs))}")
    for name, value in tool.parameters.items():
        click.echo(f"  parameter {name} = {value:g} (SI; file unit {tool.units.get(name, '-')})")
    lo, hi = tool.inclination_range_deg
    click.echo(f"  valid for inclinations {lo:g}–{hi:g}°")
    w = max(10, *(len(t.name) for t in tool.terms))
    click.echo(f"  {'term':<{w}} {'acts on':<9} {'mode':<12} {'magnitude':>12} {'unit':<12} weight")
    for t in tool.terms:
        click.echo(
            f"  {t.name:<{w}} {','.join(t.acts_on):<9} {t.mode:<12} {t.magnitude:>12g} "
            f"{t.unit:<12} {t.code}{_switch_words(t)}"
        )


def _families(listing: list[dict[str, Any]]) -> list[tuple[str, list[dict[str, Any]]]]:
    """The listing grouped: the shipped ISCWSA/gyro models, the OWSG tool library
    (``models/owsg/``), then the plugins' models."""
    from pipeline.uncertainty.engine import MODELS_DIR

    groups: dict[str, list[dict[str, Any]]] = {name: [] for name in FAMILIES}
    for item in listing:
        folder = Path(item["file"]).parent
        key = (
            "shipped"
            if folder == MODELS_DIR
            else "owsg"
            if folder == MODELS_DIR / "owsg"
            else "plugins"
        )
        groups[key].append(item)
    return [(FAMILIES[k], items) for k, items in groups.items() if items]


FAMILIES = {
    "shipped": "ISCWSA MWD and gyro models (models/)",
    "owsg": "OWSG tool library, sets A and B (models/owsg/)",
    "plugins": "from plugins",
}


def _line(item: dict[str, Any]) -> str:
    """One model: name, inclination range, terms, site needs, title (and the file of a
    plugin's model)."""
    from pipeline.uncertainty.engine import MODELS_DIR

    rng = item["inclination_range"]
    valid = f"{rng[0]:g}–{rng[1]:g}°"
    file = "" if Path(item["file"]).is_relative_to(MODELS_DIR) else f" ({item['file']})"
    return (
        f"{item['name']:<26} {valid:<9} {len(item['terms']):>3} terms  "
        f"{_needs(item['needs']):<34} {item['title']}{file}"
    )


def _needs(needs: list[str]) -> str:
    words = {"latitude": "latitude", "magnetic": "geomagnetic field"}
    return " and ".join(words.get(n, n) for n in needs) or "nothing"


def _switch_words(term: ToolTerm) -> str:
    """ " (above static_end_inc: freeze)" for a term that switches at an inclination."""
    if term.switch is None:
        return ""
    below = "" if term.switch.below == "live" else ", below: zero"
    return f" (above {term.switch.at}: {term.switch.above}{below})"

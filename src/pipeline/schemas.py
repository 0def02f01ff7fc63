"""JSON Schema of the pipeline YAML, the well metadata, every built-in table contract and
the JSON documents built-in writers produce; and ``docs/tables.md``, the columns of every
built-in table contract for people.

``gyropipe schemas`` writes them under ``schemas/`` (and the page under ``docs/``); a test
checks the committed files equal what the models generate, so neither drifts from the code.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow as pa

from pipeline.atomic import atomic_write_bytes
from pipeline.contracts import ColumnSpec, TableContract
from pipeline.registry import Registry
from pipeline.spec import PipelineSpec
from pipeline.well import WellMetadata


def builtin_contracts(registry: Registry) -> dict[str, type[TableContract]]:
    """Contracts used by built-in plugins, by class name."""
    found: dict[str, type[TableContract]] = {}
    builtin = {name for name, info in registry.plugins.items() if info.builtin}
    for stage, plugin in registry.stages.values():
        if plugin in builtin:
            for contract in (*stage.inputs.values(), *stage.outputs.values()):
                found[contract.__name__] = contract
    for reader, plugin in registry.readers.values():
        if plugin in builtin:
            found.update({c.__name__: c for c in reader.kinds.values()})
    for check, plugin in registry.checks.values():
        if plugin in builtin:
            found[check.contract.__name__] = check.contract
    return dict(sorted(found.items()))


def generate(registry: Registry) -> dict[str, str]:
    """Schema file name (relative to the schemas directory) → JSON text."""
    docs = {
        "pipeline.schema.json": PipelineSpec.model_json_schema(by_alias=True),
        "well.schema.json": WellMetadata.model_json_schema(),
    }
    for name, contract in builtin_contracts(registry).items():
        docs[f"contracts/{name}.schema.json"] = contract.model_json_schema()
    for writer, plugin in registry.writers.values():
        if writer.schema is not None and registry.plugins[plugin].builtin:
            docs[f"writers/{writer.name}.schema.json"] = writer.schema.model_json_schema()
    return {name: json.dumps(doc, indent=2, sort_keys=True) + "\n" for name, doc in docs.items()}


TABLES_PAGE = "tables.md"


def tables_page(registry: Registry) -> str:
    """Markdown: every built-in table contract, its purpose and its columns (type, unit,
    required, rules, meaning)."""
    lines = [
        "# Tables",
        "",
        "The tables gyropipe's built-in stages, readers and checks exchange, one section per",
        "contract: every column with its Arrow type, its unit (stored in the field's `unit`",
        "metadata; azimuths also carry `north_reference`), whether it must be present and the",
        "rules the engine checks at every stage boundary. Extra columns are allowed.",
        "",
        "Generated from the contracts by `gyropipe schemas` (a test keeps it current).",
        "",
    ]
    for name, contract in builtin_contracts(registry).items():
        doc = " ".join((contract.__doc__ or "").split())
        lines += [f"## {name}", "", doc, ""]
        if contract.group_by:
            lines += [f"Groups: rows with equal `{contract.group_by}` are checked apart.", ""]
        columns = contract.compiled().columns
        if not columns:
            lines += ["Any columns.", ""]
            continue
        lines += [
            "| column | type | unit | required | rules | meaning |",
            "|---|---|---|---|---|---|",
        ]
        for c in columns:
            meaning = contract.model_fields[c.name].description or ""
            unit = f"`{c.unit}`" if c.unit else ""
            required = "yes" if c.required else "no"
            lines.append(
                f"| `{c.name}` | {c.type} | {unit} | {required} | {_rules(c)} | {meaning} |"
            )
        lines.append("")
    return "\n".join(lines)


def _rules(c: ColumnSpec) -> str:
    rules = [
        f"{op} {value:g}"
        for op, value in (("≥", c.ge), ("≤", c.le), ("&gt;", c.gt), ("&lt;", c.lt))
        if value is not None
    ]
    if c.monotonic:
        rules.append("strictly increasing" if c.monotonic == "strict" else "non-decreasing")
    if c.min_step is not None:
        rules.append(f"steps ≥ {c.min_step:g} {c.unit or ''}".rstrip())
    if c.north_reference:
        rules.append("north reference stated")
    if c.finite and pa.types.is_floating(c.type):
        rules.append("finite")
    if not c.nullable:
        rules.append("no nulls")
    return ", ".join(rules)


def _files(registry: Registry, directory: Path, docs: Path) -> dict[Path, str]:
    files = {directory / name: text for name, text in generate(registry).items()}
    return {**files, docs / TABLES_PAGE: tables_page(registry)}


def write(registry: Registry, directory: Path, docs: Path) -> list[Path]:
    """Write every schema under ``directory`` and the tables page under ``docs``; returns
    the paths written."""
    written = []
    for path, text in _files(registry, directory, docs).items():
        atomic_write_bytes(path, text.encode())
        written.append(path)
    return written


def stale(registry: Registry, directory: Path, docs: Path) -> list[Path]:
    """Files that are missing or differ from what the models generate."""
    return [
        path
        for path, text in _files(registry, directory, docs).items()
        if not path.is_file() or path.read_text() != text
    ]

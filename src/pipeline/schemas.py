"""JSON Schema of the pipeline YAML, the well metadata, every built-in table contract and
the JSON documents built-in writers produce.

``gyropipe schemas`` writes them under ``schemas/``; a test checks the committed files equal
what the models generate, so the schemas never drift from the code.
"""

from __future__ import annotations

import json
from pathlib import Path

from pipeline.atomic import atomic_write_bytes
from pipeline.contracts import TableContract
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


def write(registry: Registry, directory: Path) -> list[Path]:
    """Write every schema under ``directory``; returns the paths written."""
    written = []
    for name, text in generate(registry).items():
        path = directory / name
        atomic_write_bytes(path, text.encode())
        written.append(path)
    return written


def stale(registry: Registry, directory: Path) -> list[str]:
    """Schema files that are missing or differ from what the models generate."""
    return [
        name
        for name, text in generate(registry).items()
        if not (directory / name).is_file() or (directory / name).read_text() != text
    ]

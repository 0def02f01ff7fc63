"""The tool models a stage may name: the shipped model files and those the run's plugins
registered, handed down by the registry of the run — to a params model through the
planner's validation context, to a running stage through its context's provenance (the
uncertainty code never loads plugins)."""

from __future__ import annotations

from pathlib import Path

from pydantic import ValidationInfo

from pipeline.registry import Registry, StageContext
from pipeline.uncertainty.engine import MODELS_DIR, SHIPPED, ModelCatalogue, find_model
from pipeline.uncertainty.toolmodel import ToolModel


def of_registry(registry: Registry | None) -> ModelCatalogue:
    """The shipped models and those ``registry``'s plugins registered (None: shipped only)."""
    return SHIPPED if registry is None else ModelCatalogue.of(registry.tool_model_files())


def registry_of(info: ValidationInfo) -> Registry | None:
    """The registry params are validated with (the planner's validation context), if any."""
    registry = (info.context or {}).get("registry")
    return registry if isinstance(registry, Registry) else None


def validating(info: ValidationInfo) -> ModelCatalogue:
    """The models of the registry params are validated with (the shipped ones when they are
    validated without one)."""
    return of_registry(registry_of(info))


def of_run(ctx: StageContext) -> ModelCatalogue:
    """The models of the run a stage is part of."""
    return ModelCatalogue.of(ctx.provenance.tool_models)


def disabled_message(name: str, registry: Registry | None) -> str | None:
    """Why the tool model ``name`` is unknown when a plugin ``registry`` leaves out (a
    disabled one) provides it; else None."""
    plugin = registry.disabled_provider("tool_model", name) if registry is not None else None
    if plugin is None:
        return None
    return (
        f"tool model {name} is provided by plugin {plugin}, which is disabled "
        f"(--disable-plugin {plugin})"
    )


def find(model: str, info: ValidationInfo) -> ToolModel:
    """The model a params field names, in the catalogue of :func:`validating`: an unknown
    one is a ``ValueError`` saying so (and which disabled plugin provides it, if one does)."""
    try:
        return find_model(model, validating(info))
    except KeyError as exc:
        why = disabled_message(model, registry_of(info))
        raise ValueError(why or f"unknown model: {exc.args[0]}") from None


def record(ctx: StageContext, tool: ToolModel, param: str) -> None:
    """Declare the files of ``tool`` (its own and those it extends) that are not shipped
    with gyropipe as files the stage read through ``param`` (``run.json``, fingerprint),
    each by the SHA-256 of the bytes its model was parsed from."""
    for file in tool.files:
        path = Path(file)
        if path.is_file() and not path.resolve().is_relative_to(MODELS_DIR.resolve()):
            ctx.record_file(path, param, "tool-model file", tool.file_sha256.get(file))

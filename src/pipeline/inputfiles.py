"""Files a stage reads because a parameter names them, besides the pipeline's inputs.

:data:`InputPath` is the one type of every stage (or reader) parameter that names a file to
read — the twin of :data:`~pipeline.filenames.OutputFilename`: checked when the pipeline is
validated (the file must exist and be a regular file), so a missing profile is a located
problem at its YAML line, not a failure in the middle of a run. The runner hashes every such
file a run reads (:func:`parameter_paths` finds them in a stage's params; a stage declares
the files it discovers while it runs, such as a manifest's offset wells, through its
context) and records them in ``run.json`` (``parameter_inputs``) and in a batch's
fingerprint, so ``--only-changed`` runs a well again when one of them changes.
"""

from __future__ import annotations

from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Annotated, Any, get_args, get_origin

from pydantic import AfterValidator, BaseModel, Field


def check_input_path(path: Path) -> Path:
    """``path`` if it is an existing regular file; else a ``ValueError`` saying why."""
    if not path.exists():
        raise ValueError(f"no such file: {str(path)!r} (relative to the current directory)")
    if not path.is_file():
        raise ValueError(f"not a regular file: {str(path)!r}")
    return path


CHECK = AfterValidator(check_input_path)
"""The validator that marks a field as an :data:`InputPath` (:func:`parameter_paths`)."""

InputPath = Annotated[Path, CHECK, Field(json_schema_extra={"format": "path"})]
"""A parameter naming a file the stage reads (see the module doc)."""


def parameter_paths(params: BaseModel, prefix: str = "") -> Iterator[tuple[str, Path]]:
    """(dotted parameter name, path) of every :data:`InputPath` value set in ``params``,
    nested models and lists of paths (``files.0``) included, and of the files a model lists
    in its ``parameter_files()``."""
    paths = _path_fields(type(params))
    for name in type(params).model_fields:
        value = getattr(params, name)
        marked = name in paths
        if isinstance(value, Path) and marked:
            yield f"{prefix}{name}", value
        elif isinstance(value, list | tuple) and marked:
            yield from ((f"{prefix}{name}.{i}", p) for i, p in enumerate(value))
        elif isinstance(value, BaseModel):
            yield from parameter_paths(value, f"{prefix}{name}.")
    own: Any = getattr(params, "parameter_files", None)
    if callable(own):
        for name, path in own():
            yield f"{prefix}{name}", path


@cache
def _path_fields(model: type[BaseModel]) -> frozenset[str]:
    """The fields of ``model`` declared :data:`InputPath` (alone, optional or in a list):
    told once per model (looking at a stage's annotations took ~40 µs a stage and run)."""
    return frozenset(
        name
        for name, info in model.model_fields.items()
        if CHECK in info.metadata or _marked(info.annotation)
    )


def _marked(annotation: Any) -> bool:
    """Whether ``annotation`` holds :data:`InputPath` (``InputPath | None``,
    ``list[InputPath]``)."""
    if get_origin(annotation) is Annotated:
        return CHECK in annotation.__metadata__
    return any(_marked(arg) for arg in get_args(annotation))

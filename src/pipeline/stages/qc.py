"""Built-in plugin: the stage that runs a registered QC check on a table."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Annotated, Any

import pyarrow as pa
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    model_validator,
)

from pipeline.hookspecs import hookimpl
from pipeline.registry import Registry, StageContext, StageDef, registered
from pipeline.tables import AnyTable, CheckResults


class CheckParams(BaseModel):
    """Parameters of the check stage: which check, and its own parameters."""

    model_config = ConfigDict(extra="forbid")
    check: Annotated[str, registered("check")] = Field(description="registered check name")
    params: dict[str, Any] = Field(default_factory=dict, description="the check's parameters")

    @model_validator(mode="after")
    def _check_params(self, info: ValidationInfo) -> CheckParams:
        registry = (info.context or {}).get("registry")
        if isinstance(registry, Registry) and self.check in registry.checks:
            try:
                registry.checks[self.check][0].params.model_validate(self.params)
            except ValidationError as exc:
                details = "; ".join(
                    f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors()
                )
                raise ValueError(f"params of check {self.check!r}: {details}") from None
        return self


def run_check(
    inputs: Mapping[str, pa.Table], params: CheckParams, ctx: StageContext
) -> dict[str, pa.Table]:
    """Validate the table against the check's contract, then run the check."""
    check = ctx.check(params.check)
    table = inputs["table"]
    check.contract.validate_table(table)
    return {"results": check.func(table, check.params.model_validate(params.params), ctx.well)}


@hookimpl
def gyropipe_register_stages(register: Callable[[StageDef], None]) -> None:
    register(
        StageDef(
            name="check",
            func=run_check,
            description="Run a registered QC check on a table; one result row per checked row.",
            inputs={"table": AnyTable},
            outputs={"results": CheckResults},
            params=CheckParams,
        )
    )

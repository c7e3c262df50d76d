"""Shared building blocks: the package's one error type and the strict field types every model uses."""

from __future__ import annotations

from typing import Annotated

from pydantic import ConfigDict, Field, StringConstraints

from kintsugi.core.config import StrictModel
from kintsugi.core.errors import KintsugiError


class GraphError(KintsugiError):
    """A task graph (or a piece of one) is unusable; the message names the offending element."""


class GraphModel(StrictModel):
    """StrictModel that also refuses NaN/inf anywhere a number is typed."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


Id = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9_][A-Za-z0-9_.:-]{0,63}$")]
"""Node, edge and monitor ids: short, printable, no spaces (they appear in logs and DOT files)."""

Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z][A-Za-z0-9_.-]{0,63}$")]
"""Object, arm, feature and action names; never starts with '_' (features are read by getattr)."""

Text = Annotated[str, StringConstraints(max_length=2000)]

Num = Annotated[float, Field(strict=True, allow_inf_nan=False)]
"""A finite number; ints are fine, bools and numeric strings are not."""

NonNeg = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0)]

Vec3 = tuple[Num, Num, Num]

"""Base type of every scenario section: frozen, typed, no unknown keys, no NaN/inf."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

Vec3 = tuple[float, float, float]
"""A 3-vector given as a TOML array of three numbers."""

PositiveVec3 = tuple[
    Annotated[float, Field(gt=0)], Annotated[float, Field(gt=0)], Annotated[float, Field(gt=0)]
]
"""A 3-vector of strictly positive numbers."""


class Section(BaseModel):
    """A validated, immutable group of scenario parameters.

    Unknown keys are rejected (a typo fails loudly), NaN and infinity are rejected, and
    instances are frozen (hashable and safe to share between threads and processes).
    """

    model_config = ConfigDict(
        frozen=True,
        extra="forbid",
        allow_inf_nan=False,
        validate_default=True,
        use_attribute_docstrings=True,
    )

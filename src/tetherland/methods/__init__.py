"""Landing methods: one role (:class:`LandingMethod`), two implementations, one registry.

>>> from tetherland.methods import get_method, method_names
>>> method_names()
('tethered', 'free-flight')
>>> get_method("tethered").expects.required_conditions
(1, 2, 3, 4, 5)

The CLI (``--method``), the closed loop (:func:`tetherland.runs.run_mission`) and the
campaign all look methods up here.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from tetherland.errors import ConfigError
from tetherland.methods.base import ControllerChoice, Flight, LandingMethod, Planners
from tetherland.methods.contact_free import ContactFreeMethod
from tetherland.methods.tethered import TetheredMethod

METHODS: Mapping[str, LandingMethod] = MappingProxyType(
    {m.name: m for m in (TetheredMethod(), ContactFreeMethod())}
)
"""Every registered landing method by name."""


def method_names() -> tuple[str, ...]:
    """Names of the registered methods, the tethered one first."""
    return tuple(METHODS)


def get_method(name: str, option: str = "method") -> LandingMethod:
    """The registered method ``name``; a one-line :class:`ConfigError` naming ``option``
    (the field or command-line option that gave it) if there is none."""
    try:
        return METHODS[name]
    except KeyError:
        raise ConfigError(f"{option} must be one of {', '.join(METHODS)} (got {name!r})") from None


__all__ = [
    "METHODS",
    "ContactFreeMethod",
    "ControllerChoice",
    "Flight",
    "LandingMethod",
    "Planners",
    "TetheredMethod",
    "get_method",
    "method_names",
]

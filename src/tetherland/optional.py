"""Optional dependencies: import them with one clear message when they are missing."""

from __future__ import annotations

import importlib
from types import ModuleType

from tetherland.errors import MissingDependencyError


def require(module: str, *, package: str, extra: str, feature: str) -> ModuleType:
    """Import ``module`` or raise :class:`MissingDependencyError` naming the extra to install.

    Parameters
    ----------
    module : str
        Module to import (``"foxglove"``).
    package : str
        Distribution that provides it (``"foxglove-sdk"``).
    extra : str
        tetherland extra that installs it (``"viz"``).
    feature : str
        What needs it, for the message (``"the MCAP export"``).
    """
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise MissingDependencyError(
            f"{feature} needs the '{package}' package, which is not installed: "
            f"pip install 'tetherland[{extra}]' (or pip install {package})"
        ) from err

"""Exception types. ``str(error)`` is always a one-line message fit for a user."""

from __future__ import annotations


class TetherlandError(Exception):
    """Base class of every error the command line reports without a traceback."""


class ConfigError(TetherlandError, ValueError):
    """A scenario, an override or a command-line value is malformed or out of range."""


class ConfigErrors(ConfigError):
    """Every problem of one input at once (a scenario file with several bad fields).

    ``messages`` holds one line per problem; ``str(error)`` joins them on one line.
    """

    def __init__(self, messages: list[str] | tuple[str, ...]):
        self.messages = tuple(messages)
        super().__init__("; ".join(self.messages))


class SingularityError(TetherlandError, ArithmeticError):
    """A formula was evaluated at (or too near) a singular configuration.

    Raised instead of dividing by zero, e.g. for a horizontal surface where a direction
    is undefined, or a link elevation with ``cos(delta) = 0``.
    """


class SimulationError(TetherlandError, RuntimeError):
    """The physics simulation diverged or was driven with an invalid input."""


class InfeasibleError(TetherlandError):
    """A valid request that cannot be met (no plan, no design, a surface out of reach).

    The command line reports it on one line with exit code 1 (invalid input is 2).
    """


class MissingDependencyError(TetherlandError, ImportError):
    """An optional dependency (an extra such as ``tetherland[viz]``) is not installed."""

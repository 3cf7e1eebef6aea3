"""Fixed-step integrators of x' = f(x, u) with the input held, for numpy and CasADi alike.

The steps are plain arithmetic on whatever ``f`` returns, so one function serves numbers
(floats, numpy arrays with any trailing sample axes) and CasADi symbols (SX, MX): the
shooting transcription, the planners' dense re-simulations and the rigid-body model all
integrate with :func:`rk4`.

Classical Runge-Kutta (4th order, local error O(h^5)):

  k1 = f(x, u),  k2 = f(x + h/2 k1, u),  k3 = f(x + h/2 k2, u),  k4 = f(x + h k3, u)
  x(t + h) = x + h/6 (k1 + 2 k2 + 2 k3 + k4)

``h`` may be a scalar or, for numpy, an array that broadcasts against ``x`` (one step
length per sample).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Literal, TypeVar

X = TypeVar("X")
Rhs = Callable[[Any, Any], Any]
"""f(x, u) -> x' (same type and shape as x)."""
Method = Literal["rk4", "euler"]
METHODS: tuple[str, ...] = ("rk4", "euler")


def rk4(f: Rhs, x: X, u: Any, h: Any) -> X:
    """One classical Runge-Kutta step of length ``h`` from ``x`` with ``u`` held."""
    k1 = f(x, u)
    k2 = f(x + 0.5 * h * k1, u)
    k3 = f(x + 0.5 * h * k2, u)
    k4 = f(x + h * k3, u)
    return x + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)  # type: ignore[no-any-return]


def euler(f: Rhs, x: X, u: Any, h: Any) -> X:
    """One explicit Euler step (1st order; for tests of the transcription)."""
    return x + h * f(x, u)  # type: ignore[no-any-return]


def step(method: Method, f: Rhs, x: X, u: Any, h: Any) -> X:
    """One step of ``method`` ("rk4" or "euler")."""
    if method == "rk4":
        return rk4(f, x, u, h)
    if method == "euler":
        return euler(f, x, u, h)
    raise ValueError(f"integrator must be one of {', '.join(METHODS)}, got {method!r}")

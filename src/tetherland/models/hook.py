"""The hook model: where the vehicle's hook point is relative to its cable attachment.

Assumed model: the hook point is the cable attachment point moved by ``hook_drop`` along
the approach direction n, leading the vehicle in the direction it moves. For the default
approach n = -z_W this is the hook hanging under the vehicle; for other directions the
hook is held out along the approach direction (a hook on a short stiff arm), which lets
the vehicle hook an anchor on a wall or an overhang from the side or from below.

:func:`hook_offset` is the one statement of it: the plant's hook (:mod:`tetherland.sim.hook`)
and the robot's hooking pass, clearance check and design search
(:mod:`tetherland.mission.hooking`) all use it.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland import GRAVITY
from tetherland.geometry import FloatArray


def hook_offset(n_W: FloatArray, hook_drop: float) -> FloatArray:
    """Hook point minus attachment point, hook_drop n [m], for the unit approach direction
    ``n_W`` (F_W) and the hook drop [m]."""
    return hook_drop * n_W


def bar_line_length(tether_length: float, hook_shank: float, hook_radius: float,
                    bar_radius: float) -> float:  # fmt: skip
    """Length of the hanging line of the bar mechanism, attachment to the hook's eye [m].

    Caught, the bar rests in the crook between the shank and a tip, on the arm: its axis
    lies ``hook_radius + bar_radius`` above the crown, the eye ``hook_shank`` above it. The
    line is shorter than ``tether_length`` by the eye's height above the bar's axis, so
    that the anchor p_A (the bar's axis) to the attachment is l when taut.
    """
    return tether_length - (hook_shank - hook_radius - bar_radius)


def bar_hook_offset(x_A_W: FloatArray, line_length: float, hook_shank: float,
                    pass_offset: float) -> FloatArray:  # fmt: skip
    """The bar mechanism's counterpart of :func:`hook_offset`: the vector v such that the
    attachment point p_A + s n - v puts the hanging hook's crown ``pass_offset`` from the
    bar's axis, on the side away from the landing point (-x_A, ``x_A_W`` in F_W), at depth
    s along the pass (n = -z_W) [m].

    The hook hangs ``line_length + hook_shank`` straight below the attachment (at rest),
    so v = -(line_length + hook_shank) z_W + pass_offset x_A (horizontal part of x_A).
    """
    x = np.array([x_A_W[0], x_A_W[1], 0.0])
    x /= np.linalg.norm(x)
    return np.array([0.0, 0.0, -(line_length + hook_shank)]) + pass_offset * x


def swing_period(line_length: float, hook_shank: float) -> float:
    """Swing period 2 pi sqrt(L/g) of a hook hanging on a line, L the line plus half the
    shank (the hook's mass dominates the line's) [s]."""
    return 2.0 * math.pi * math.sqrt((line_length + 0.5 * hook_shank) / GRAVITY)

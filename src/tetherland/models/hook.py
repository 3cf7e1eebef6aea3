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

from tetherland.geometry import FloatArray


def hook_offset(n_W: FloatArray, hook_drop: float) -> FloatArray:
    """Hook point minus attachment point, hook_drop n [m], for the unit approach direction
    ``n_W`` (F_W) and the hook drop [m]."""
    return hook_drop * n_W

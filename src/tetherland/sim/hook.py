"""Hook and anchoring mechanism (chapter 6.6.1-6.6.2): when the cable is engaged.

The vehicle carries the hook; the anchoring mechanism sits at the anchor point p_A. The
capture disk has centre p_A, unit normal n (the approach direction) and radius r_c. The
hook point is the cable attachment point moved by ``hook_drop`` along n
(:func:`tetherland.models.hook.hook_offset`, the one statement of the hook model that the
mission plan, the clearance check and the design search also use): for the default
n = -z_W the hook hanging under the vehicle, for any other direction a hook held out along
n (on a short stiff arm), e.g. horizontally toward a wall or along the normal of a steep
slope or an overhang. ``hook_drop = 0`` puts it at the attachment point.

- Disengaged, the hook point crossing the disk's plane along +n at a distance <= r_c from
  p_A engages the cable (``ENGAGED``); the same crossing farther than r_c but within
  ``miss_radius`` is a ``MISSED`` hook (the crossing happened, the hook did not catch).
- Engaged, crossing the disk back (along -n, within r_c) releases the cable (``RELEASED``):
  the approach path flown in reverse.

Crossings are detected between consecutive updates (sign change of n.(p_hook - p_A)), the
crossing point is interpolated linearly. Pure Python floats: it runs at the physics rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.models.hook import hook_offset


class HookState(IntEnum):
    """Whether the cable is attached to the anchor."""

    DISENGAGED = 0
    ENGAGED = 1


class HookEventKind(IntEnum):
    """What happened at a crossing of the capture plane."""

    ENGAGED = 1
    RELEASED = 2
    MISSED = 3
    SNAPPED = 4
    """Fault: the cable broke (distance and point: the attachment point then)."""


@dataclass(frozen=True, slots=True)
class HookEvent:
    """A hook event.

    Attributes
    ----------
    t : float
        Time of the update that detected the crossing [s].
    kind : HookEventKind
    distance : float
        Distance of the crossing point from p_A [m].
    point_W : (3,) array
        Crossing point of the hook point with the capture plane [m].
    """

    t: float
    kind: HookEventKind
    distance: float
    point_W: FloatArray

    def as_dict(self) -> dict[str, object]:
        return {
            "t": self.t,
            "kind": self.kind.name,
            "distance": self.distance,
            "point_W": [float(x) for x in self.point_W],
        }


class Hook:
    """Capture-disk hook model; call :meth:`update` with the attachment point each step.

    Parameters
    ----------
    anchor_W : (3,) array
        Anchor point p_A (disk centre) [m].
    approach_W : (3,) array
        Approach direction n (disk normal), any length [-].
    capture_radius : float
        r_c [m].
    hook_drop : float
        Distance of the hook point from the attachment point, along n [m].
    miss_radius : float
        Forward crossings with r_c < distance <= miss_radius are reported as ``MISSED`` [m].
    """

    __slots__ = (
        "_engaged",
        "_n",
        "_offset",
        "_p_A",
        "_prev",
        "capture_radius",
        "events",
        "jammed",
        "miss_radius",
        "severed",
    )

    def __init__(
        self,
        anchor_W: ArrayLike,
        approach_W: ArrayLike,
        capture_radius: float,
        hook_drop: float = 0.0,
        miss_radius: float = math.inf,
    ) -> None:
        n = np.asarray(approach_W, dtype=float)
        norm = float(np.linalg.norm(n))
        if norm < 1e-12:
            raise ValueError("approach direction must be non-zero")
        if capture_radius <= 0 or hook_drop < 0:
            raise ValueError("capture_radius must be > 0 and hook_drop >= 0")
        n_W = n / norm
        self._n = tuple(float(x) for x in n_W)
        self._p_A = tuple(float(x) for x in np.asarray(anchor_W, dtype=float))
        self._offset = tuple(float(x) for x in hook_offset(n_W, float(hook_drop)))
        self.capture_radius = float(capture_radius)
        self.miss_radius = float(miss_radius)
        self._engaged = False
        self._prev: tuple[float, float, float] | None = None
        self.events: list[HookEvent] = []
        self.jammed = False
        """Fault: crossing the disk back does not release the cable."""
        self.severed = False
        """Fault: the cable is broken; it never engages again."""

    @property
    def engaged(self) -> bool:
        """True while the cable is attached to the anchor."""
        return self._engaged

    def record(self, t: float, engaged: bool, point_W: ArrayLike) -> None:
        """A mechanism in contact (the bar) caught (``engaged``) or let go of the hook at
        ``t`` with the hook at ``point_W``: record the event and set the state [s, m]."""
        p = np.asarray(point_W, dtype=float)
        dist = float(np.linalg.norm(p - np.asarray(self._p_A)))
        kind = HookEventKind.ENGAGED if engaged else HookEventKind.RELEASED
        self.events.append(HookEvent(t, kind, dist, p.copy()))
        self._engaged = bool(engaged)

    def sever(self, t: float, p_att_W: ArrayLike) -> None:
        """Fault: the cable breaks at ``t`` with the attachment point at ``p_att_W``; it
        is detached and never engages again."""
        p = np.asarray(p_att_W, dtype=float)
        dist = float(np.linalg.norm(p - np.asarray(self._p_A)))
        self.events.append(HookEvent(t, HookEventKind.SNAPPED, dist, p.copy()))
        self._engaged = False
        self.severed = True

    @property
    def state(self) -> HookState:
        return HookState.ENGAGED if self._engaged else HookState.DISENGAGED

    def reset(self, engaged: bool = False) -> None:
        """Forget the previous position, events and faults; set the state."""
        self._engaged = bool(engaged)
        self.jammed = self.severed = False
        self._prev = None
        self.events.clear()

    @property
    def n_W(self) -> FloatArray:
        """Unit approach direction n (the capture disk's normal) [-]."""
        return np.array(self._n)

    @property
    def offset_W(self) -> FloatArray:
        """Hook point minus attachment point, ``hook_drop`` n [m]."""
        return np.array(self._offset)

    @property
    def plane(self) -> tuple[float, float, float, float]:
        """(n_x, n_y, n_z, c) with :meth:`side` >= 0 exactly when n.p_att >= c, for a
        caller that tests the attachment point itself [-, m]."""
        n, p_A, off = self._n, self._p_A, self._offset
        c = sum(n[i] * (p_A[i] - off[i]) for i in range(3))
        return (n[0], n[1], n[2], c)

    def hook_point(self, p_att_W: ArrayLike) -> FloatArray:
        """Hook point for an attachment point [m]."""
        return np.asarray(p_att_W, dtype=float) + self.offset_W

    def side(self, x: float, y: float, z: float) -> float:
        """Signed distance n.(p_hook - p_A) of the hook point for attachment point (x, y, z):
        negative before the capture plane (on the approach side) [m]."""
        nx, ny, nz = self._n
        ax, ay, az = self._p_A
        ox, oy, oz = self._offset
        return nx * (x + ox - ax) + ny * (y + oy - ay) + nz * (z + oz - az)

    def update(self, t: float, x: float, y: float, z: float) -> HookEventKind | None:
        """Advance with the attachment point (x, y, z) in F_W at time ``t`` [s, m].

        Returns the event kind if the state changed or a hook was missed, else None.
        """
        prev = self._prev
        self._prev = (x, y, z)
        if prev is None:
            return None
        return self.cross(t, prev, (x, y, z))

    def cross(
        self, t: float, prev: tuple[float, float, float], p: tuple[float, float, float]
    ) -> HookEventKind | None:
        """Process the move of the attachment point from ``prev`` to ``p`` (at time ``t``).

        Stateless apart from the engaged flag and the events: callers that track the
        previous point themselves (the plant, at every physics step) call this only when
        :meth:`side` changed sign.
        """
        self._prev = p
        prev_s, s = self.side(*prev), self.side(*p)
        forward = prev_s < 0.0 <= s
        backward = prev_s >= 0.0 > s
        if not ((forward and not self._engaged) or (backward and self._engaged)):
            return None
        if (forward and self.severed) or (backward and self.jammed):
            return None
        lam = prev_s / (prev_s - s)
        ox, oy, oz = self._offset
        px, py, pz = prev[0] + ox, prev[1] + oy, prev[2] + oz
        x, y, z = p[0] + ox, p[1] + oy, p[2] + oz
        ax, ay, az = self._p_A
        cx, cy, cz = px + lam * (x - px), py + lam * (y - py), pz + lam * (z - pz)
        dist = math.sqrt((cx - ax) ** 2 + (cy - ay) ** 2 + (cz - az) ** 2)
        kind: HookEventKind | None = None
        if forward:
            if dist <= self.capture_radius:
                kind = HookEventKind.ENGAGED
                self._engaged = True
            elif dist <= self.miss_radius:
                kind = HookEventKind.MISSED
        elif dist <= self.capture_radius:
            kind = HookEventKind.RELEASED
            self._engaged = False
        if kind is not None:
            self.events.append(HookEvent(t, kind, dist, np.array([cx, cy, cz])))
        return kind

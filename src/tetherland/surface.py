"""The landing surface P_S and its frame F_S (docs/theory.md section 3, chapter section 6.2).

Pure geometry of plain numbers: the surface frame from a slope and azimuth or from a
normal, the :class:`Surface` (a plane, or the tangent plane on top of a pipe) and how far
spherical lander tips sag below a pipe's top line. It sits below the configuration, whose
cross-section checks use it, and below :mod:`tetherland.geometry`, which builds the
landing geometry on it. ``R_XY`` maps coordinates in Y to coordinates in X; columns of
``R_WS`` are x_S, y_S, z_S. Lengths in metres, angles in radians.

``FloatArray``, the float64 array type of every signature in the package, is stated here,
at the bottom of the geometry (:mod:`tetherland.geometry` re-exports it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tetherland.errors import SingularityError

FloatArray = NDArray[np.float64]

Z_W: FloatArray = np.array([0.0, 0.0, 1.0])
HORIZONTAL_TOL = 1e-12
"""Below this ||z_W x z_S|| the surface counts as horizontal and F_S = F_W (section 6.2)."""


def unit(v: ArrayLike, what: str = "vector") -> FloatArray:
    """Return ``v / ||v||``; raise :class:`SingularityError` for a (near) zero vector."""
    v = np.asarray(v, dtype=float)
    n = float(np.linalg.norm(v))
    if n < 1e-15:
        raise SingularityError(f"{what} has zero length; its direction is undefined")
    return v / n


def normal_from_slope(slope: float, azimuth: float = 0.0) -> FloatArray:
    """Outward unit normal n_S of a surface with slope angle ``slope`` in [0, pi] whose
    downhill direction has azimuth ``azimuth`` (from x_W towards y_W) [rad].

    n_S = [sin(beta) cos(az), sin(beta) sin(az), cos(beta)]: past vertical (beta > pi/2)
    the surface faces down and n_S . z_W = cos(beta) < 0 (an overhang).
    """
    s = math.sin(slope)
    return np.array([s * math.cos(azimuth), s * math.sin(azimuth), math.cos(slope)])


def surface_frame_from_slope(slope: float, azimuth: float = 0.0) -> FloatArray:
    """R_WS = [x_S y_S z_S] of a surface given by its slope angle and downhill azimuth.

    With beta = ``slope`` in [0, pi] and az = ``azimuth`` [rad]:
      z_S = n_S = [sin(beta) cos(az), sin(beta) sin(az), cos(beta)]  (outward normal)
      y_S = [-sin(az), cos(az), 0]                                    (horizontal)
      x_S = y_S x z_S = [cos(beta) cos(az), cos(beta) sin(az), -sin(beta)]  (downhill)
    so x_S . z_W = -sin(beta), z_S . z_W = cos(beta), y_S . z_W = 0 for every slope,
    walls (beta = pi/2) and overhangs (beta > pi/2) included; the frame is smooth in
    beta. For 0 < beta < pi it equals :func:`surface_frame` of n_S (section 6.2:
    y_S = z_W x z_S / ||.||); at beta = 0 x_S points along ``azimuth`` (F_S = F_W for
    azimuth 0, the chapter's horizontal case).
    """
    cb, sb = math.cos(slope), math.sin(slope)
    ca_, sa = math.cos(azimuth), math.sin(azimuth)
    x_S = np.array([cb * ca_, cb * sa, -sb])
    y_S = np.array([-sa, ca_, 0.0])
    z_S = np.array([sb * ca_, sb * sa, cb])
    return np.column_stack((x_S, y_S, z_S))


def surface_frame(n_S: ArrayLike) -> FloatArray:
    """Rotation R_WS = [x_S y_S z_S] of the surface frame (section 6.2).

    z_S = n_S, the outward normal (the side the vehicle lands on; z_S . z_W < 0 for an
    overhang). If z_S = z_W the surface is horizontal and F_S = F_W; if z_S = -z_W (a
    ceiling) F_S = F_W turned by pi about y_W (x_S = -x_W, y_S = y_W), the limit of a
    slope of azimuth 0; otherwise y_S = z_W x z_S / ||.|| and x_S = y_S x z_S, so x_S
    points downhill (x_S . z_W = -sin(beta) <= 0).
    """
    z_S = unit(n_S, "surface normal")
    cross = np.cross(Z_W, z_S)
    norm = float(np.linalg.norm(cross))
    if norm < HORIZONTAL_TOL:
        if z_S @ Z_W > 0:
            return np.eye(3)
        return np.diag([-1.0, 1.0, -1.0])
    y_S = cross / norm
    x_S = np.cross(y_S, z_S)
    x_S /= np.linalg.norm(x_S)
    return np.column_stack((x_S, y_S, z_S))


def surface_frame_of(normal: ArrayLike | None, slope: float, azimuth: float) -> FloatArray:
    """R_WS of a surface given by its ``normal`` (:func:`surface_frame`) or, when that is
    None, by its slope angle and downhill azimuth [rad] (:func:`surface_frame_from_slope`)."""
    if normal is not None:
        return surface_frame(np.asarray(normal, dtype=float))
    return surface_frame_from_slope(slope, azimuth)


def slope_angle(R_WS: FloatArray) -> float:
    """Slope angle beta = acos(z_S . z_W) [rad], in [0, pi] (past pi/2: an overhang)."""
    return math.acos(min(1.0, max(-1.0, float(R_WS[2, 2]))))


def pipe_sag(pipe_radius: float, lander_half_width: float, lander_radius: float = 0.0) -> float:
    """How far the lander tips sit below the top line of a pipe [m].

    Spherical tips of radius r at lateral offset w rest on a cylinder of radius R with
    their centres at R + r from the axis, so their lowest points (the landers plane) are
    R + r - sqrt((R + r)^2 - w^2) below the tangent plane P_S; the effective h_R on a
    pipe is h_R minus this sag.
    """
    if lander_half_width >= pipe_radius:
        raise SingularityError(
            f"landers (half-width {lander_half_width} m) do not fit on a pipe of radius "
            f"{pipe_radius} m"
        )
    reach = pipe_radius + lander_radius
    return reach - math.sqrt(reach**2 - lander_half_width**2)


@dataclass(frozen=True)
class Surface:
    """The landing surface P_S (a plane, or the tangent plane on top of a pipe).

    Attributes
    ----------
    origin : (3,) array
        A point O_S on P_S in F_W [m].
    R_WS : (3, 3) array
        Surface frame; columns x_S (downhill), y_S, z_S = n_S.
    kind : str
        ``"plane"`` or ``"pipe"``.
    pipe_radius : float
        Pipe radius [m] (pipe only).
    friction : float
        mu [-].
    f_N_min : float
        Minimum normal force [N] (<= 0).
    """

    origin: FloatArray
    R_WS: FloatArray
    kind: str = "plane"
    pipe_radius: float = 0.0
    friction: float = 0.6
    f_N_min: float = 0.0

    @property
    def x_S(self) -> FloatArray:
        return self.R_WS[:, 0]

    @property
    def y_S(self) -> FloatArray:
        return self.R_WS[:, 1]

    @property
    def z_S(self) -> FloatArray:
        return self.R_WS[:, 2]

    @property
    def slope(self) -> float:
        """Slope angle beta [rad]."""
        return slope_angle(self.R_WS)

    @property
    def is_horizontal(self) -> bool:
        """z_S = z_W (facing up; x_S may point along any azimuth)."""
        return bool(self.R_WS[2, 2] > 1.0 - 1e-12)

    def height(self, p: ArrayLike) -> float:
        """Signed distance of ``p`` above P_S along z_S [m] (h_A for the anchor)."""
        return float(self.z_S @ (np.asarray(p, dtype=float) - self.origin))

    def project(self, p: ArrayLike) -> FloatArray:
        """Orthogonal projection of ``p`` on P_S [m]."""
        return np.asarray(p, dtype=float) - self.height(p) * self.z_S

    def plane_coefficients(self) -> FloatArray:
        """[a, b, c, d] with a x + b y + c z + d = 0 and [a, b, c] = n_S."""
        return np.append(self.z_S, -self.z_S @ self.origin)

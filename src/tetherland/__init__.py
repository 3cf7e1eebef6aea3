"""tetherland: tethered landing and takeoff of aerial robots on steep slopes.

Conventions (see ``docs/theory.md`` section 2): SI units inside the code, degrees only at the
user boundary; world frame z_W up; body frame FLU with z_B the thrust axis (the
chapter's z_R = -z_B); quaternions scalar-first (w, x, y, z); ``R_XY`` maps coordinates in
frame Y to frame X.
"""

from importlib.metadata import PackageNotFoundError, version

from tetherland import kernel_cache

# before numba is imported: compiled kernels cached by their sources (kernel_cache's doc)
kernel_cache.configure()

try:
    __version__ = version("tetherland")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

GRAVITY = 9.81
"""Gravitational acceleration g [m/s^2] (docs/theory.md section 2)."""

__all__ = ["GRAVITY", "__version__"]

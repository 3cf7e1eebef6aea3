"""Dynamics models (docs/theory.md section 4).

* :mod:`.quadrotor`: rotor layout, allocation Gamma (6.19) and its saturated inverse
  (:meth:`RotorLayout.allocate`), rotor lag :class:`RotorModel`;
* :mod:`.rigid_body`: free-flight rigid-body dynamics (6.1)-(6.2);
* :mod:`.tethered`: taut-tether 3D dynamics of (phi, delta) and the tension (6.4);
* :mod:`.planar`: planar model (6.18) and its double dynamic extension (6.20), numpy and
  CasADi;
* :mod:`.flatness`: the flatness map from y^b = [phi, delta, theta_A, psi] to the nominal
  state and input;
* :mod:`.airframe`: the vehicle's collision shape (landers, legs, hub, arms, rotor guards,
  cable mount);
* :mod:`.hook`: the hook model (where the hook point is, relative to the attachment).
"""

from tetherland.models.flatness import FlatnessMap, NominalState, OutputDerivatives
from tetherland.models.planar import ExtendedPlanarModel, PlanarParams, planar_flat_inputs
from tetherland.models.quadrotor import Allocation, RotorLayout, RotorModel, Saturation
from tetherland.models.rigid_body import RigidBodyParams, rigid_body_derivative, rk4_step

__all__ = [
    "Allocation",
    "ExtendedPlanarModel",
    "FlatnessMap",
    "NominalState",
    "OutputDerivatives",
    "PlanarParams",
    "RigidBodyParams",
    "RotorLayout",
    "RotorModel",
    "Saturation",
    "planar_flat_inputs",
    "rigid_body_derivative",
    "rk4_step",
]

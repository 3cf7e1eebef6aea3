"""The plant's state at the start of a tethered plan: the cable taut at the planned tension.

The plan's link is the landed link l + s (docs/theory.md section 13.2); an elastic cable
holding the plan's start tension T is l (1 + T/EA) long, so the plant starts there, along
the planned link, and its cable pulls T from the first step.
"""

from __future__ import annotations

import numpy as np

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry, cable_stretch
from tetherland.models.quadrotor import RotorModel
from tetherland.planning.trajectory import Trajectory
from tetherland.rotations import rotmat_to_quat
from tetherland.state import RigidBodyState


def plan_start_state(plan: Trajectory, scenario: Scenario) -> tuple[RigidBodyState, FloatArray]:
    """The plan's first state with the cable taut, and the rotor speeds [rad/s] of its
    thrusts (flatness, 6.6.1).

    The attachment point lies l (1 + T/EA) from the anchor along the planned link
    direction, T the plan's start tension [N] (l for an inextensible cable); attitude,
    velocity and body rate are the plan's.
    """
    nom = plan.nominal(0.0)
    r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
    t = scenario.tether
    stretch = cable_stretch(float(nom.tension), t.length, t.effective_axial_stiffness)
    p_A = LandingGeometry.from_scenario(scenario).p_A
    link = nom.p_W - p_A  # nom.p_W: the planned attachment point
    p_att = p_A + link * ((t.length + stretch) / float(np.linalg.norm(link)))
    x0 = RigidBodyState(p_att - nom.R_WB @ r_att, nom.v_W, rotmat_to_quat(nom.R_WB),
                        nom.omega_B)  # fmt: skip
    return x0, RotorModel.from_config(scenario.vehicle).speed(nom.rotor_thrusts)

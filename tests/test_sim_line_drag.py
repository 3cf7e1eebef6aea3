"""The bar mechanism's hanging line in air (docs/mechanism.md, *Numerics*): its drag, and
a slack line whipped by its falling hook that must not gain energy (campaign slope50,
slope 35 deg, run tethered-35-00004: the released hook fell off the bar, the slack line
whipped and the plant diverged)."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.sim.line_drag import (
    AIR_DENSITY,
    LINE_DRAG_COEFFICIENT,
    line_drag_into,
    line_drag_reference,
)
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

PILOT = ["tether.length=1.2", "tether.hook_drop=1.0", "mechanism.kind=bar",
         "surface.slope_deg=35"]  # fmt: skip
"""The pilot campaign's settings (tethered-35-00004)."""


def _held_plant() -> tuple[Plant, int, list[int]]:
    """The pilot's plant with the vehicle 1e4 times heavier, 2.5 m above the anchor (far
    from anything) and its weight and the line's carried by an applied force: a fixed
    point that does no work [plant, vehicle body id, line and hook body ids]."""
    plant = Plant(load_scenario("slope50", PILOT))
    m = plant.model
    vehicle = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
    m.body_mass[vehicle] *= 1e4
    m.body_inertia[vehicle] *= 1e4
    names = [f"line_link{i}" for i in range(plant.cable.spec.segments)] + ["hook"]
    line = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, n) for n in names]
    start = plant.layout.geometry.p_A + np.array([0.0, 0.0, 2.5])
    plant.reset(RigidBodyState.at_rest(start, plant.start_state().q_WB))
    return plant, vehicle, line


def test_each_link_is_pushed_back_with_its_broadside_drag() -> None:
    """The line laid out straight and level, turned as one rigid piece about its first
    joint at w: link i's centre moves broadside at w r_i, and the kernel pushes it back
    with 1/2 rho C_d (2 r) l_s (w r_i)^2 against that velocity; the compiled kernel gives
    its numpy reference."""
    plant, _, line = _held_plant()
    m, d = plant.model, plant.data
    spec = plant.cable.spec
    p_att = plant.attachment_point()
    plant.cable.lay_out(toward_W=p_att + np.array([2.0, 0.0, 0.0]))
    w = 3.0  # [rad/s] about the link's local z: the line sweeps a horizontal plane
    adr = m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "line_joint0")]
    d.qvel[adr : adr + 3] = (0.0, 0.0, w)
    mujoco.mj_forward(m, d)
    links = np.array(line[:-1], dtype=np.int64)
    root = int(m.body_rootid[links[0]])
    k = 0.5 * AIR_DENSITY * LINE_DRAG_COEFFICIENT * 2.0 * spec.radius * spec.link_length
    xfrc = np.zeros_like(d.xfrc_applied)
    line_drag_into(links, root, k, d.cvel, d.xipos, d.xmat, d.subtree_com, xfrc)
    r = (np.arange(spec.segments) + 0.5) * spec.link_length
    np.testing.assert_allclose(np.linalg.norm(xfrc[links, 0:3], axis=1), k * (w * r) ** 2,
                               rtol=1e-6)  # fmt: skip
    v = np.array([np.cross(d.cvel[b, 0:3], d.xipos[b] - p_att) for b in links])
    cos = (
        np.sum(xfrc[links, 0:3] * v, axis=1)
        / np.linalg.norm(v, axis=1)
        / (np.linalg.norm(xfrc[links, 0:3], axis=1))
    )
    np.testing.assert_allclose(cos, -1.0, atol=1e-9)  # against the velocity
    ref = line_drag_reference(links, root, k, d.cvel, d.xipos, d.xmat, d.subtree_com)
    np.testing.assert_allclose(xfrc[links, 0:3], ref, rtol=1e-12, atol=1e-15)
    assert not xfrc[[b for b in range(m.nbody) if b not in set(links)]].any()


@pytest.mark.parametrize("direction", [(1.0, 0.0, 1.0), (-1.0, 0.5, 0.8)])
def test_slack_line_whipped_by_its_falling_hook_does_not_gain_energy(
    direction: tuple[float, float, float],
) -> None:
    """The line laid out straight up and out from a fixed point and let go: the hook
    falls, the slack line folds and whips (its joints turning at 100-300 rad/s) and
    snaps taut under it. Nothing does work on the line and the hook but gravity (the
    applied force holds the pivot still), so their energy E = T + V can only fall (air
    drag, joint damping). Before the line's drag, the integration's error added 26 mJ
    and 10 mJ for these two directions (the campaign's run gained joules and diverged);
    allowed: 0.5 % of the hook's fall through the line's length, m g L. No divergence,
    and the pivot does not move."""
    plant, vehicle, line = _held_plant()
    m, d = plant.model, plant.data
    line_mass = float(sum(m.body_mass[b] for b in line))
    p_att = plant.attachment_point()
    u = np.asarray(direction) / np.linalg.norm(direction)
    plant.cable.lay_out(toward_W=p_att + 5.0 * u)
    plant.forward()
    M = np.zeros((m.nv, m.nv))

    def energy() -> float:
        """Kinetic energy of everything plus the line's and the hook's weight's potential;
        the vehicle's weight and the applied force cancel but for the line's share."""
        mujoco.mj_fullM(m, d, M)
        height = sum(float(m.body_mass[b] * d.xipos[b, 2]) for b in line)
        return 0.5 * float(d.qvel @ M @ d.qvel) + GRAVITY * (
            height - line_mass * float(d.xipos[vehicle, 2])
        )

    E = [energy()]
    for _ in range(round(4.0 / plant.dt)):
        d.xfrc_applied[vehicle, :] = 0.0
        d.xfrc_applied[vehicle, 2] = (m.body_mass[vehicle] + line_mass) * GRAVITY
        plant.step(1)  # raises SimulationError on a divergence
        E.append(energy())
    allowed = 0.005 * plant.scenario.mechanism.hook_mass * GRAVITY * (plant.cable.spec.line_length)
    assert max(E) - E[0] < allowed
    assert E[-1] < E[0] - 10 * allowed  # the whip's energy was dissipated, not kept
    np.testing.assert_allclose(plant.attachment_point(), p_att, atol=1e-3)

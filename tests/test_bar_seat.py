"""The bar hook's seat (``mechanism.hook_arm_rise_deg``, docs/mechanism.md): rising arms
give the crook one low point, the arm-tip corner, and the plan's line length, climb and
validator use the plant's geometry."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.models.hook import bar_line_length
from tetherland.sim.plant import Plant

BAR = ["mechanism.kind=bar"]


def _hook_segments(rise_deg: float) -> tuple[list[tuple[np.ndarray, np.ndarray]], Plant]:
    """The hook's capsule axes as (start, end) in the hook body's frame (x from the eye
    down the shank), from the compiled plant model [m]."""
    plant = Plant(load_scenario("slope50", [*BAR, f"mechanism.hook_arm_rise_deg={rise_deg}"]))
    model = plant.model
    hook = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "hook")
    segs = []
    for g in np.flatnonzero(model.geom_bodyid == hook):
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, model.geom_quat[g])
        half = model.geom_size[g][1] * mat.reshape(3, 3)[:, 2]
        segs.append((model.geom_pos[g] - half, model.geom_pos[g] + half))
    return segs, plant


def _distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of the points ``p`` (N x 3) from the segment a-b [m]."""
    ab = b - a
    t = np.clip((p - a) @ ab / (ab @ ab), 0.0, 1.0)
    return np.linalg.norm(p - a - t[:, None] * ab, axis=1)


def _lowest_bar_positions(rise_deg: float, step: float = 1e-4) -> tuple[np.ndarray, Plant]:
    """Bar axes (in the plane of the first arm, hook frame) inside the crook (above the
    arm, between the shank and the tip) that touch no
    capsule closer than hook_radius + bar_radius and lie lowest (largest x, the hanging
    hook's down), within one grid step [m]."""
    segs, plant = _hook_segments(rise_deg)
    m = plant.scenario.mechanism
    rad = m.hook_radius + m.bar_radius
    u, x = np.meshgrid(np.arange(0.0, m.hook_reach, step),
                       np.arange(m.hook_shank - m.hook_tip_length, m.hook_shank + m.arm_fall,
                                 step))  # fmt: skip
    p = np.column_stack([x.ravel(), u.ravel(), np.zeros(u.size)])
    above = p[:, 0] <= m.hook_shank + p[:, 1] * math.tan(math.radians(rise_deg))  # the arm
    free = above & np.all([_distance(p, a, b) >= rad - 1e-9 for a, b in segs], axis=0)
    p = p[free]
    low = p[p[:, 0] >= p[:, 0].max() - step]
    return low, plant


def test_rising_arms_give_the_crook_one_low_point_where_the_plan_seats_the_bar() -> None:
    low, plant = _lowest_bar_positions(25.0)
    m = plant.scenario.mechanism
    u, z = m.bar_seat
    # derived: the tip stands straight up at hook_reach, so the seat is hook_radius +
    # bar_radius inside it, on the corner's bisector (the corner's angle 90 deg - rise)
    rad = m.hook_radius + m.bar_radius
    assert u == pytest.approx(m.hook_reach - rad, abs=1e-12)
    foot = rad / math.tan(math.radians(0.5 * (90.0 - 25.0)))
    assert z == pytest.approx(-m.arm_fall + foot, abs=1e-12)
    # the plant's lowest free bar position is that one point (to the grid's 0.1 mm)
    seat_hook = np.array([m.hook_shank - z, u, 0.0])
    assert float(np.max(np.linalg.norm(low - seat_hook, axis=1))) < 3e-4
    # the hook's lowest point is the arm-tip corner, arm_fall below the crown
    segs, _ = _hook_segments(25.0)
    lowest = max(max(a[0], b[0]) for a, b in segs)
    assert lowest == pytest.approx(m.hook_shank + m.hook_reach * math.tan(math.radians(25.0)))


def test_flat_arms_have_no_single_low_point() -> None:
    """The flat arm (``hook_arm_rise_deg = 0``, the default before rising arms): the bar
    rests anywhere along it (the pilot's shallow seats, 9.5 mm from the crown, and the
    corner 19 mm out are equally low)."""
    low, plant = _lowest_bar_positions(0.0)
    m = plant.scenario.mechanism
    spread = float(np.ptp(low[:, 1]))
    assert spread > m.hook_reach - 2.0 * (m.hook_radius + m.bar_radius) - 1e-3
    assert m.bar_seat == (0.0, m.hook_radius + m.bar_radius)


def test_line_length_puts_the_bar_axis_a_cable_length_from_the_attachment() -> None:
    """The plan's line plus the eye's distance from the seated bar's axis (the plant's
    hook geometry) is the cable length l; flat arms keep the former formula bit for bit."""
    s = load_scenario("slope50", [*BAR, "mechanism.hook_arm_rise_deg=0"])
    m = s.mechanism
    l_t = s.tether.length
    assert bar_line_length(l_t, m) == l_t - (m.hook_shank - m.hook_radius - m.bar_radius)
    low, plant = _lowest_bar_positions(25.0)
    m = plant.scenario.mechanism
    eye_to_axis = float(np.linalg.norm(low.mean(axis=0)))  # the eye is the hook's origin
    assert bar_line_length(l_t, m) + eye_to_axis == pytest.approx(l_t, abs=2e-4)


def test_rise_beyond_the_tip_is_refused_with_one_line() -> None:
    """The bar seated in the corner touches the arm and the tip (hook_radius + bar_radius)
    / tan((90 deg - rise) / 2) from it: beyond the 20 mm tip above 90 - 2 atan(6/20) =
    56.6 deg."""
    s = load_scenario("slope50", BAR)
    m = s.mechanism
    limit = 90.0 - 2.0 * math.degrees(math.atan((m.hook_radius + m.bar_radius)
                                                / m.hook_tip_length))  # fmt: skip
    assert limit == pytest.approx(56.6, abs=0.05)
    load_scenario("slope50", [*BAR, f"mechanism.hook_arm_rise_deg={limit - 0.3}"])
    with pytest.raises(ConfigError, match="hook_arm_rise_deg") as err:
        load_scenario("slope50", [*BAR, f"mechanism.hook_arm_rise_deg={limit + 0.3}"])
    assert "\n" not in str(err.value).strip()


@pytest.mark.slow
def test_pilot_draw_50_00008_lands_with_rising_arms() -> None:
    """Closed loop, the campaign's way: the pilot's draw 50-00008 (slope50 at 50 deg,
    cable 1.2 m, hook drop 1.0 m, bar; seed 2298760360), which failed condition (4) with
    flat arms (the shallow seat rolled into the arm-tip corner on the surface: slack, then a
    26 N snatch), lands and returns with 25 deg arms; the bar sits in the corner from the
    hand-over through the touchdown (the crown's distance from the bar's axis within 1 mm
    of the seat's, ``MechanismConfig.bar_seat``), and the true tension never drops to zero there.
    About 60 s of CPU."""
    from tetherland.campaign.jobs import draw_run, fly_perturbed

    truth = load_scenario("slope50", ["tether.length=1.2", "tether.hook_drop=1.0", *BAR,
                                      "mechanism.hook_arm_rise_deg=25"])  # fmt: skip
    drawn = draw_run(truth, 2298760360)
    r = fly_perturbed(drawn, "tethered")
    assert r.summary["success"], r.summary["reason"]
    geo = Plant(drawn.plant).layout.geometry
    y = geo.R_WA[:, 1]
    off = np.asarray(r.log["hook_p_W"], float) - geo.p_A
    dist = np.linalg.norm(off - np.outer(off @ y, y), axis=1)
    u, z = truth.mechanism.bar_seat
    seat = math.hypot(u, z)
    phases = {p["name"]: p for p in r.summary["phases"]}
    t = r.log["t"]
    held = (t >= phases["tethered_landing"]["start"]) & (t < phases["touchdown"]["end"])
    assert float(np.max(np.abs(dist[held] - seat))) < 1e-3
    landed = (t >= phases["touchdown"]["start"]) & (t < phases["touchdown"]["end"])
    assert float(np.min(r.log["tension"][landed])) > 1.0

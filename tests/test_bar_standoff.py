"""The bar's standoff against the slope: the highest anchor the rotors hold at the landed
hover, the cable-offset torque included, and the design that lands the bar at 70 deg
(docs/mechanism.md, *The bar on steep slopes*)."""

from __future__ import annotations

import math

import pytest

from tetherland import GRAVITY as g
from tetherland.analysis import VehicleLimits, anchor_height_range, landed_hover_rotor_reason
from tetherland.config import load_scenario
from tetherland.design import DesignLimit, DesignSpace, search_designs
from tetherland.geometry import attachment_height
from tetherland.planning import Planner

PILOT = ("tether.length=1.2", "tether.hook_drop=1.0")  # the README's slope sweep
BAR = ('mechanism.kind="bar"',)


def _highest_anchor(beta: float, a: float, length: float, sc) -> float:
    """The highest anchor of an x-layout quadrotor with the cable a below its centre of
    mass, by hand: at the landed hover (z_B = z_S, heading 0) f_R = m g (cos(beta) + t
    sin(beta)) and f_L d~_B = m g sin(beta) [1, 0, t] with t = tan(gamma), so the offset's
    pitch torque is a m g sin(beta) whatever gamma; shared by the four rotors at d =
    L/sqrt(2) from the pitch axis it takes Delta = a m g sin(beta)/(4 d) off the unloaded
    pair. f_R/4 - Delta >= f_min + margin needs t >= t_min, and h_A = h_att - l sin(gamma)."""
    v = sc.vehicle
    lo, d, w = v.f_min + v.control_margin, v.arm_length / math.sqrt(2.0), v.mass * g
    t_min = (4.0 * lo / w - math.cos(beta) + a * math.sin(beta) / d) / math.sin(beta)
    return v.h_R - a - length * t_min / math.sqrt(1.0 + t_min * t_min)


@pytest.mark.parametrize(("slope_deg", "a"), [(60.0, 0.03), (65.0, 0.03), (70.0, 0.0)])
def test_highest_anchor_is_the_rotor_floor_under_the_offset_torque(slope_deg, a):
    """The analytic bound equals the hand-derived one, and the planner's own feasibility
    check (the landed hover's rotors with the offset torque) flips within 2 mm of it,
    with the bar's standoff as the anchor height."""
    att = f"vehicle.cable_attachment=[0,0,{-a}]"
    sc = load_scenario("slope50", [*PILOT, *BAR, att, f"surface.slope_deg={slope_deg}"])
    beta = math.radians(slope_deg)
    lo, hi = anchor_height_range(beta, attachment_height(sc), 1.2, VehicleLimits.from_scenario(sc))
    assert hi == pytest.approx(_highest_anchor(beta, a, 1.2, sc), abs=1e-12)
    assert lo < 0.0 < hi  # the ceiling and the lower bound do not bind here
    for standoff, feasible in ((hi - 0.002, True), (hi + 0.002, False)):
        bar = load_scenario("slope50", [*PILOT, *BAR, att, f"surface.slope_deg={slope_deg}",
                                        f"mechanism.standoff={standoff}"])  # fmt: skip
        assert bar.anchor.h_A == pytest.approx(standoff, abs=1e-12)
        reason = landed_hover_rotor_reason(bar)
        assert (reason is None) is feasible, reason
        if not feasible:  # no offset: the even split meets the rotor floor there
            assert ("cable-offset torque" if a else "per rotor, below f_min") in reason


def test_no_standoff_or_cable_lands_the_bar_at_70_deg_with_the_3_cm_offset():
    """With the attachment 3 cm below the centre of mass, 70 deg needs t_min > 0 (the
    cable tilted toward the surface): every cable length puts the highest anchor below the
    attachment height h_att = 7 cm, and the bar's hook needs a standoff above pass_offset +
    pass_depth + pass_margin + hook_radius (11.2 cm, the configuration's floor)."""
    sc = load_scenario("slope50", [*PILOT, *BAR, "surface.slope_deg=70"])
    m, h_att = sc.mechanism, attachment_height(sc)
    floor = m.pass_offset + m.pass_depth + m.pass_margin + m.hook_radius
    assert h_att < floor
    limits = VehicleLimits.from_scenario(sc)
    for length in (0.3, 0.6, 1.2, 2.4):
        hi = anchor_height_range(math.radians(70.0), h_att, length, limits)[1]
        assert hi == pytest.approx(_highest_anchor(math.radians(70.0), 0.03, length, sc), abs=1e-12)
        assert hi < h_att
    # the default bar at 70 deg: the planner's check refuses it on the offset torque
    assert "cable-offset torque" in landed_hover_rotor_reason(sc)


def test_design_moves_the_bars_attachment_to_the_centre_of_mass_at_70_deg():
    """`design` keeps the bar's standoff and its straight-down pass: with only the 3 cm
    offset no design exists (the offset torque binds, and the reason names the highest
    anchor, 5.1 cm at l = 1 m, against the 15 cm standoff); allowed the attachment at the
    centre of mass, it chooses it, and the design's scenario is a valid bar the planner's
    check accepts."""
    planner = Planner()
    sc = load_scenario("slope50", list(BAR))
    few = {"lengths": (1.0,), "shortlist": 1, "max_designs": 1}
    r = search_designs(sc, 70.0, DesignSpace(attachment_z=(-0.03,), **few), planner=planner)
    assert not r.feasible and r.limit is DesignLimit.LANDED_HOVER
    assert r.binding == "offset_torque"
    at70 = load_scenario("slope50", [*BAR, "surface.slope_deg=70", "tether.length=1.0"])
    hi = anchor_height_range(
        math.radians(70.0), attachment_height(at70), 1.0, VehicleLimits.from_scenario(at70)
    )[1]
    assert f"z = -0.03 m: {hi:.3f} m" in r.reason and "standoff = 0.15 m" in r.reason

    r = search_designs(sc, 70.0, DesignSpace(attachment_z=(-0.03, 0.0), **few), planner=planner)
    assert r.feasible, r.reason
    point = r.chosen.point
    assert point.attachment[2] == 0.0 and point.h_A == sc.mechanism.standoff
    assert point.approach_A == (0.0, 0.0, -1.0)
    chosen = point.apply(sc)
    assert chosen.mechanism.kind == "bar" and landed_hover_rotor_reason(chosen) is None

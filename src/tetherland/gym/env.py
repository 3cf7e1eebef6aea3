"""The tethered landing and takeoff as Gymnasium environments (one step = one control tick).

Physics, sensors and estimator are the mission's: the MuJoCo :class:`~tetherland.sim.Plant`
at 1 kHz, IMU 1 kHz and mocap 120 Hz (late) through :meth:`tetherland.sim.Runner.steps`,
the :class:`~tetherland.estimation.UkfEstimator` in the loop. An episode starts in the
first state of the planned maneuver with the cable taut (landing: the taut start hover;
takeoff: the landed hover), rotors at the planned thrusts.

Observation (float64, :data:`OBSERVATION`): time, the estimated body state, the estimated
link state and the estimated tension. Action (float32, 4): normalised rotor thrusts
a_i in [0, 1], f_i = f_min + a_i (f_max - f_min) [N], sent as speed commands through the
believed rotor model.

Landing: the episode runs to touchdown (a contact force above ``verdict.touchdown_force``,
as the judge of a mission) and on until the rotors have idled (the action's zero, the
motors-off of the mission) for ``rest_time``; conditions (1)-(4) are judged at touchdown
with the scenario's ``[verdict]`` tolerances and (5) over the rest as the judge does: the
slip over the whole idle interval, the speed from ``verdict.rest_settle_time`` after idling.
The rest ends early if the rotors are driven again. The final
reward is the number of conditions held plus ``success_bonus`` when all five hold.
Takeoff: the episode ends ``rest_time`` after the planned end; success when the link
elevation and the tilt are within ``takeoff_tolerance`` of the planned taut end hover.
A contact above ``verdict.crash_force`` on any part but the landers, at any physics
step (crash), or a slack cable (true tension
below ``SLACK_TENSION`` for ``mission.detection.slack_dwell`` while airborne) ends the
episode with ``-failure_penalty``;
each step costs ``dt`` x the distance to the goal [m s]. Episodes are truncated at
``time_limit`` (default: the plan's duration + ``rest_time`` + 3 s).

Each reset draws the episode's seed from the env's RNG (``info["seed"]``); the episode's
sensor noise and perturbation come from that seed's named streams
(:mod:`tetherland.randomness`). ``randomize=True`` draws the campaign perturbations
(:mod:`tetherland.campaign.perturb`) at each reset: the plant keeps the scenario as the
truth (with the drawn sensor-noise scale and mocap dropouts), the estimator believes the
perturbed vehicle, surface and anchor (``env.belief``, what an agent or the expert may plan
on). Wind gusts are not applied.

``info`` holds what an agent may know: ``t``, ``seed``, ``outcome``, the landing
``conditions`` when judged (the episode's result, as the reward) and a ``message`` when the
physics diverged. The truth (:data:`PRIVILEGED_INFO`: the true ``tension``, the drawn
``perturbation``, the judge's ``measures``, the true touchdown ``t_L`` and the start of
the judged rest ``t_rest``) is added only for an env made with ``privileged=True``: for
debugging, or for the critic of an asymmetric actor-critic, never for a policy that is
meant to fly a real robot.
"""

from __future__ import annotations

import math
from collections import deque
from enum import StrEnum
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from tetherland.analysis.conditions import evaluate_landing
from tetherland.campaign.perturb import apply_perturbation, sample_perturbation
from tetherland.config import Scenario, load_scenario, with_overrides
from tetherland.errors import ConfigError
from tetherland.estimation import UkfEstimator
from tetherland.geometry import (
    FloatArray,
    LandingGeometry,
    link_angles,
    theta_A_from_z_B,
)
from tetherland.interfaces import Command, StateEstimate
from tetherland.models.quadrotor import RotorModel
from tetherland.planning import Planner
from tetherland.planning.maneuver import Maneuver
from tetherland.planning.start import plan_start_state
from tetherland.planning.trajectory import Trajectory
from tetherland.randomness import RandomSource
from tetherland.rotations import quat_to_rotmat
from tetherland.sim import Plant, Runner
from tetherland.sim.baselines import ConstantSpeedController
from tetherland.state import LinkState, RigidBodyState
from tetherland.verdict import tolerances_of

OBSERVATION = (
    "t", "p_x", "p_y", "p_z", "v_x", "v_y", "v_z", "q_w", "q_x", "q_y", "q_z",
    "omega_x", "omega_y", "omega_z", "phi", "delta", "phi_dot", "delta_dot", "tension",
)  # fmt: skip
"""Observation entries: time [s], estimated p_W [m], v_W [m/s], q_WB (w, x, y, z),
omega_B [rad/s], link phi, delta [rad] and rates [rad/s], cable tension [N]."""
OBSERVATION_BOUND = np.array(
    [1e3] + [1e2] * 3 + [1e2] * 3 + [1.0] * 4 + [1e2] * 3 + [np.pi] * 2 + [1e2] * 2 + [1e3]
)
"""Bounds of the observation space (far beyond any flight; |q| = 1; angles wrap at pi)."""
SLACK_TENSION = 0.05
"""True tension below which the cable counts as slack [N]."""
PRIVILEGED_INFO = ("tension", "perturbation", "measures", "t_L", "t_rest")
"""``info`` entries that carry the plant's truth: only with ``privileged=True``."""


class Outcome(StrEnum):
    """How an episode ended (``info["outcome"]``)."""

    RUNNING = "running"
    LANDED = "landed"
    """Touchdown and rest with all of conditions (1)-(5)."""
    LANDED_OUTSIDE_CONDITIONS = "landed_outside_conditions"
    """Touchdown and rest, some condition missed (``info["conditions"]``)."""
    REACHED = "reached"
    """Takeoff: at the taut end hover within the tolerance."""
    MISSED = "missed"
    """Takeoff: the end hover was not reached within the tolerance."""
    CRASHED = "crashed"
    SLACK = "slack"
    DIVERGED = "diverged"
    TIME_LIMIT = "time_limit"


def estimate_of(observation: FloatArray) -> StateEstimate:
    """The :class:`StateEstimate` an observation encodes (for controllers and policies)."""
    o = np.asarray(observation, dtype=float)
    return StateEstimate(
        t=float(o[0]),
        body=RigidBodyState(o[1:4].copy(), o[4:7].copy(), o[7:11].copy(), o[11:14].copy()),
        link=LinkState(float(o[14]), float(o[15]), float(o[16]), float(o[17])),
        tension=float(o[18]),
    )


def _observe(est: StateEstimate) -> FloatArray:
    b = est.body
    link = est.link.as_array() if est.link is not None else np.zeros(4)
    tension = est.tension if est.tension is not None else 0.0
    return np.concatenate(([est.t], b.p_W, b.v_W, b.q_WB, b.omega_B, link, [tension]))


def initial_state(plan: Trajectory, scenario: Scenario) -> tuple[RigidBodyState, FloatArray]:
    """The plan's first state (cable taut at the plan's start tension) and rotor speeds
    [rad/s]: :func:`tetherland.planning.start.plan_start_state`."""
    return plan_start_state(plan, scenario)


class TetheredEnv(gymnasium.Env):
    """Tethered landing or takeoff of one scenario (see the module docstring).

    Parameters
    ----------
    scenario : str or Scenario
        Built-in name, TOML path or a scenario object (the truth the plant simulates).
    maneuver : str
        ``"landing"`` or ``"takeoff"``.
    overrides : sequence of str
        ``section.key=value`` scenario overrides.
    randomize : bool
        Draw the campaign perturbations at each reset.
    rest_time : float
        Landing: the rest with idle rotors judged for condition (5) (> verdict.rest_settle_time);
        takeoff: time after the planned end [s], in (0, 10].
    time_limit : float, optional
        Truncation time [s] (default: plan duration + rest_time + 3 s), in (0, 600].
    takeoff_tolerance_deg : float
        Takeoff success: |phi - phi_end| and |theta_A - theta_A_end| below this [deg].
    success_bonus, failure_penalty : float
        Reward terms [-].
    planner : Planner, optional
        Reuse compiled solvers (kept as :attr:`planner`, the expert's too).
    privileged : bool
        Add the truth to ``info`` (:data:`PRIVILEGED_INFO`): debugging, asymmetric
        actor-critic.

    Attributes
    ----------
    scenario : Scenario
        The truth the plant simulates.
    belief : Scenario
        What the robot believes this episode (the scenario itself unless ``randomize``).
    """

    metadata: dict[str, Any] = {"render_modes": []}  # noqa: RUF012 (gymnasium's convention)

    def __init__(
        self,
        scenario: str | Scenario = "slope50",
        maneuver: str = "landing",
        *,
        overrides: tuple[str, ...] | list[str] = (),
        randomize: bool = False,
        rest_time: float = 1.0,
        time_limit: float | None = None,
        takeoff_tolerance_deg: float = 3.0,
        success_bonus: float = 5.0,
        failure_penalty: float = 10.0,
        planner: Planner | None = None,
        privileged: bool = False,
    ) -> None:
        super().__init__()
        if isinstance(scenario, Scenario):
            sc = with_overrides(scenario, list(overrides))
        else:
            sc = load_scenario(scenario, list(overrides))
        try:
            self.maneuver = Maneuver(maneuver)
        except ValueError:
            raise ConfigError(f"maneuver must be landing or takeoff (got {maneuver!r})") from None
        if not 0 < rest_time <= 10:
            raise ConfigError(f"rest_time must be in (0, 10] s (got {rest_time})")
        self._rest_settle = sc.verdict.rest_settle_time
        if self.maneuver is Maneuver.LANDING and rest_time <= self._rest_settle:
            raise ConfigError(
                f"rest_time must exceed verdict.rest_settle_time = {self._rest_settle:g} s for a "
                f"landing (got {rest_time})"
            )
        if time_limit is not None and not 0 < time_limit <= 600:
            raise ConfigError(f"time_limit must be in (0, 600] s (got {time_limit})")
        if not 0 < takeoff_tolerance_deg <= 45:
            raise ConfigError(
                f"takeoff_tolerance_deg must be in (0, 45] (got {takeoff_tolerance_deg})"
            )
        self.scenario = sc
        self.belief = sc
        self.randomize = bool(randomize)
        self.privileged = bool(privileged)
        self.rest_time = float(rest_time)
        self.tolerance = tolerances_of(sc)
        self.takeoff_tolerance = math.radians(takeoff_tolerance_deg)
        self.success_bonus, self.failure_penalty = float(success_bonus), float(failure_penalty)
        self.planner = planner or Planner()
        result = self.planner.plan(sc, self.maneuver)
        if result.trajectory is None or result.status.value != "solved":
            raise ConfigError(f"no {self.maneuver.value} plan for '{sc.name}': {result.message}")
        self.plan: Trajectory = result.require()
        self.time_limit = float(time_limit or self.plan.duration + self.rest_time + 4.0)
        self.geometry = LandingGeometry.from_scenario(sc)
        self.dt = 1.0 / sc.controller.rate_hz
        self._x0, self._w0 = initial_state(self.plan, sc)
        end = self.plan.final_output
        self._phi_end, self._theta_end = float(end[0]), float(end[2])
        self._att_end = self.geometry.link_end(self._phi_end, 0.0)
        self._plant = Plant(sc)
        v = sc.vehicle
        self._f_min, self._f_max = v.f_min, v.f_max
        self.observation_space = spaces.Box(-OBSERVATION_BOUND, OBSERVATION_BOUND, dtype=np.float64)
        self.action_space = spaces.Box(0.0, 1.0, (4,), np.float32)
        self._loop: Any = None
        self._rotors = RotorModel.from_config(v)

    def planned_action(self) -> FloatArray:
        """The action of the plan's initial rotor thrusts (the taut start hover) [-]."""
        f = RotorModel.from_config(self.scenario.vehicle).thrust(self._w0)
        return ((f - self._f_min) / (self._f_max - self._f_min)).astype(np.float32)

    # ------------------------------------------------------------------ gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[FloatArray, dict[str, Any]]:
        super().reset(seed=seed)
        # one random source per episode, its seed drawn from the environment's generator
        random = RandomSource(int(self.np_random.integers(2**63)))
        plant_sc, belief, perturbation = self.scenario, self.scenario, None
        if self.randomize:
            perturbation = sample_perturbation(self.scenario, random, horizon=self.time_limit)
            plant_sc, belief = apply_perturbation(self.scenario, perturbation)
        if self._plant.scenario != plant_sc:
            self._plant = Plant(plant_sc)
        self._rotors = RotorModel.from_config(belief.vehicle)
        self.belief = belief
        estimator = UkfEstimator(belief, self._x0, 0.0, rotor_speeds0=self._w0)
        runner = Runner(plant_sc, ConstantSpeedController.motors_off(), estimator=estimator,
                        plant=self._plant)  # fmt: skip
        if self._loop is not None:
            self._loop.close()
        self._loop = runner.steps(
            self.time_limit + 2 * self.dt, initial_state=self._x0, rotor_speeds=self._w0,
            cable_engaged=True, random=random,
        )  # fmt: skip
        tick = next(self._loop)
        self._history: deque[tuple[FloatArray, FloatArray]] = deque(maxlen=3)
        self._touchdown: dict[str, Any] | None = None
        self._rest_p: list[FloatArray] = []
        self._rest_v: list[FloatArray] = []
        self._slack_since: float | None = None
        self._idle_since: float | None = None
        self._done = False
        self._record_truth()
        info = {"t": tick.t, "outcome": Outcome.RUNNING.value, "seed": random.seed,
                "perturbation": perturbation.to_dict() if perturbation else {}}  # fmt: skip
        return _observe(tick.estimate), self._shown(info)

    def step(self, action: FloatArray) -> tuple[FloatArray, float, bool, bool, dict[str, Any]]:
        if self._loop is None or self._done:
            raise RuntimeError("call reset() before step() (the episode is over)")
        a = np.clip(np.asarray(action, dtype=float).reshape(4), 0.0, 1.0)
        f = self._f_min + a * (self._f_max - self._f_min)
        command = Command(rotor_speeds=self._rotors.speed(f), thrust=float(f.sum()))
        try:
            tick = self._loop.send(command)
        except StopIteration as stop:
            self._done = True
            log = stop.value
            status = log.metadata.get("status")
            outcome = Outcome.TIME_LIMIT if status == "completed" else Outcome.DIVERGED
            t = float(log["t"][-1]) if len(log) else 0.0
            obs = np.zeros(len(OBSERVATION))
            obs[0] = t
            penalty = 0.0 if outcome is Outcome.TIME_LIMIT else -self.failure_penalty
            info = {"t": t, "outcome": outcome.value, "message": log.metadata.get("message", "")}
            return (obs, penalty, outcome is Outcome.DIVERGED, outcome is Outcome.TIME_LIMIT,
                    self._shown(info))  # fmt: skip
        reward, outcome, info = self._judge(tick.t, not a.any())
        terminated = outcome not in (Outcome.RUNNING, Outcome.TIME_LIMIT)
        truncated = outcome is Outcome.TIME_LIMIT
        self._done = terminated or truncated
        info.update(t=tick.t, outcome=outcome.value)
        return _observe(tick.estimate), reward, terminated, truncated, self._shown(info)

    def _shown(self, info: dict[str, Any]) -> dict[str, Any]:
        """``info`` as the env shows it: without the truth unless privileged."""
        if self.privileged:
            return info
        return {k: v for k, v in info.items() if k not in PRIVILEGED_INFO}

    def close(self) -> None:
        if self._loop is not None:
            self._loop.close()
            self._loop = None

    # ------------------------------------------------------------------ judging
    def _record_truth(self) -> tuple[FloatArray, FloatArray]:
        plant = self._plant
        v, w = plant.qvel[0:3].copy(), plant.qvel[3:6].copy()
        self._history.append((v, w))
        return v, w

    def _judge(self, t: float, idle: bool) -> tuple[float, Outcome, dict[str, Any]]:
        plant, geo = self._plant, self.geometry
        v_W, _ = self._record_truth()
        p_W, q_WB = plant.qpos[0:3], plant.qpos[3:7]
        R_WB = quat_to_rotmat(q_WB)
        z_B = R_WB[:, 2]
        p_RL = p_W - geo.h_R * z_B
        info: dict[str, Any] = {"tension": plant.tension}
        cfg = self.scenario.verdict
        frame = plant.frame_contact_peak  # every physics step since the last tick
        if frame > cfg.crash_force:
            return -self.failure_penalty, Outcome.CRASHED, info
        force = max(float(plant.lander_forces.max()), frame)
        airborne = force <= cfg.touchdown_force
        if self._slack(t, plant.tension, airborne):
            return -self.failure_penalty, Outcome.SLACK, info
        if self.maneuver is Maneuver.LANDING:
            cost = self.dt * float(np.linalg.norm(p_RL - geo.p_L))
            reward, outcome = self._landing(t, p_RL, z_B, v_W, airborne, idle, info)
            return reward - cost, outcome, info
        p_att = p_W + R_WB @ np.asarray(self.scenario.vehicle.cable_attachment, dtype=float)
        cost = self.dt * float(np.linalg.norm(p_att - self._att_end))
        reward, outcome = self._takeoff(t, p_W, R_WB, info)
        return reward - cost, outcome, info

    def _slack(self, t: float, tension: float, airborne: bool) -> bool:
        """Slack cable while airborne for longer than the mission's fault time."""
        if tension >= SLACK_TENSION or not airborne or self._touchdown is not None:
            self._slack_since = None
            return False
        if self._slack_since is None:
            self._slack_since = t
        return t - self._slack_since > self.scenario.mission.detection.slack_dwell

    def _landing(self, t, p_RL, z_B, v_W, airborne, idle, info) -> tuple[float, Outcome]:
        geo = self.geometry
        if self._touchdown is None:
            if airborne:
                return (0.0, Outcome.TIME_LIMIT if t >= self.time_limit else Outcome.RUNNING)
            # touchdown: the state now, and t_L- (the tick before) from the history
            hist = list(self._history)
            v1, w1 = hist[-2] if len(hist) >= 2 else hist[-1]
            v2, w2 = hist[-3] if len(hist) >= 3 else (v1, w1)
            self._touchdown = {
                "t": t, "p_RL": p_RL.copy(), "z_B": z_B.copy(), "v_W": v1, "omega_B": w1,
                "a_W": (v1 - v2) / self.dt, "omega_dot_B": (w1 - w2) / self.dt,
            }  # fmt: skip
        td = self._touchdown
        info["t_L"] = td["t"]
        running = Outcome.TIME_LIMIT if t >= self.time_limit else Outcome.RUNNING
        if self._idle_since is None:
            if not idle:
                return 0.0, running
            self._idle_since = t
        rest_over = not idle or t >= self._idle_since + self.rest_time
        if idle:
            self._rest_p.append(p_RL.copy())
            if t >= self._idle_since + self._rest_settle:
                self._rest_v.append(v_W.copy())
        info["t_rest"] = self._idle_since
        if not rest_over:
            return 0.0, running
        rest_v = np.array(self._rest_v) if self._rest_v else np.full((1, 3), np.inf)
        verdict = evaluate_landing(
            p_RL=td["p_RL"], z_B=td["z_B"], v_W=td["v_W"], omega_B=td["omega_B"],
            a_W=td["a_W"], omega_dot_B=td["omega_dot_B"], p_L_star=geo.p_L, z_S=geo.surface.z_S,
            rest_p_RL=np.array(self._rest_p), rest_v_W=rest_v, tol=self.tolerance,
        )  # fmt: skip
        info["conditions"] = verdict.to_dict()
        info["measures"] = {m.name: m.value for c in verdict.conditions for m in c.measures}
        held = sum(c.holds for c in verdict.conditions)
        if verdict.all_hold:
            return held + self.success_bonus, Outcome.LANDED
        return float(held), Outcome.LANDED_OUTSIDE_CONDITIONS

    def _takeoff(self, t, p_W, R_WB, info) -> tuple[float, Outcome]:
        if t < self.plan.duration + self.rest_time:
            return 0.0, (Outcome.TIME_LIMIT if t >= self.time_limit else Outcome.RUNNING)
        geo = self.geometry
        r_att = np.asarray(self.scenario.vehicle.cable_attachment, dtype=float)
        d_A = geo.R_WA.T @ (p_W + R_WB @ r_att - geo.p_A)
        phi, delta = link_angles(d_A)
        theta = theta_A_from_z_B(geo.R_WA.T @ R_WB[:, 2], phi, delta)
        errors = {"phi_error_rad": abs(phi - self._phi_end),
                  "theta_A_error_rad": abs(theta - self._theta_end)}  # fmt: skip
        info["measures"] = errors
        if max(errors.values()) <= self.takeoff_tolerance:
            return self.success_bonus, Outcome.REACHED
        return 0.0, Outcome.MISSED

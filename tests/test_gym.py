"""The Gymnasium environments (issue 16, item 3)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tetherland.gym as tg
from tetherland.config import with_overrides
from tetherland.errors import ConfigError
from tetherland.gym.env import OBSERVATION, PRIVILEGED_INFO, Outcome, TetheredEnv, estimate_of


@pytest.fixture(scope="module")
def env():
    e = gym.make(tg.LANDING_ID, privileged=True)  # the tests read the truth in info
    yield e
    e.close()


def hover_action(env) -> np.ndarray:
    """The planned initial rotor thrusts as an action (normalised)."""
    a = env.unwrapped.planned_action()
    v = env.unwrapped.scenario.vehicle
    f = v.f_min + a * (v.f_max - v.f_min)
    assert f.sum() > 0.5 * v.mass * 9.81  # the taut hover carries most of the weight
    return a


def test_registered_spaces_and_check_env(env):
    assert {tg.LANDING_ID, tg.TAKEOFF_ID} <= set(gym.registry)
    assert env.observation_space.shape == (len(OBSERVATION),)
    assert env.action_space.shape == (4,)
    assert env.action_space.low.min() == 0.0 and env.action_space.high.max() == 1.0
    check_env(env.unwrapped, skip_render_check=True)


def test_reset_is_the_taut_start_of_the_plan_and_seeded(env):
    e = env.unwrapped
    obs, info = env.reset(seed=7)
    assert info["outcome"] == Outcome.RUNNING
    # the observation is the UKF estimate at t = 0: the plan's first state, cable taut
    est = estimate_of(obs)
    assert est.t == 0.0
    np.testing.assert_allclose(est.body.p_W, e._x0.p_W, atol=0.02)
    assert est.link.phi == pytest.approx(float(e.plan.initial_output[0]), abs=np.radians(1.0))
    assert e._plant.tension > 0.5 * e.scenario.planner.start_tension
    # same seed, same actions: the same trajectory; another seed: other sensor noise
    a = hover_action(env)

    def rollout(seed):
        env.reset(seed=seed)
        return np.array([env.step(a)[0] for _ in range(40)])

    first, again, other = rollout(3), rollout(3), rollout(4)
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    # one step is one control tick of the mission's loop
    np.testing.assert_allclose(np.diff(first[:, 0]), 1.0 / e.scenario.controller.rate_hz)


def test_two_vectorised_envs_step_together_as_they_would_alone():
    """SyncVectorEnv and AsyncVectorEnv (subprocesses) of 2 envs: every sub-env follows
    the same trajectory as a single env with its seed and actions."""
    single = gym.make(tg.LANDING_ID)
    a = hover_action(single)
    actions = np.stack([a, np.clip(a + 0.02, 0, 1)])
    expected = []
    for i, seed in enumerate((11, 12)):
        single.reset(seed=seed)
        expected.append(np.array([single.step(actions[i])[0] for _ in range(25)]))
    single.close()
    for vector in (gym.vector.SyncVectorEnv, gym.vector.AsyncVectorEnv):
        venv = vector([lambda: gym.make(tg.LANDING_ID)] * 2)
        try:
            obs, _ = venv.reset(seed=[11, 12])
            assert obs.shape == (2, len(OBSERVATION))
            got = np.array([venv.step(actions)[0] for _ in range(25)])
        finally:
            venv.close()
        for i in range(2):
            np.testing.assert_allclose(got[:, i], expected[i], rtol=0, atol=1e-12,
                                       err_msg=vector.__name__)  # fmt: skip


def fly_expert(env, seed):
    expert = tg.ExpertPolicy.for_env(env)
    obs, _ = env.reset(seed=seed)
    expert.reset()
    while True:
        obs, _, terminated, truncated, info = env.step(expert(obs))
        if terminated or truncated:
            return info


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(5))
def test_the_expert_lands_with_conditions_1_to_5(env, seed):
    expert = tg.ExpertPolicy.for_env(env)
    obs, _ = env.reset(seed=seed)
    expert.reset()
    total, steps = 0.0, 0
    while True:
        obs, reward, terminated, truncated, info = env.step(expert(obs))
        total, steps = total + reward, steps + 1
        if terminated or truncated:
            break
    assert info["outcome"] == Outcome.LANDED, info
    assert terminated and not truncated
    assert info["conditions"] == {str(i): True for i in range(1, 6)}
    e = env.unwrapped
    # touchdown near the end of the plan; the rotors idle after the mission's settle time
    # (the motors-off) and the episode ends rest_time later
    assert abs(info["t_L"] - e.plan.duration) < 0.5
    assert info["t_rest"] - info["t_L"] >= e.scenario.mission.settle_time
    assert info["t"] == pytest.approx(info["t_rest"] + e.rest_time, abs=2e-3)
    assert total > 5 + e.success_bonus - 1.0  # the final reward minus a small path cost


@pytest.mark.slow
def test_the_expert_takes_off_to_the_end_hover():
    env = gym.make(tg.TAKEOFF_ID, privileged=True)
    expert = tg.ExpertPolicy.for_env(env)
    obs, _ = env.reset(seed=0)
    expert.reset()
    while True:
        obs, _, terminated, truncated, info = env.step(expert(obs))
        if terminated or truncated:
            break
    assert info["outcome"] == Outcome.REACHED
    assert max(info["measures"].values()) < np.radians(1.0)
    env.close()


def test_idle_rotors_fail_with_a_slack_cable_or_a_crash(env):
    """At f_min on all rotors the vehicle falls: the episode fails, it does not hang."""
    env.reset(seed=0)
    for _ in range(2000):
        _, reward, terminated, truncated, info = env.step(np.zeros(4, np.float32))
        if terminated or truncated:
            break
    assert terminated and info["outcome"] in (Outcome.SLACK, Outcome.CRASHED,
                                              Outcome.LANDED_OUTSIDE_CONDITIONS)  # fmt: skip
    if info["outcome"] != Outcome.LANDED_OUTSIDE_CONDITIONS:
        assert reward < -env.unwrapped.failure_penalty + 1


@pytest.mark.slow
def test_the_expert_lands_under_the_campaign_perturbations():
    """The estimator believes a perturbed vehicle, surface and anchor; the expert still
    meets (1)-(5) (touchdown before the planned end, found by the guarded rule)."""
    env = gym.make(tg.LANDING_ID, randomize=True, privileged=True)
    info = fly_expert(env, 1)
    assert info["outcome"] == Outcome.LANDED, info
    assert info["t_L"] < env.unwrapped.plan.duration  # the surface was not where believed
    env.close()


def test_randomised_perturbations_come_from_the_seed():
    env = TetheredEnv("slope50", randomize=True, privileged=True)
    _, a = env.reset(seed=5)
    _, b = env.reset(seed=5)
    _, c = env.reset(seed=6)
    assert a["perturbation"] == b["perturbation"] != c["perturbation"]
    assert a["perturbation"]["mass_factor"] != 1.0
    assert env.belief.vehicle.mass == pytest.approx(
        env.scenario.vehicle.mass * a["perturbation"]["mass_factor"]
    ) or env.belief.vehicle.mass == pytest.approx(
        env.scenario.vehicle.mass * c["perturbation"]["mass_factor"]
    )
    env.close()


def test_info_has_no_truth_unless_privileged():
    """An agent's info: time, outcome, the judged conditions; the true tension and the
    drawn perturbation only for a privileged env (debugging, asymmetric actor-critic)."""
    public = TetheredEnv("slope50", randomize=True)
    privileged = TetheredEnv("slope50", randomize=True, privileged=True,
                             planner=public.planner)  # fmt: skip
    a = public.planned_action()
    for env in (public, privileged):
        _, info = env.reset(seed=5)
        infos = [info] + [env.step(a)[4] for _ in range(5)]
        env.close()
        keys = set().union(*infos)
        if env is public:
            assert keys == {"t", "seed", "outcome"}
            assert not keys & set(PRIVILEGED_INFO)
        else:
            assert keys == {"t", "seed", "outcome", "tension", "perturbation"}
            assert infos[0]["perturbation"]["mass_factor"] != 1.0
            assert infos[-1]["tension"] == privileged._plant.tension > 0.0
    # the landing's end: conditions are public, the judge's measures and times are not
    shown = public._shown({"t": 1.0, "outcome": "landed", "conditions": {"1": True},
                           "measures": {"speed": 0.01}, "t_L": 0.5, "t_rest": 0.6,
                           "tension": 2.0})  # fmt: skip
    assert shown == {"t": 1.0, "outcome": "landed", "conditions": {"1": True}}


def test_the_expert_plans_on_the_belief_not_the_truth():
    """Changing only the truth of a perturbed env leaves the expert's plan and actions
    unchanged; an expert given the truth would have planned otherwise. At the next reset
    the expert takes up the newly drawn belief."""
    env = TetheredEnv("slope50", randomize=True)
    obs, _ = env.reset(seed=2)
    assert env.belief != env.scenario
    expert = tg.ExpertPolicy.for_env(env)
    expert.reset()
    assert expert.scenario == env.belief
    plan, action = expert.plan.to_csv(), expert(obs)
    env.scenario = with_overrides(env.scenario, ["surface.slope_deg=55", "vehicle.mass=1.1"])
    other = tg.ExpertPolicy.for_env(env)
    other.reset()
    assert other.plan.to_csv() == plan
    np.testing.assert_array_equal(other(obs), action)
    on_truth = tg.ExpertPolicy(env.scenario, planner=env.planner)
    assert on_truth.plan.to_csv() != plan  # the test would see an expert reading the truth
    assert tg.ExpertPolicy(env.belief, planner=env.planner).plan.to_csv() == plan
    env.reset(seed=3)  # another draw: the expert re-plans on it
    expert.reset()
    assert expert.scenario == env.belief and expert.plan.to_csv() != plan
    env.close()


def test_bad_settings_are_rejected():
    with pytest.raises(ConfigError, match="maneuver"):
        TetheredEnv("slope50", "hover")
    with pytest.raises(ConfigError, match="rest_time"):
        TetheredEnv("slope50", rest_time=0.2)
    with pytest.raises(ConfigError, match="time_limit"):
        TetheredEnv("slope50", time_limit=-1.0)

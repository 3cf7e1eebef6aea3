"""Steps per second of the Gymnasium environment (issue 16, item 3).

One step is one 500 Hz control tick: 2 MuJoCo steps, 2 IMU samples, the UKF, mocap when
due. Prints the steps/s of one env under a constant action and under the expert policy,
and of 2 envs in a SyncVectorEnv and an AsyncVectorEnv (2 processes), over whole landing
episodes (the same seeds each time).
Run: .venv/bin/python benchmarks/bench_gym.py [steps]
"""

from __future__ import annotations

import sys
import time

import gymnasium as gym
import numpy as np

import tetherland.gym as tg


def single(steps: int) -> None:
    env = gym.make(tg.LANDING_ID)
    hover = env.unwrapped.planned_action()
    expert = tg.ExpertPolicy.for_env(env)
    for label, policy in (("constant action", lambda obs: hover), ("expert policy", expert)):
        n, seed = 0, 0
        obs, _ = env.reset(seed=seed)
        expert.reset()
        t0 = time.perf_counter()
        while n < steps:
            obs, _, terminated, truncated, _ = env.step(policy(obs))
            n += 1
            if terminated or truncated:
                seed += 1
                obs, _ = env.reset(seed=seed)
                expert.reset()
        wall = time.perf_counter() - t0
        print(f"1 env, {label}: {n / wall:,.0f} steps/s ({n / wall / 500:.1f}x real time)")
    env.close()


def vectorised(steps: int) -> None:
    hover = gym.make(tg.LANDING_ID).unwrapped.planned_action()
    for vector in (gym.vector.SyncVectorEnv, gym.vector.AsyncVectorEnv):
        venv = vector([lambda: gym.make(tg.LANDING_ID)] * 2)
        venv.reset(seed=[0, 1])
        action = np.stack([hover, hover])
        t0 = time.perf_counter()
        for _ in range(steps // 2):
            venv.step(action)  # sub-envs that end are reset automatically
        wall = time.perf_counter() - t0
        print(f"2 envs, {vector.__name__}: {steps / wall:,.0f} env steps/s in total")
        venv.close()


def main() -> None:
    steps = int(sys.argv[1]) if len(sys.argv) > 1 else 6000
    single(steps)
    vectorised(steps)


if __name__ == "__main__":
    main()

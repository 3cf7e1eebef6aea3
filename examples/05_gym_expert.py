"""The Gymnasium environment, flown by the shipped expert (OCP plan + Gamma_HC^b)."""

import gymnasium as gym

import tetherland.gym  # registers tetherland/TetheredLanding-v0 and -Takeoff-v0

env = gym.make("tetherland/TetheredLanding-v0", scenario="slope50")
expert = tetherland.gym.ExpertPolicy.for_env(env)
obs, info = env.reset(seed=0)
expert.reset()
total = 0.0
while True:
    obs, reward, terminated, truncated, info = env.step(expert(obs))  # 4 thrusts in [0, 1]
    total += reward
    if terminated or truncated:
        break
print(info["outcome"], info["conditions"], f"return {total:.2f}")
assert all(info["conditions"].values())
env.close()

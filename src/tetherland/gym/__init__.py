"""Gymnasium environments of the tethered landing and takeoff (needs the ``gym`` extra).

``import tetherland.gym`` registers

- ``tetherland/TetheredLanding-v0``: from the taut start hover of the planned landing to
  touchdown and rest; reward and termination by landing conditions (1)-(5);
- ``tetherland/TetheredTakeoff-v0``: from the landed hover to the taut end hover.

Both run the mission's physics (MuJoCo plant at 1 kHz, IMU and mocap, UKF in the loop);
one step is one 500 Hz control tick. :class:`ExpertPolicy` (the OCP plan and the
hierarchical controller, on the env's belief) maps observations to actions, for learning
from demonstration; ``info`` carries the truth only with ``privileged=True``::

    import gymnasium as gym
    import tetherland.gym
    env = gym.make("tetherland/TetheredLanding-v0", scenario="slope50")
    expert = tetherland.gym.ExpertPolicy.for_env(env)
    obs, info = env.reset(seed=0)
    expert.reset()
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(expert(obs))
        done = terminated or truncated
    print(info["outcome"], info["conditions"])
"""

from __future__ import annotations

from tetherland.optional import require

gymnasium = require("gymnasium", package="gymnasium", extra="gym", feature="tetherland.gym")

from tetherland.gym.env import Outcome, TetheredEnv  # noqa: E402
from tetherland.gym.expert import ExpertPolicy  # noqa: E402

LANDING_ID = "tetherland/TetheredLanding-v0"
TAKEOFF_ID = "tetherland/TetheredTakeoff-v0"

for _id, _maneuver in ((LANDING_ID, "landing"), (TAKEOFF_ID, "takeoff")):
    if _id not in gymnasium.registry:
        gymnasium.register(
            id=_id, entry_point="tetherland.gym.env:TetheredEnv", kwargs={"maneuver": _maneuver}
        )

__all__ = ["LANDING_ID", "TAKEOFF_ID", "ExpertPolicy", "Outcome", "TetheredEnv"]

"""Residual RL on a DMP: plain SB3 SAC on the step-based wiping env (``rdmp_gym/ArmarWipeStep-v1``: ArmarWipe-v1's
scene, cup, controller and reward, one control step per ``step``; the action is a bounded coupling term).

    MUJOCO_GL=egl python examples/step_env_sac.py      # writes runs/examples/step_sac.zip
"""

import gymnasium as gym
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from stable_baselines3 import SAC

env = gym.make("rdmp_gym/ArmarWipeStep-v1", n_periods=2)
model = SAC("MlpPolicy", env, learning_starts=500, device="cpu", seed=0).learn(total_timesteps=2_000)
model.save("runs/examples/step_sac")
print("returns of the last episodes:", [round(e["r"], 3) for e in list(model.ep_info_buffer)[-3:]])

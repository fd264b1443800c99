"""stable-baselines3 SAC and PPO on a task's cycle-level face: the step-based baselines of the cycle-by-cycle search.

One env step is one cycle (:mod:`rdmp_gym.envs.cycle_env`); the episode's reward comes at its last step. The
policy starts at the imitation: its mean action is 0 before learning (the output layer's weights scaled by 0.01 and
its bias 0) and its exploration standard deviation is ``sigma`` (PPO's ``log_std_init``; SAC's set as the one-step
SAC agent sets it, :func:`~rdmp_gym.agents.sb3.start_sac_actor`); SAC acts with its policy from the first step
(no uniform random warm-up, which would leave the imitation). Validation and test are as for
:func:`~rdmp_gym.agents.cycle_training.train_cycle_search` (the deterministic policy on the same contexts), so their
runs compare seed by seed.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from rdmp_gym.envs.registration import cycle_id
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.callbacks import BaseCallback

from .cycle_training import CycleRun, cycle_episode, cycle_scores, failure_counts
from .protocol import final_test_seeds, stratified_validation_seeds
from .sb3 import start_sac_actor

__all__ = ["train_cycle_sb3"]


def _model(algorithm: str, env: gym.Env, seed: int, sigma: float, episode_steps: int, rollouts: int) -> Any:
    """SAC or PPO on ``env`` with the policy at the imitation (see the module docstring)."""
    kwargs = {"seed": seed, "verbose": 0, "device": "cpu"}
    if algorithm == "sac":
        model = SAC("MlpPolicy", env, learning_starts=0, batch_size=64, buffer_size=100_000, **kwargs)
        start_sac_actor(model, np.zeros(env.action_space.shape), sigma)
        return model
    if algorithm != "ppo":
        raise ValueError(f"algorithm: expected 'sac' or 'ppo', got {algorithm!r}")
    model = PPO("MlpPolicy", env, n_steps=episode_steps * rollouts, batch_size=episode_steps * rollouts // 2,
                n_epochs=10, ent_coef=0.0, target_kl=0.05, policy_kwargs={"log_std_init": float(np.log(sigma))},
                **kwargs)
    with torch.no_grad():
        model.policy.action_net.weight.mul_(0.01)
        model.policy.action_net.bias.zero_()
    return model


class _Evaluation(BaseCallback):
    """Every ``every`` episodes: the deterministic policy on the validation contexts, the best one kept."""

    def __init__(self, evaluate: Callable[[], dict[str, Any]], every: int, run: CycleRun,
                 progress: Callable[[int, dict[str, float]], None] | None):
        super().__init__()
        self.evaluate, self.every, self.run, self.progress = evaluate, every, run, progress
        self.best_key, self.best_state, self.episodes = (-1.0, -np.inf), None, 0

    def _on_step(self) -> bool:
        for done in self.locals["dones"]:
            self.episodes += int(done)
            if done and self.episodes % self.every == 0:
                self.check(self.episodes)
        return True

    def _on_training_end(self) -> None:
        if not self.run.curve or self.run.curve[-1]["episodes"] != self.episodes:
            self.check(self.episodes)

    def check(self, episodes: int) -> None:
        judged = self.evaluate()
        row = {"episodes": episodes, "validation_success": judged["success_rate"],
               "validation_return": judged["mean_return"], "validation_failures": failure_counts(judged["failures"])}
        self.run.curve.append(row)
        if self.progress is not None:
            self.progress(episodes, row)
        key = (judged["success_rate"], judged["mean_return"])
        if key > self.best_key:
            self.best_key, self.run.best_episodes = key, episodes
            self.best_state = {k: v.clone() for k, v in self.model.policy.state_dict().items()}


def train_cycle_sb3(env_id: str, algorithm: str = "sac", *, episodes: int = 1000, seed: int = 0, sigma: float = 0.3,
                    rollouts: int = 16, eval_every: int = 80, validation: int = 20, test: int = 50,
                    progress: Callable[[int, dict[str, float]], None] | None = None, validation_pool: int = 400
                    ) -> CycleRun:
    """SAC or PPO (``algorithm``) on the cycle face of ``env_id`` for ``episodes`` training episodes (PPO updates
    every ``rollouts`` episodes); the deterministic policy is evaluated every ``eval_every`` episodes on the
    validation contexts (``validation_pool`` as in :func:`~rdmp_gym.agents.cycle_training.train_cycle_search`) and
    the best one scored on the test contexts."""
    torch.set_num_threads(1)
    face_id = env_id if "Cycle-v" in env_id else cycle_id(env_id)
    start = time.perf_counter()
    env, judge = gym.make(face_id), gym.make(face_id).unwrapped
    steps = judge.n_cycles
    model = _model(algorithm, env, seed, sigma, steps, rollouts)
    validation_seeds = stratified_validation_seeds(judge.face, validation, pool=max(validation_pool, validation))

    def act(cycle: int, observation: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
        return model.predict(observation.astype(np.float32), deterministic=True)[0]

    def evaluate(seeds: np.ndarray = validation_seeds) -> dict[str, Any]:
        return cycle_scores([cycle_episode(judge, act, s) for s in seeds], seeds)

    run = CycleRun(face_id, seed, {"algorithm": algorithm, "episodes": episodes, "sigma": sigma,
                                   "rollouts": rollouts})
    callback = _Evaluation(evaluate, eval_every, run, progress)
    try:
        model.learn(total_timesteps=episodes * steps, callback=callback)   # at most: an episode may end early
        if callback.best_state is not None:
            model.policy.load_state_dict(callback.best_state)
        test_seeds = final_test_seeds(test)
        run.test = evaluate(test_seeds)
        run.wall_seconds = time.perf_counter() - start
        return run
    finally:
        env.close()
        judge.close()

"""stable-baselines3 PPO and SAC on the same episodic env: a contextual bandit, one step per episode.

Settings: see :mod:`rdmp_gym.agents.sb3_config`.

``PPOAgent`` and ``SACAgent`` implement the training loop's agent interface (see ``rdmp_gym.agents.training``).
A resumed PPO run continues from the saved model and optimiser, but not bit-identically (the envs'
random streams restart). Its checkpoint is SB3's own ``.zip``, of which only the weights are read
(``set_parameters``: torch ``weights_only`` loading); SB3's ``data`` entry, which may hold pickled
objects, is never loaded.

With the ``length`` option > 0 the policy acts on a latent vector that a fixed smooth map turns into the action
(:mod:`rdmp_gym.agents.sb3_smooth_actions`); the agents' batches, policy actions and evaluation are actions.
"""

from __future__ import annotations

import importlib.util
import io
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import torch
from rdmp_gym.envs.contract import TaskContract, contract_of
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.logger import Logger, configure
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv, VecEnv

from .episodes import episode_batch, episode_metrics
from .learners.base import EpisodeBatch
from .sb3_config import PPOConfig, SACConfig
from .sb3_smooth_actions import SmoothActions, SmoothActionVecEnv
from .tasks import TaskSpec

__all__ = ["PPOAgent", "SACAgent", "load_weights", "parallel_envs", "start_sac_actor"]


class _EpisodeCollector(BaseCallback):
    """Collects the executed actions and episode metrics of one rollout phase (``contract``: the task's, whose
    metrics the episodes report; ``key``: the name of the policy's actions among the algorithm's locals:
    ``clipped_actions`` for PPO, ``actions`` for SAC; ``smooth``: their map to the executed actions, None if they
    are executed as they are)."""

    def __init__(self, contract: TaskContract, key: str = "clipped_actions", smooth: SmoothActions | None = None
                 ) -> None:
        super().__init__()
        self.contract = contract
        self.key = key
        self.smooth = smooth
        self.actions: list[np.ndarray] = []
        self.metrics: list[dict[str, Any]] = []

    def _on_step(self) -> bool:
        actions = self.locals[self.key] if self.smooth is None else self.smooth(self.locals[self.key])
        for action, reward, info in zip(actions, self.locals["rewards"], self.locals["infos"], strict=True):
            self.actions.append(np.asarray(action, dtype=np.float64))
            # float32 as PPO learns from it (DummyVecEnv keeps rewards in float32, SubprocVecEnv in float64)
            self.metrics.append(episode_metrics(float(np.float32(reward)), info, self.contract))
        return True

    def pop_batch(self) -> EpisodeBatch:
        """The episodes collected since the last call (seeds -1: the vector envs reset themselves)."""
        batch = episode_batch(np.stack(self.actions), self.metrics, np.full(len(self.metrics), -1, dtype=np.int64),
                              self.contract)
        self.actions, self.metrics = [], []
        return batch


def _task_contract(task: TaskSpec) -> TaskContract:
    """The task's contract, read from an env built (and closed) here: the vector env's envs may run in subprocesses."""
    env = task.make()
    try:
        return contract_of(env)
    finally:
        env.close()


def parallel_envs(rollouts: int, envs: int) -> int:
    """PPO's vector-env size: the largest divisor of ``rollouts`` not above the ``envs`` setting (so every
    env takes the same number of steps per update). It depends on the settings only, not on the machine."""
    return max(count for count in range(1, min(envs, rollouts) + 1) if rollouts % count == 0)


def _vector_env(task: TaskSpec, envs: int, workers: int, smooth: SmoothActions | None) -> VecEnv:
    """``envs`` envs, in this process (``workers == 1``) or one subprocess each (the same numbers either way),
    taking latent actions if ``smooth`` is given."""
    makers = [task.make_with_options] * envs
    venv = DummyVecEnv(makers) if workers == 1 or envs == 1 else SubprocVecEnv(makers, start_method="spawn")
    return venv if smooth is None else SmoothActionVecEnv(venv, smooth)


def _smooth_actions(task: TaskSpec, length: float) -> SmoothActions | None:
    """The latent-to-action map correlated over ``length`` neighbouring weights; None for ``length`` 0."""
    if length == 0:
        return None
    env = task.make()
    try:
        return SmoothActions.from_env(env, length)
    finally:
        env.close()


def _latent(smooth: SmoothActions | None, action: np.ndarray) -> np.ndarray:
    """``[n]`` the policy's output for the action ``[n]``."""
    return np.asarray(action, dtype=np.float64) if smooth is None else smooth.latent(action)


def _logger(tensorboard: bool, log_dir: str | Path | None) -> Logger:
    """SB3's logger: TensorBoard files in ``log_dir/tensorboard``, or no output at all. Setting one keeps
    every ``learn()`` from leaving an empty ``SB3-<date>`` folder in the temporary directory (SB3's default)."""
    if not tensorboard:
        return Logger(folder=None, output_formats=[])
    if log_dir is None:
        raise ValueError("ppo.tensorboard: needs a run directory to write to")
    if importlib.util.find_spec("tensorboard") is None:
        raise ModuleNotFoundError('ppo.tensorboard: needs the tensorboard extra: pip install "rdmp-gym[tensorboard]"',
                                  name="tensorboard")
    return configure(str(Path(log_dir) / "tensorboard"), ["tensorboard"])

def load_weights(model: PPO | SAC, state: Mapping[str, Any], name: str) -> None:
    """Load ``state["model"]`` (SB3's zip) into ``model`` weights-only (``set_parameters``: torch
    ``weights_only``); SB3's ``data`` entry, which may hold pickled objects, is never read."""
    if not isinstance(state.get("model"), bytes):
        raise ValueError("state.model: expected the bytes of an SB3 model zip")
    for key in ("num_timesteps", "n_updates"):
        if isinstance(state.get(key), bool) or not isinstance(state.get(key), int) or state[key] < 0:
            raise ValueError(f"state.{key}: expected a count >= 0, got {state.get(key)!r}")
    try:
        model.set_parameters(io.BytesIO(state["model"]), exact_match=True, device="cpu")
    except (ValueError, KeyError, RuntimeError) as error:
        raise ValueError(f"state.model: not a {name} model of this run's shape ({error})") from error
    model.num_timesteps, model._n_updates = state["num_timesteps"], state["n_updates"]


def start_sac_actor(model: SAC, action: np.ndarray, sigma: float) -> None:
    """Start SAC's policy at ``action [n]`` (its mean, squashed) with standard deviation ``sigma`` (before the
    squash) for every observation: the output layers' weights scaled by 0.01 (SAC's standard deviation is an output
    of the network, not a parameter; ``log_std_init`` does not set it)."""
    start = np.arctanh(np.clip(np.asarray(action, dtype=np.float64), -0.999, 0.999))
    actor = model.actor
    with torch.no_grad():
        actor.mu.weight.mul_(0.01)
        actor.mu.bias.copy_(torch.as_tensor(start, dtype=torch.float32))
        actor.log_std.weight.mul_(0.01)
        actor.log_std.bias.fill_(math.log(sigma))


class _SB3Agent:
    """What PPO and SAC agents share: deterministic policy actions, weights-only checkpoints, the divergence check.

    Subclasses set ``model``, ``env``, ``smooth`` (the latent-to-action map or None), ``name`` (``"ppo"``,
    ``"sac"``) and ``divergence_hint``.
    """

    model: PPO | SAC
    env: VecEnv
    smooth: SmoothActions | None
    name: str = ""
    divergence_hint: str = ""

    def _check_finite(self, cause: Exception | None = None) -> None:
        """Raise ``FloatingPointError`` if any policy weight is NaN or inf."""
        if not all(torch.isfinite(parameter).all() for parameter in self.model.policy.parameters()):
            raise FloatingPointError(f"{self.name}: the policy diverged (NaN or inf weights); "
                                     f"{self.divergence_hint}") from cause

    def policy_actions(self, observations: np.ndarray) -> np.ndarray:
        """``[E, n]`` deterministic actions for the contexts ``observations [E, o]``, in ``[-1, 1]``."""
        actions, _ = self.model.predict(np.asarray(observations, dtype=np.float32), deterministic=True)
        if self.smooth is not None:
            return self.smooth(actions)
        return np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0)

    def state_dict(self) -> dict[str, Any]:
        buffer = io.BytesIO()
        self.model.save(buffer)
        return {"model": buffer.getvalue(), "num_timesteps": int(self.model.num_timesteps),
                "n_updates": int(self.model._n_updates)}

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        """Restore the networks and optimisers from SB3's zip (weights only, nothing unpickled)."""
        load_weights(self.model, state, self.name.upper())

    def close(self) -> None:
        self.env.close()


class PPOAgent(_SB3Agent):
    """PPO with one iteration (``rollouts`` episodes, then the gradient epochs) per update.

    Args:
        task: the env.
        initial_action: ``[n]`` the policy mean at the start.
        rollouts: episodes per update.
        workers: 1 steps the envs in this process; more runs each of the ``envs`` envs (see
            :func:`parallel_envs`) in its own subprocess (``SubprocVecEnv``). The numbers do not depend on it.
        seed: seeds torch, the policy and the envs.
        options: fields of :class:`PPOConfig`.
    """

    name = "ppo"
    divergence_hint = "lower learning_rate or target_kl (--option learning_rate=...)"

    def __init__(self, task: TaskSpec, initial_action: np.ndarray, rollouts: int, workers: int, seed: int,
                 options: PPOConfig | Mapping[str, Any] | None = None, log_dir: str | Path | None = None) -> None:
        self.config = options if isinstance(options, PPOConfig) else PPOConfig.from_dict(options)
        self._logger = _logger(self.config.tensorboard, log_dir)
        envs = parallel_envs(rollouts, self.config.envs)
        self.rollouts = rollouts
        self.smooth = _smooth_actions(task, self.config.length)
        self.env = _vector_env(task, envs, workers, self.smooth)
        self.env.seed(seed)
        batch = self.config.batch_size or rollouts
        hidden = [self.config.hidden, self.config.hidden]
        self.model = PPO("MlpPolicy", self.env, n_steps=rollouts // envs, batch_size=batch,
                         n_epochs=self.config.n_epochs, learning_rate=self.config.learning_rate,
                         clip_range=self.config.clip_range, ent_coef=self.config.ent_coef,
                         target_kl=self.config.target_kl or None, gamma=0.0,
                         gae_lambda=1.0, seed=seed, device="cpu", verbose=0,
                         policy_kwargs={"net_arch": {"pi": hidden, "vf": hidden},
                                        "log_std_init": math.log(self.config.sigma)})
        self.model.set_logger(self._logger)
        with torch.no_grad():
            self.model.policy.action_net.bias.copy_(torch.as_tensor(_latent(self.smooth, initial_action),
                                                                    dtype=torch.float32))
        self._collector = _EpisodeCollector(_task_contract(task), smooth=self.smooth)

    @classmethod
    def from_run(cls, config: Any, initial_action: np.ndarray, run_path: Path) -> PPOAgent:
        """The agent of a training run (``config``: a :class:`~rdmp_gym.agents.training.TrainConfig`)."""
        return cls(config.task, initial_action, config.rollouts, config.workers, config.seed, config.options,
                   log_dir=run_path)

    @property
    def exploration(self) -> float:
        return float(torch.exp(self.model.policy.log_std.detach()).mean())

    def train_update(self) -> EpisodeBatch:
        try:
            self.model.learn(self.rollouts, callback=self._collector, reset_num_timesteps=False)
        except ValueError as error:        # torch rejects a Normal with NaN parameters while collecting
            self._check_finite(error)
            raise
        self._check_finite()
        return self._collector.pop_batch()


class SACAgent(_SB3Agent):
    """SAC with ``rollouts`` environment steps (episodes) and their gradient steps per update.

    Args:
        task: the env.
        initial_action: ``[n]`` the policy mean at the start (in ``(-1, 1)``).
        rollouts: episodes per update.
        seed: seeds torch, the policy and the env.
        options: fields of :class:`SACConfig`.
    """

    name = "sac"
    divergence_hint = "lower learning_rate (--option learning_rate=...)"

    @classmethod
    def from_run(cls, config: Any, initial_action: np.ndarray, run_path: Path) -> SACAgent:
        """The agent of a training run (``config``: a :class:`~rdmp_gym.agents.training.TrainConfig`)."""
        return cls(config.task, initial_action, config.rollouts, config.seed, config.options)

    def __init__(self, task: TaskSpec, initial_action: np.ndarray, rollouts: int, seed: int,
                 options: SACConfig | Mapping[str, Any] | None = None) -> None:
        self.config = options if isinstance(options, SACConfig) else SACConfig.from_dict(options)
        self.rollouts = rollouts
        self.smooth = _smooth_actions(task, self.config.length)
        self.env = _vector_env(task, 1, 1, self.smooth)
        self.env.seed(seed)
        hidden = [self.config.hidden, self.config.hidden]
        self.model = SAC("MlpPolicy", self.env, learning_rate=self.config.learning_rate,
                         buffer_size=self.config.buffer_size, learning_starts=0, batch_size=self.config.batch_size,
                         gamma=0.0, train_freq=(rollouts, "step"), gradient_steps=self.config.gradient_steps * rollouts,
                         seed=seed, device="cpu", verbose=0,
                         policy_kwargs={"net_arch": hidden})
        start_sac_actor(self.model, _latent(self.smooth, initial_action), self.config.sigma)
        self.model.set_logger(_logger(False, None))
        self._collector = _EpisodeCollector(_task_contract(task), "actions", self.smooth)

    @property
    def exploration(self) -> float:
        """Mean standard deviation of the pre-squash Gaussian for a zero context."""
        with torch.no_grad():
            features = self.model.actor.extract_features(torch.zeros((1, *self.env.observation_space.shape)),
                                                         self.model.actor.features_extractor)
            log_std = self.model.actor.log_std(self.model.actor.latent_pi(features))
        return float(torch.exp(log_std).mean())

    def train_update(self) -> EpisodeBatch:
        self.model.learn(self.rollouts, callback=self._collector, reset_num_timesteps=False)
        self._check_finite()
        return self._collector.pop_batch()


"""rdmp_gym.agents: imitation start, PI²/CMA-ES/contextual learners, SB3 PPO, training runs and the CLI.

Main entry points (stable-baselines3/torch are imported only when PPO is used)::

    from rdmp_gym.agents import TrainConfig, train, evaluate_run
    run = train(TrainConfig(agent="pi2", updates=30, rollouts=10, workers=2), "runs/pi2", progress=True)
    evaluate_run(run.path, episodes=10)

The names below are imported on first use, so that the ``rdmp-gym`` command (which lives in this
package) runs its core-only commands (``--help``, ``fit``) on an install without the ``agents`` extra.
"""

from __future__ import annotations

import importlib
from typing import Any

# name -> the submodule that defines it (add new public names here)
_EXPORTS = {
    "evaluate_run": "report", "record_best_episode": "report",
    "Evaluator": "pool",
    "fit_dmp": "imitation", "load_demonstration": "imitation",
    **dict.fromkeys(("CMAES", "PI2", "BBRLConfig", "CMAESConfig", "ContextualConfig", "EpisodeBatch", "Learner",
                     "PI2Config", "make_learner"), "learners"),
    "PPOConfig": "sb3_config", "SACConfig": "sb3_config", "Settings": "config", "register": "registry",
    "RunDirectory": "runs",
    "WIPE_ID": "tasks", "TaskSpec": "tasks",
    "TRACKING_ID": "rdmp_gym.envs.registration", "TrackingEnv": "rdmp_gym.envs.tracking",
    "AGENTS": "train_config", "TrainConfig": "train_config", "train": "training",
}

__all__ = sorted(_EXPORTS)

#: Python modules of the optional extras (``agents``, ``tensorboard``): a missing one is a missing extra.
EXTRA_MODULES = ("gymnasium", "mujoco", "imageio", "cma", "tqdm", "stable_baselines3", "torch", "filelock",
                 "matplotlib", "tensorboard")


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    target = _EXPORTS[name]
    try:
        module = importlib.import_module(target if "." in target else f"{__name__}.{target}")
    except ModuleNotFoundError as error:
        if error.name and error.name.split(".")[0] in EXTRA_MODULES:
            raise ModuleNotFoundError(f"rdmp_gym.agents.{name} needs the 'agents' extra (missing module "
                                      f"{error.name!r}): pip install \"rdmp-gym[agents]\"", name=error.name) from error
        raise
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])

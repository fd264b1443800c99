"""What the agents run on: an environment id, its ``gym.make`` keywords and fixed reset options."""

from __future__ import annotations

import copy
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import rdmp_gym.envs  # noqa: F401  (registers the env ids with gymnasium)
from rdmp_gym.envs.registration import ENV_ID, ENV_ID_V2, LATEST_ENV_ID, learner_defaults
from rdmp_gym.envs.specs import env_class, is_episodic

from .episodes import episode_metrics, failure_contexts, run_episode
from .imitation import load_demonstration

__all__ = ["MAIN_AGENT", "MAIN_ENV", "MAIN_ENV_KWARGS", "MAIN_OPTIONS", "STEP_AGENT", "STEP_OPTIONS", "WIPE_ID",
           "WIPE_V2_ID", "ResetOptions", "TaskSpec", "episode_metrics", "failure_contexts", "main_agent",
           "main_env_kwargs", "main_options", "run_episode", "task_options"]

#: the first wiping task (the ids are defined in ``rdmp_gym.envs.registration``)
WIPE_ID = ENV_ID
#: The wiping task whose pattern travels across the patch (every context solvable); see
#: ``rdmp_gym.envs.tasks.wiping.versions``.
WIPE_V2_ID = ENV_ID_V2

#: The defaults of every layer, defined here once: the main job (``rdmp-gym main``), ``rdmp-gym train`` without
#: ``--agent``/``--env``, ``TrainConfig()`` and ``TaskSpec()`` all run the learner that reached the validation target
#: soonest in the benchmark, ``bbrl`` exploring the approach 3x wider, on the current task executed with the hand's
#: clearance from the cup, at the trust region it was measured with (``epsilon`` 0.2; ``bbrl``'s own default is 1.0).
#: Given options and env keywords of the same name replace these.
MAIN_AGENT = "bbrl"
MAIN_ENV = LATEST_ENV_ID
MAIN_ENV_KWARGS: dict[str, Any] = {"cup_clearance": 0.01}
MAIN_OPTIONS: dict[str, Any] = {"sigma_factors": {"approach": 3.0}, "epsilon": 0.2}
#: On a step-based env (run under the rhythmic black-box wrapper) the learner that scored highest in the locomotion
#: benchmark: CMA-ES with its first step a third of its own default, so that it searches near the wrapper's default
#: pattern (Swimmer-v5 331, HalfCheetah-v5 2287 over 10 seeds at 100k env steps, against 126 and 758 for ``bbrl``).
STEP_AGENT = "cmaes"
STEP_OPTIONS: dict[str, Any] = {"sigma": 0.2}


def main_agent(env_id: str) -> str:
    """The learner a run gets when none is given: :data:`MAIN_AGENT` on an episodic env, :data:`STEP_AGENT` on a
    step-based one."""
    return MAIN_AGENT if is_episodic(env_id) else STEP_AGENT


def main_env_kwargs(env_id: str) -> dict[str, Any]:
    """The env keywords a run gets when none are given: :data:`MAIN_ENV_KWARGS` on the main env, else none."""
    return copy.deepcopy(MAIN_ENV_KWARGS) if env_id == MAIN_ENV else {}


def main_options(agent: str, env_id: str) -> dict[str, Any]:
    """The learner settings a run gets when none are given: :data:`MAIN_OPTIONS` for the main learner on the main
    env, :data:`STEP_OPTIONS` for :data:`STEP_AGENT` on a step-based env, else none (the task's learner defaults still
    apply: :func:`task_options`)."""
    if agent == MAIN_AGENT and env_id == MAIN_ENV:
        return copy.deepcopy(MAIN_OPTIONS)
    if agent == STEP_AGENT and not is_episodic(env_id):
        return copy.deepcopy(STEP_OPTIONS)
    return {}



#: options that name the env's action groups: a task's defaults assume its own layout and drop them under other groups
_GROUP_OPTIONS = ("gain_groups", "features", "sigma_factors")


def task_options(env_id: str, agent: str, options: Mapping[str, Any], env_kwargs: Mapping[str, Any] | None = None
                 ) -> dict[str, Any]:
    """``options`` over what ``agent`` may read from the task of ``env_id``
    (:func:`rdmp_gym.envs.registration.learner_defaults`); with ``env_kwargs`` that choose other action ``groups``,
    the defaults that name groups are dropped."""
    defaults = learner_defaults(env_id).get(agent, {})
    if "groups" in (env_kwargs or {}):
        defaults = {key: value for key, value in defaults.items() if key not in _GROUP_OPTIONS}
    return {**defaults, **options}


@dataclass(frozen=True)
class TaskSpec:
    """A picklable recipe for the task's environment (worker processes rebuild it from this).

    Attributes:
        env_id: a registered env with a continuous action space, with a string or a class entry point: an episodic
            env (one that declares a task contract, :func:`rdmp_gym.envs.specs.is_episodic`; default
            :data:`MAIN_ENV`, the current wiping task), or a step-based env, run under the rhythmic black-box wrapper.
        env_kwargs: the env's settings (the wiping task's style, groups, n_periodic, duration, ...; on a step-based
            env the wrapper's settings and the env's ``gym.make`` keywords,
            :func:`rdmp_gym.envs.blackbox.split_settings`); None: :func:`main_env_kwargs`.
        reset_options: ``options`` passed to every ``reset`` (e.g. to fix the context), or None.
        demo: a CSV/NPZ demonstration that the env fits its initial DMP to ("" = none), in the env's own space (the
            wiping and tracking tasks: the table frame in metres; a step-based env: its actuated joints); passed as
            the env's (or the wrapper's) ``demonstration`` keyword.
    """

    env_id: str = MAIN_ENV
    env_kwargs: Mapping[str, Any] | None = None
    reset_options: Mapping[str, Any] | None = None
    demo: str = ""

    def __post_init__(self) -> None:
        if self.env_kwargs is None:
            object.__setattr__(self, "env_kwargs", main_env_kwargs(self.env_id))

    def make(self, render_mode: str | None = None) -> gym.Env:
        """Build the environment (importing the packages that register the ids): an episodic env as it is, with
        ``env_kwargs``; a step-based env under the rhythmic black-box wrapper (:meth:`_black_box`). Which it is, is
        told by what the env is (:func:`rdmp_gym.envs.specs.is_episodic`), not by the package that registers it."""
        if not is_episodic(self.env_id):           # ValueError naming an unknown id
            return self._black_box(render_mode)
        kwargs = dict(self.env_kwargs)
        if render_mode is not None:
            kwargs["render_mode"] = render_mode
        if self.demo:
            kwargs["demonstration"] = load_demonstration(self.demo)
        try:
            return gym.make(self.env_id, disable_env_checker=True, **kwargs)
        except gym.error.Error as error:   # unknown id, namespace or version
            raise ValueError(f"env_id: {error}") from error

    def _black_box(self, render_mode: str | None) -> gym.Env:
        """A step-based env under the rhythmic black-box wrapper with its defaults: the wrapper's settings among
        ``env_kwargs`` replace them, the rest go to the env's ``gym.make`` (``demo``: the wrapper's demonstration, in
        the actuated joints); ValueError passing on the wrapper's reason where it cannot drive the env (a discrete
        action space, a setting it needs). Without ``render_mode``, an env whose class renders RGB frames is made with
        ``render_mode="rgb_array"``, so that the wrapper can record its episodes (a Gymnasium MuJoCo env renders only
        when asked: nothing is spent otherwise)."""
        from rdmp_gym.envs.blackbox import make_blackbox, split_settings

        twin = self.env_id.replace("Step-v", "-v")
        if self.env_id.startswith("rdmp_gym/") and twin != self.env_id and twin in gym.registry:
            raise ValueError(f"env_id: {self.env_id} is the step twin of {twin} (one control step per env step, for a "
                             f"step-based learner of your own); the agents of rdmp-gym run episodic envs: use {twin}")
        wrapper, env_kwargs = split_settings(self.env_id, self.env_kwargs)   # ValueError naming a setting nobody takes
        kind = env_class(self.env_id)
        if render_mode is None and "render_mode" not in env_kwargs and kind is not None \
                and "rgb_array" in getattr(kind, "metadata", {}).get("render_modes", ()):
            render_mode = "rgb_array"
        if self.demo:
            wrapper["demonstration"] = load_demonstration(self.demo)
        try:
            return make_blackbox(self.env_id, env_kwargs=env_kwargs, render_mode=render_mode, **wrapper)
        except ValueError as error:
            raise ValueError(f"env_id: {self.env_id} is a step-based env, not an episodic DMP env (one step = one "
                             f"DMP rollout), and the rhythmic black-box wrapper that would run it cannot: {error}"
                             ) from error

    def make_with_options(self) -> gym.Env:
        """The environment, wrapped so that every reset without options uses ``reset_options``."""
        return ResetOptions(self.make(), self.options())

    def options(self) -> dict[str, Any] | None:
        """A fresh copy of the reset options."""
        return None if self.reset_options is None else dict(self.reset_options)


class ResetOptions(gym.Wrapper):
    """Applies fixed reset options whenever ``reset`` gets none (vector envs auto-reset without options)."""

    def __init__(self, env: gym.Env, options: dict[str, Any] | None) -> None:
        super().__init__(env)
        self.fixed_options = options

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[Any, dict[str, Any]]:
        return self.env.reset(seed=seed, options=self.fixed_options if options is None else options)

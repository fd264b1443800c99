"""Locomotion study of the rhythmic black-box wrapper: Swimmer-v5 and HalfCheetah-v5 (and the other locomotion envs),
rhythmic learners vs PPO/SAC.

Rhythmic learners (``cmaes``, ``bbrl``, ``plain_prior`` = ``cpi2`` with ``gain_prior`` 10, and the random-return
control ``random``) train through the package's own loop (:func:`rdmp_gym.agents.training.train`) on the black-box
wrapper with the env's defaults (:data:`rdmp_gym.envs.blackbox.ENV_DEFAULTS`): one episode = one DMP rollout of
1000 env steps, ``updates x rollouts`` episodes per run (default 10 x 10 = 100k env steps). Their policy is
evaluated after every update (every 10k env steps) on the validation contexts of :mod:`rdmp_gym.agents.protocol`.

stable-baselines3 PPO and SAC run on the raw step env (``gym.make(env_id)``) with the RL Zoo's hyperparameters
(:data:`ZOO`), their deterministic policy evaluated by a callback on the same validation contexts at the same env
step marks. SAC is the expensive one (about 70 env steps/s on one core: 100k env steps take ~25 min a run).

Every run's final policy is scored on the test contexts (``final_test_seeds``), which no run trains or selects on.
Per (env, learner, seed) one JSON under ``--run-dir`` (default ``runs/locomotion/``): a finished run is skipped, an
interrupted one resumes (rhythmic learners from their checkpoint; PPO/SAC from their last step mark, which is not
bit-identical to an uninterrupted run). The summary per env x learner: the interquartile mean over seeds of the final
test return with a 95 % percentile-bootstrap interval (``rdmp_gym.agents.protocol.interval``), and the env steps
until the validation return first reaches the thresholds of :data:`THRESHOLDS` (median over the seeds that reach it,
and how many do). The published anchors (:data:`ANCHORS`, each with its source) go beside it.

    # everything, one job after the other, the most important first (on one core of a shared 2-core machine:
    # Swimmer ~45 min, HalfCheetah ~75 min, the 20 SAC runs ~8 h):
    python benchmarks/bench_locomotion.py --save
    # a smoke test (1 seed, 2 updates, 2 PPO marks):
    python benchmarks/bench_locomotion.py --seeds 1 --updates 2 --ppo-steps 20000 --sac-seeds 0 --run-dir /tmp/loco
    # the table from the runs so far, without training; the figures (learning curves, Swimmer filmstrip):
    python benchmarks/bench_locomotion.py --summary-only --save
    python benchmarks/bench_locomotion.py --figures --save

``--feedback``: the reacting policy against the open-loop one, ``cmaes`` with the wrapper's default settings against
``cmaes_feedback`` (the same with ``feedback="linear"``), seed by seed alternating between the envs, no SAC, runs in
``runs/locomotion_feedback/``; ``locomotion_feedback.json`` has PPO and SAC from ``locomotion.json`` (they run on the
raw env, so the wrapper's defaults do not touch them), the open-loop oscillator from ``open_loop_oscillator.json`` and
the default pattern's ``a = 0`` return on the test contexts beside them:

    python benchmarks/bench_locomotion.py --feedback --seeds 10 --save

``--other-envs``: the feedback study's best settings (``cmaes_near``, ``cmaes_feedback_near``) and the random-return
control on Hopper-v5 and Walker2d-v5 (Ant-v5 with ``--envs``), whose default pattern comes from the MuJoCo model and
whose episodes end on a fall (each run records the env steps it used, ``env_steps_used``), no SAC, the RL Zoo's
1M-step returns beside them, written to ``locomotion_other.json``:

    python benchmarks/bench_locomotion.py --other-envs --save
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
from output import COMMITTED, add_save_argument, results_dir
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.protocol import context_observations, final_test_seeds, interval, validation_seeds
from rdmp_gym.agents.report import trained_actions
from rdmp_gym.agents.training import TrainConfig, environment_record, train

ROOT = Path(__file__).resolve().parent.parent
ENVS = ("Swimmer-v5", "HalfCheetah-v5")
#: the envs of --other-envs: the terminating locomotion envs, whose default pattern comes from the MuJoCo model
OTHER_ENVS = ("Hopper-v5", "Walker2d-v5", "Ant-v5")
ALL_ENVS = (*ENVS, *OTHER_ENVS)
#: label -> (agent, options, wrapper settings over the env's defaults) of the rhythmic learners
LEARNERS: dict[str, tuple[str, dict[str, Any], dict[str, Any]]] = {
    "cmaes": ("cmaes", {}, {}),
    "bbrl": ("bbrl", {"epsilon": 0.2}, {}),          # the trust region the study was run with
    "plain_prior": ("cpi2", {"gain_prior": 10}, {}),
    "random": ("random", {}, {}),
    # the amplitude's action scale 1 instead of 0.5: a = +1 doubles the default amplitude (on Swimmer to the 1 rad of
    # Raffin et al.'s oscillator, which the default range, at most 1.5 x 0.5 rad, cannot reach); opt-in
    "cmaes_wide": ("cmaes", {}, {"scales": {"amplitude": 1.0}}),
    "plain_prior_wide": ("cpi2", {"gain_prior": 10}, {"scales": {"amplitude": 1.0}}),
    # the reacting policy: the controller's command gains K z (z the observation standardised on the a = 0 gait,
    # K the action's last group, zero at a = 0); opt-in
    "cmaes_feedback": ("cmaes", {}, {"feedback": "linear"}),
    # CMA-ES's first step a third of its default (0.2 instead of 0.6 action units), so that the search stays near the
    # default pattern it starts from; opt-in, open loop and with the feedback
    "cmaes_near": ("cmaes", {"sigma": 0.2}, {}),
    "cmaes_feedback_near": ("cmaes", {"sigma": 0.2}, {"feedback": "linear"}),
    # a sixth of the default: on Swimmer, whose default pattern is the published optimum, the search keeps it; on the
    # envs whose pattern is derived from the model it moves too little; opt-in
    "cmaes_closer": ("cmaes", {"sigma": 0.1}, {}),
}
#: the learners of --feedback
FEEDBACK_LEARNERS = ("cmaes", "cmaes_feedback")
#: the learners of --other-envs: the best settings of the feedback study and the random-return control
OTHER_LEARNERS = ("cmaes_near", "cmaes_feedback_near", "random")
#: (learner, baseline) pairs compared seed by seed in the --feedback study, where both ran
PAIRS = (("cmaes_feedback", "cmaes"), ("cmaes_feedback_near", "cmaes_near"), ("cmaes_near", "cmaes"),
         ("cmaes_feedback_near", "cmaes_feedback"), ("cmaes_closer", "cmaes_near"))
#: the learners run when --learners is not given
MAIN_LEARNERS = ("cmaes", "bbrl", "plain_prior", "random", "ppo")
SB3_ALGOS = ("ppo", "sac")
#: step-based learners on the DMP's residual env (:mod:`rdmp_gym.envs.blackbox.residual`, the default pattern at
#: ``a = 0``) -> (their algorithm with its RL Zoo settings, the residual's scale: a = +-1 adds that share of half the
#: action range; 1.0 lets the residual command the whole range)
RESIDUAL_LEARNERS = {"sac_residual": ("sac", 0.3), "sac_residual_full": ("sac", 1.0), "ppo_residual": ("ppo", 0.3)}
EPISODE_STEPS = 1000   # Swimmer, HalfCheetah: 1000 env steps per episode; the other envs end earlier on a fall, so
                       # their rhythmic runs' env steps (episodes x 1000) are an upper bound

#: Return thresholds: Mania et al. 2018 (Simple random search provides a competitive approach to reinforcement
#: learning, arXiv 1803.07055, Table 1): Swimmer 325. HalfCheetah: 3000 as the study was specified, and 3430, the
#: value we recall from their Table 1 (not checked against the paper text here, see ANCHORS).
THRESHOLDS: dict[str, tuple[float, ...]] = {"Swimmer-v5": (325.0,), "HalfCheetah-v5": (3000.0, 3430.0)}

_ZOO = "rl-baselines3-zoo hyperparams/{}.yml (DLR-RM/rl-baselines3-zoo, commit 22e3ff2, entries for the -v4 envs)"
#: The RL Zoo's tuned hyperparameters (``normalize``: VecNormalize of observations and rewards with the run's gamma).
ZOO: dict[str, dict[str, dict[str, Any]]] = {
    "ppo": {
        "Swimmer-v5": {"normalize": True, "n_envs": 4, "gamma": 0.9999, "n_steps": 1024, "batch_size": 256,
                       "learning_rate": 6e-4, "gae_lambda": 0.98},
        "HalfCheetah-v5": {"normalize": True, "n_envs": 1, "batch_size": 64, "n_steps": 512, "gamma": 0.98,
                           "learning_rate": 2.0633e-05, "ent_coef": 0.000401762, "clip_range": 0.1, "n_epochs": 20,
                           "gae_lambda": 0.92, "max_grad_norm": 0.8, "vf_coef": 0.58096,
                           "policy_kwargs": {"log_std_init": -2, "ortho_init": False, "activation_fn": "relu",
                                             "net_arch": {"pi": [256, 256], "vf": [256, 256]}}},
    },
    "sac": {
        "Swimmer-v5": {"learning_starts": 10000, "gamma": 0.999},
        "HalfCheetah-v5": {"learning_starts": 10000},
    },
}

_BENCHMARK_MD = ("rl-baselines3-zoo benchmark.md, 'Performance of trained agents' (DLR-RM/rl-baselines3-zoo, commit "
                 "22e3ff2): one trained agent each, deterministic policy, 150 evaluation episodes, mean +- std")
_ARS = ("Mania, Guy, Recht 2018, Simple random search provides a competitive approach to reinforcement learning, "
        "arXiv 1803.07055, Table 1 (average episodes over 3 seeds to reach the threshold; -v1 envs); recalled, not "
        "checked against the paper text in this study")
_RAFFIN = ("Raffin, Sigaud, Kober, Albu-Schaeffer, Silverio, Stulp 2024, An Open-Loop Baseline for Reinforcement "
           "Learning Locomotion Tasks, arXiv 2310.05808 (https://arxiv.org/html/2310.05808v3)")
_CITE_ZOO = "RL Zoo benchmark.md (22e3ff2)"
_CITE_ARS = "Mania et al. 2018, Table 1 (recalled, not checked)"
_CITE_RAFFIN = "Raffin et al. 2024 (arXiv 2310.05808)"
#: Published anchors. ``return`` is the final return (``std`` its spread as published), ``env_steps`` the training
#: budget; ``episodes_to_threshold`` where the source gives it. None: the source has no such number (or we could not
#: read it: ``note`` says so).
ANCHORS: list[dict[str, Any]] = [
    {"env": "Swimmer-v5", "method": "RL Zoo PPO (Swimmer-v3)", "return": 281.561, "std": 9.671,
     "env_steps": 1_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    {"env": "Swimmer-v5", "method": "RL Zoo SAC (Swimmer-v3)", "return": 345.568, "std": 3.084,
     "env_steps": 1_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    {"env": "Swimmer-v5", "method": "RL Zoo ARS (Swimmer-v3)", "return": 355.267, "std": 12.796,
     "env_steps": 2_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    {"env": "HalfCheetah-v5", "method": "RL Zoo PPO (HalfCheetah-v3)", "return": 5819.099, "std": 663.530,
     "env_steps": 1_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    {"env": "HalfCheetah-v5", "method": "RL Zoo SAC (HalfCheetah-v3)", "return": 9535.451, "std": 100.470,
     "env_steps": 1_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    {"env": "HalfCheetah-v5", "method": "RL Zoo ARS (HalfCheetah-v3)", "return": 4815.192, "std": 1340.752,
     "env_steps": 12_000_000, "source": _BENCHMARK_MD, "cite": _CITE_ZOO},
    *({"env": env, "method": f"RL Zoo {algo} ({env.replace('v5', 'v3')})", "return": value, "std": None,
       "env_steps": 1_000_000, "source": _BENCHMARK_MD + " (read from the project's anchor notes; std not kept)",
       "cite": _CITE_ZOO}
      for env, algo, value in (("Hopper-v5", "PPO", 2410.0), ("Hopper-v5", "SAC", 2326.0),
                               ("Walker2d-v5", "PPO", 3479.0), ("Walker2d-v5", "SAC", 3863.0),
                               ("Ant-v5", "PPO", 1327.0), ("Ant-v5", "SAC", 4616.0))),
    {"env": "Swimmer-v5", "method": "ARS V1 / V2-t (Swimmer-v1)", "return": None, "threshold": 325.0,
     "episodes_to_threshold": {"ARS V1": 100, "ARS V2-t": 427}, "env_steps_to_threshold": {"ARS V1": 100_000},
     "source": _ARS, "cite": _CITE_ARS},
    {"env": "HalfCheetah-v5", "method": "ARS V1 / V2-t (HalfCheetah-v1)", "return": None, "threshold": 3430.0,
     "episodes_to_threshold": {"ARS V1": 10240, "ARS V2-t": 1707}, "source": _ARS,
     "cite": _CITE_ARS},
    {"env": "Swimmer-v5", "method": "open-loop oscillator, Raffin et al. 2024", "return": None,
     "note": "their table of returns could not be read from the stored text in this study; the row "
             "'oscillator re-run here' is their published Swimmer oscillator (0.62 Hz, phases 0 and 0.95 x 2 pi, PD "
             "10 / 0.5, unit amplitude) run on Swimmer-v5 by this script", "source": _RAFFIN, "cite": _CITE_RAFFIN},
    {"env": "HalfCheetah-v5", "method": "open-loop oscillator, Raffin et al. 2024", "return": None,
     "note": "their table of returns and their HalfCheetah oscillator parameters could not be read from the stored "
             "text in this study", "source": _RAFFIN, "cite": _CITE_RAFFIN},
]


# ---------------------------------------------------------------------------------------------------- arguments
def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--envs", nargs="+", default=None, choices=ALL_ENVS,
                        help=f"default: {' '.join(ENVS)}; with --other-envs {' '.join(OTHER_ENVS[:2])}")
    parser.add_argument("--learners", nargs="+", default=None, choices=[*LEARNERS, *SB3_ALGOS, *RESIDUAL_LEARNERS],
                        help="the learners of the main jobs (SAC runs after them, see --sac-seeds; default: "
                             f"{' '.join(MAIN_LEARNERS)}, with --feedback {' '.join(FEEDBACK_LEARNERS)}, "
                             "with --residual sac_residual)")
    parser.add_argument("--seeds", type=int, default=10, help="seeds 0..n-1 of every main learner")
    parser.add_argument("--updates", type=int, default=10, help="rhythmic learners: updates per run")
    parser.add_argument("--rollouts", type=int, default=10, help="rhythmic learners: episodes per update")
    parser.add_argument("--ppo-steps", type=int, default=None, help="PPO env steps (default: the rhythmic budget)")
    parser.add_argument("--sac-seeds", type=int, default=10, help="SAC seeds 0..n-1 per env (0: no SAC)")
    parser.add_argument("--sac-steps", type=int, default=None, help="SAC env steps (default: the rhythmic budget)")
    parser.add_argument("--eval-episodes", type=int, default=3, help="validation contexts per evaluation")
    parser.add_argument("--test-episodes", type=int, default=10, help="test contexts for the final policy")
    parser.add_argument("--run-dir", default=None,
                        help="where the runs live (default: runs/locomotion, runs/locomotion_feedback with "
                             "--feedback, runs/locomotion_residual with --residual)")
    study = parser.add_mutually_exclusive_group()
    study.add_argument("--feedback", action="store_true",
                       help="the feedback study: cmaes open loop vs with feedback='linear', no SAC, written to "
                            "locomotion_feedback.json")
    study.add_argument("--residual", action="store_true",
                       help="the residual study: SAC on the DMP's residual env, no plain SAC, written to "
                            "locomotion_residual.json")
    study.add_argument("--other-envs", action="store_true",
                       help="the rhythmic learners of the feedback study on the other locomotion envs (Hopper, "
                            "Walker2d; Ant with --envs), no SAC, written to locomotion_other.json")
    parser.add_argument("--summary-only", action="store_true", help="gather the finished runs; train nothing")
    parser.add_argument("--figures", action="store_true",
                        help="draw the study's curves (locomotion.png from locomotion.json, with --feedback "
                             "locomotion_feedback.png, ...) and per env a filmstrip and a video of its best run's "
                             "final policy; train nothing")
    add_save_argument(parser)
    args = parser.parse_args()
    args.study = ("feedback" if args.feedback else "residual" if args.residual else "other" if args.other_envs
                  else "main")
    if args.envs is None:
        args.envs = list(OTHER_ENVS[:2] if args.other_envs else ENVS)
    if args.learners is None:
        args.learners = list({"feedback": FEEDBACK_LEARNERS, "residual": ("sac_residual",),
                              "other": OTHER_LEARNERS}.get(args.study, MAIN_LEARNERS))
    if args.run_dir is None:
        args.run_dir = str(ROOT / "runs" / {"main": "locomotion"}.get(args.study, f"locomotion_{args.study}"))
    if args.study != "main":
        args.sac_seeds = 0
    budget = args.updates * args.rollouts * EPISODE_STEPS
    args.ppo_steps = budget if args.ppo_steps is None else args.ppo_steps
    args.sac_steps = budget if args.sac_steps is None else args.sac_steps
    return args


def _marks(total: int) -> list[int]:
    """The env-step marks of the curves: every update of the rhythmic learners (10 episodes = 10k steps)."""
    step = 10 * EPISODE_STEPS
    return sorted({*range(0, total, step), total})


# ---------------------------------------------------------------------------------------------------- rhythmic
def _rhythmic_config(env_id: str, label: str, seed: int, args: argparse.Namespace) -> TrainConfig:
    agent, options, settings = LEARNERS[label]
    return TrainConfig(agent=agent, env_id=env_id, updates=args.updates, rollouts=args.rollouts, seed=seed,
                       options=options, env_kwargs=dict(settings), eval_every=1, eval_episodes=args.eval_episodes,
                       shared_context=False)


def run_rhythmic(env_id: str, label: str, seed: int, args: argparse.Namespace, folder: Path) -> dict[str, Any]:
    """One rhythmic learner's run (resumed where ``folder/<label>-<seed>`` holds one) and its final test score."""
    began = time.perf_counter()
    config = _rhythmic_config(env_id, label, seed, args)
    run_dir = folder / f"{label}-{seed}"
    run = train(config, run_dir, resume=(run_dir / "config.json").is_file())
    records = run.read_log()
    curve = [{"env_steps": int(r["episodes"]) * EPISODE_STEPS, "return": float(r["eval_return_mean"])}
             for r in records if r.get("eval_return_mean") is not None]
    # each update's mean episode length x its rollouts: the env steps the run took (the budget where none ends early)
    used = sum(float(r.get("env_steps", 0.0)) * args.rollouts for r in records)
    seeds = final_test_seeds(args.test_episodes)
    with Evaluator(config.task, 1) as tester:
        observations = context_observations(tester.env, seeds)
        actions = trained_actions(run, config, "last", observations, tester.n_actions)
        batch = tester.run(actions, seeds)
    return {"curve": curve, "test_returns": batch.returns.tolist(), "options": config.options.to_dict(),
            "env_steps_used": round(used), "seconds": round(time.perf_counter() - began, 1)}


# ---------------------------------------------------------------------------------------------------- SB3
def _sb3_kwargs(algo: str, env_id: str) -> tuple[dict[str, Any], bool, int]:
    """(the model's keywords, normalize, n_envs) of :data:`ZOO`."""
    import torch

    values = dict(ZOO[algo][env_id])
    normalize, n_envs = values.pop("normalize", False), values.pop("n_envs", 1)
    if "policy_kwargs" in values:
        policy = dict(values["policy_kwargs"])
        policy["activation_fn"] = {"relu": torch.nn.ReLU, "tanh": torch.nn.Tanh}[policy["activation_fn"]]
        values["policy_kwargs"] = policy
    return values, normalize, n_envs


def evaluate_sb3(model: Any, normalizer: Any, env: gym.Env, seeds: np.ndarray) -> list[float]:
    """Returns ``[E]`` of the deterministic policy, one episode per reset seed on the raw env ``env``."""
    returns = []
    for seed in seeds:
        observation, _ = env.reset(seed=int(seed))
        total, done = 0.0, False
        while not done:
            seen = normalizer.normalize_obs(observation) if normalizer is not None else observation
            action, _ = model.predict(seen, deterministic=True)
            observation, reward, terminated, truncated, _ = env.step(action)
            total += float(reward)
            done = terminated or truncated
        returns.append(total)
    return returns


def _algorithm(label: str) -> str:
    """``ppo`` or ``sac``: the algorithm of a step learner (a raw-env one or one of :data:`RESIDUAL_LEARNERS`)."""
    return RESIDUAL_LEARNERS[label][0] if label in RESIDUAL_LEARNERS else label


def _sb3_env(env_id: str, label: str) -> tuple[str, dict[str, Any]]:
    """(the id to make, its keywords) of a PPO/SAC learner: the raw env, or for :data:`RESIDUAL_LEARNERS` the
    DMP's residual env on it."""
    if label not in RESIDUAL_LEARNERS:
        return env_id, {}
    from rdmp_gym.envs.blackbox import RESIDUAL_ID

    return RESIDUAL_ID, {"env_id": env_id, "scale": RESIDUAL_LEARNERS[label][1]}


def run_sb3(env_id: str, label: str, seed: int, total: int, args: argparse.Namespace, folder: Path
            ) -> dict[str, Any]:
    """One PPO/SAC run (on the raw env, or on the residual env for :data:`RESIDUAL_LEARNERS`), evaluated at the
    env-step marks; checkpointed at every mark."""
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecNormalize

    torch.set_num_threads(1)
    began = time.perf_counter()
    algo = _algorithm(label)
    kind = {"ppo": PPO, "sac": SAC}[algo]
    keywords, normalize, n_envs = _sb3_kwargs(algo, env_id)
    partial = folder / f"{label}-{seed}.partial"
    state_path = partial / "state.json"
    make_id, make_kwargs = _sb3_env(env_id, label)
    venv = make_vec_env(make_id, n_envs=n_envs, seed=seed, env_kwargs=make_kwargs)
    resumed = state_path.is_file()
    if resumed:
        state = json.loads(state_path.read_text())
        if normalize:
            venv = VecNormalize.load(str(partial / "vecnormalize.pkl"), venv)
        model = kind.load(str(partial / "model.zip"), env=venv, device="cpu")
        if algo == "sac":
            model.load_replay_buffer(str(partial / "replay.pkl"))
    else:
        state = {"curve": [], "seconds": 0.0}
        if normalize:
            venv = VecNormalize(venv, gamma=keywords["gamma"])
        model = kind("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **keywords)
    normalizer = venv if normalize else None
    eval_env = gym.make(make_id, **make_kwargs)
    marks = [m for m in _marks(total) if m > (state["curve"][-1]["env_steps"] if state["curve"] else -1)]
    val_seeds, test_seeds = validation_seeds(args.eval_episodes), final_test_seeds(args.test_episodes)
    result: dict[str, Any] = {}

    def evaluate_mark(steps: int) -> None:
        state["curve"].append({"env_steps": steps,
                               "return": float(np.mean(evaluate_sb3(model, normalizer, eval_env, val_seeds)))})
        if steps >= total:
            result["test_returns"] = evaluate_sb3(model, normalizer, eval_env, test_seeds)
            return
        partial.mkdir(parents=True, exist_ok=True)
        model.save(str(partial / "model.zip"))
        if normalize:
            normalizer.save(str(partial / "vecnormalize.pkl"))
        if algo == "sac":
            model.save_replay_buffer(str(partial / "replay.pkl"))
        state["seconds"] += time.perf_counter() - clock[0]
        clock[0] = time.perf_counter()
        state_path.write_text(json.dumps(state))

    clock = [time.perf_counter()]

    class Marks(BaseCallback):
        def _on_step(self) -> bool:
            while marks and self.num_timesteps >= marks[0]:
                evaluate_mark(marks.pop(0))
            return "test_returns" not in result

    if marks and marks[0] == 0:
        evaluate_mark(marks.pop(0))
    if marks:
        model.learn(total_timesteps=total - model.num_timesteps + 10 * EPISODE_STEPS, callback=Marks(),
                    reset_num_timesteps=False)
    eval_env.close()
    venv.close()
    if "test_returns" not in result:
        raise RuntimeError(f"{algo}: the run ended at {model.num_timesteps} env steps without reaching {total}")
    model.save(str(folder / f"{label}-{seed}.zip"))     # the final policy (for the figures), without its buffer
    if normalize:
        normalizer.save(str(folder / f"{label}-{seed}.vecnormalize.pkl"))
    shutil.rmtree(partial, ignore_errors=True)         # finished: its JSON and the final policy hold everything
    return {"curve": state["curve"], "test_returns": result["test_returns"], "resumed": resumed,
            "made": {"id": make_id, **make_kwargs},
            "hyperparameters": ZOO[algo][env_id], "hyperparameter_source": _ZOO.format(algo),
            "seconds": round(state["seconds"] + time.perf_counter() - clock[0], 1),
            "wall_seconds_this_session": round(time.perf_counter() - began, 1)}


# ---------------------------------------------------------------------------------------------------- jobs
def _jobs(args: argparse.Namespace) -> list[tuple[str, str, int]]:
    """(env, learner, seed) in the order they run: per env the main learners seed by seed, then SAC seed by seed,
    alternating between the envs (so that an interrupted study has SAC seeds on both)."""
    if args.study != "main":    # seed by seed, alternating between the envs, so that a cut-short study has both
        return [(env_id, label, seed) for seed in range(args.seeds) for env_id in args.envs for label in args.learners]
    jobs = [(env_id, label, seed) for env_id in args.envs for seed in range(args.seeds) for label in args.learners]
    jobs += [(env_id, "sac", seed) for seed in range(args.sac_seeds) for env_id in args.envs
             if "sac" not in args.learners]
    return jobs


def _result_path(root: Path, env_id: str, label: str, seed: int) -> Path:
    return root / env_id / f"{label}-{seed}.json"


def run_job(env_id: str, label: str, seed: int, args: argparse.Namespace, root: Path) -> dict[str, Any]:
    folder = root / env_id
    folder.mkdir(parents=True, exist_ok=True)
    if label in LEARNERS:
        body = run_rhythmic(env_id, label, seed, args, folder)
        budget = args.updates * args.rollouts * EPISODE_STEPS
    else:
        budget = args.ppo_steps if _algorithm(label) == "ppo" else args.sac_steps
        body = run_sb3(env_id, label, seed, budget, args, folder)
    record = {"env": env_id, "learner": label, "seed": seed, "env_steps": budget,
              "final_return": float(np.mean(body["test_returns"])), **body,
              "validation_seeds": validation_seeds(args.eval_episodes).tolist(),
              "test_seeds": final_test_seeds(args.test_episodes).tolist(), "code": environment_record()}
    path = _result_path(root, env_id, label, seed)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(record, indent=1) + "\n")
    tmp.replace(path)
    return record


# ---------------------------------------------------------------------------------------------------- summary
def steps_to(curve: list[dict[str, Any]], threshold: float) -> int | None:
    """The first env-step mark whose validation return reaches ``threshold`` (None: never)."""
    return next((int(c["env_steps"]) for c in curve if c["return"] >= threshold), None)


def summarise(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per (env, learner): the IQM of the final test return over seeds with its 95 % interval, and the
    env steps to each threshold (median over the seeds that reach it, and how many do)."""
    rows = []
    for env_id in dict.fromkeys(r["env"] for r in runs):
        for label in dict.fromkeys(r["learner"] for r in runs if r["env"] == env_id):
            group = sorted((r for r in runs if r["env"] == env_id and r["learner"] == label), key=lambda r: r["seed"])
            finals = [r["final_return"] for r in group]
            reach = {}
            for threshold in THRESHOLDS.get(env_id, ()):
                steps = [s for s in (steps_to(r["curve"], threshold) for r in group) if s is not None]
                reach[f"{threshold:g}"] = {"reached": len(steps), "of": len(group),
                                          "median_env_steps": float(np.median(steps)) if steps else None}
            rows.append({"env": env_id, "learner": label, "seeds": [r["seed"] for r in group],
                         "env_steps": sorted({r["env_steps"] for r in group}),
                         "final_return": interval(np.asarray(finals)).to_dict(), "to_threshold": reach,
                         "seconds_per_run": float(np.median([r["seconds"] for r in group])),
                         "env_steps_used_median": float(np.median([r.get("env_steps_used", r["env_steps"])
                                                                   for r in group]))})
    return rows


def _curve_marks(group: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """The marks all runs share and ``[seeds, marks]`` returns there."""
    marks = sorted(set.intersection(*({c["env_steps"] for c in r["curve"]} for r in group)))
    values = np.array([[next(c["return"] for c in r["curve"] if c["env_steps"] == m) for m in marks] for r in group])
    return np.asarray(marks), values


def _thousands(steps: float | None) -> str:
    return "-" if steps is None else f"{steps / 1000:.0f}k"


def markdown(rows: list[dict[str, Any]], reference: list[dict[str, Any]]) -> str:
    lines = ["| env | learner | seeds | env steps | final return, IQM [95 % CI] | env steps to threshold "
             "(median; seeds reaching) |", "|---|---|---|---|---|---|"]
    for r in rows:
        f = r["final_return"]
        reach = "; ".join(f"{t}: {_thousands(e['median_env_steps'])} ({e['reached']}/{e['of']})"
                          for t, e in r["to_threshold"].items())
        steps = "/".join(f"{s / 1000:.0f}k" for s in r["env_steps"])
        if r["env_steps_used_median"] < min(r["env_steps"]):         # episodes that end early: the steps taken
            steps += f" (used {r['env_steps_used_median'] / 1000:.0f}k)"
        lines.append(f"| {r['env']} | `{r['learner']}` | {len(r['seeds'])} | {steps} | "
                     f"{f['estimate']:.1f} [{f['low']:.1f}, {f['high']:.1f}] | {reach} |")
    lines += ["", "| env | anchor | return | training env steps | source |", "|---|---|---|---|---|"]
    for a in reference:
        spread = f" +- {a['std']:.1f}" if a.get("std") is not None else ""
        value = "-" if a.get("return") is None else f"{a['return']:.1f}{spread}"
        if "interval" in a:
            value = f"{a['return']:.1f} [{a['interval'][0]:.1f}, {a['interval'][1]:.1f}] ({a['n']} seeds)"
        if "episodes_to_threshold" in a:
            value = "episodes to " + f"{a['threshold']:g}: " + ", ".join(
                f"{k} {v}" for k, v in a["episodes_to_threshold"].items())
        steps = "-" if a.get("env_steps") is None else f"{a['env_steps'] / 1e6:g}M" if a["env_steps"] else "0"
        if a.get("return") is None and "episodes_to_threshold" not in a:
            value = "not read here (see the JSON's note)"
        lines.append(f"| {a['env']} | {a['method']} | {value} | {steps} | {a.get('cite', a['source'])} |")
    return "\n".join(lines)


def oscillator_anchor(seeds: np.ndarray) -> dict[str, Any]:
    """Raffin et al.'s published Swimmer oscillator (their slides' code: q_des = sin(2 pi 0.62 t + phase), phases
    0 and 0.95 x 2 pi, PD 10 / 0.5) on Swimmer-v5, one episode per test seed: mean return."""
    env = gym.make("Swimmer-v5")
    base = env.unwrapped
    omega, phase = 2 * np.pi * 0.62, 2 * np.pi * np.array([0.0, 0.95])
    returns = []
    for seed in seeds:
        env.reset(seed=int(seed))
        total, done, t = 0.0, False, 0.0
        while not done:
            q, qd = base.data.qpos[-2:], base.data.qvel[-2:]
            action = np.clip(10.0 * (np.sin(omega * t + phase) - q) - 0.5 * qd, -1.0, 1.0)
            _, reward, terminated, truncated, _ = env.step(action)
            t += base.dt
            total += float(reward)
            done = terminated or truncated
        returns.append(total)
    env.close()
    return {"env": "Swimmer-v5", "method": "open-loop oscillator of Raffin et al. 2024, re-run here",
            "return": float(np.mean(returns)), "std": float(np.std(returns)), "env_steps": None,
            "note": f"{len(returns)} test contexts, mean +- std; the authors optimised the oscillator with CMA-ES",
            "source": _RAFFIN + "; parameters from the code on the authors' RLC 2024 slides "
                                "(https://araffin.github.io/slides/rlc24-open-loop-baseline), run by this script",
            "cite": "Raffin et al. 2024's slides, run here"}


def zero_action_reference(env_id: str, seeds: np.ndarray) -> dict[str, Any]:
    """The wrapper's default pattern (``a = 0``, the same gait with or without feedback) on ``seeds``."""
    from rdmp_gym.envs.blackbox import make_blackbox

    env = make_blackbox(env_id)
    returns = []
    for seed in seeds:
        env.reset(seed=int(seed))
        returns.append(float(env.step(np.zeros(env.action_space.shape, dtype=np.float32))[1]))
    env.close()
    return {"env": env_id, "method": "default pattern, a = 0 (no training)", "return": float(np.mean(returns)),
            "std": float(np.std(returns)), "env_steps": 0, "note": f"{len(returns)} test contexts, mean +- std",
            "source": "make_blackbox(env_id) with its default settings, run by this script", "cite": "run here"}


def study_references(args: argparse.Namespace) -> list[dict[str, Any]]:
    """Beside the feedback and the residual study: PPO/SAC at the same budget from ``locomotion.json``, the open-loop
    oscillator's CMA-ES runs from ``open_loop_oscillator.json`` and the default pattern's ``a = 0`` return (each where
    found)."""
    rows = []
    budget = args.updates * args.rollouts * EPISODE_STEPS
    study = COMMITTED / "locomotion.json"
    if study.is_file():
        for row in json.loads(study.read_text())["summary"]:
            if row["learner"] in SB3_ALGOS and row["env"] in args.envs and row["env_steps"] == [budget]:
                f = row["final_return"]
                rows.append({"env": row["env"], "method": f"{row['learner'].upper()} (raw env, RL Zoo settings)",
                             "return": f["estimate"], "interval": [f["low"], f["high"]], "n": f["n"],
                             "env_steps": budget, "source": "benchmarks/results/locomotion.json (IQM of the final "
                             "test return, 95 % CI)", "cite": "locomotion.json"})
    oscillator = COMMITTED / "open_loop_oscillator.json"
    if oscillator.is_file():
        for row in json.loads(oscillator.read_text())["rows"]:
            if row["env"] not in args.envs:
                continue
            label = "swing/stance split" if row["split"] else "one frequency"
            for key, what in (("final", "final mean"), ("best_test", "best candidate")):
                f = row[key]
                rows.append({"env": row["env"], "method": f"open-loop oscillator + CMA-ES ({label}), {what}",
                             "return": f["estimate"], "interval": [f["low"], f["high"]], "n": f["n"],
                             "env_steps": row["env_steps"], "source": "benchmarks/results/open_loop_oscillator.json "
                             "(IQM over seeds, 95 % CI)", "cite": "open_loop_oscillator.json"})
    rows += [anchor for anchor in ANCHORS if anchor["env"] in args.envs and anchor["env"] in OTHER_ENVS]
    seeds = final_test_seeds(args.test_episodes)
    rows += [zero_action_reference(env_id, seeds) for env_id in args.envs]
    return rows


def paired_differences(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per env and pair of :data:`PAIRS`: the learner's final test return less the baseline's on the same seed, the
    IQM of those differences with its 95 % interval and how many seeds gain."""
    rows = []
    for env_id in dict.fromkeys(r["env"] for r in runs):
        by = {(r["learner"], r["seed"]): r["final_return"] for r in runs if r["env"] == env_id}
        for learner, baseline in PAIRS:
            seeds = sorted(seed for (label, seed) in by if label == learner and (baseline, seed) in by)
            if not seeds:
                continue
            gains = np.array([by[learner, seed] - by[baseline, seed] for seed in seeds])
            rows.append({"env": env_id, "learner": learner, "baseline": baseline, "seeds": seeds,
                         "differences": gains.tolist(), "iqm_difference": interval(gains).to_dict(),
                         "seeds_gaining": int(np.sum(gains > 0))})
    return rows


def gather(args: argparse.Namespace, root: Path) -> dict[str, Any]:
    runs = [json.loads(p.read_text()) for env_id in ALL_ENVS for p in sorted((root / env_id).glob("*.json"))
            if (root / env_id).is_dir()]
    anchors = study_references(args) if args.study != "main" else \
        [*ANCHORS, oscillator_anchor(final_test_seeds(args.test_episodes))]
    settings = {key: value for key, value in vars(args).items() if key not in ("summary_only", "figures", "save")}
    settings.update({"thresholds": {k: list(v) for k, v in THRESHOLDS.items()}, "zoo": ZOO,
                     "zoo_source": {a: _ZOO.format(a) for a in SB3_ALGOS}, "cpus": os.cpu_count(),
                     "learners": {k: {"agent": a, "options": o, "wrapper": w} for k, (a, o, w) in LEARNERS.items()}})
    curves = {}
    for env_id in dict.fromkeys(r["env"] for r in runs):
        for label in dict.fromkeys(r["learner"] for r in runs if r["env"] == env_id):
            marks, values = _curve_marks([r for r in runs if r["env"] == env_id and r["learner"] == label])
            curves[f"{env_id}/{label}"] = [{"env_steps": int(m), **interval(values[:, i]).to_dict()}
                                          for i, m in enumerate(marks)]
    document = {"settings": settings, "summary": summarise(runs), "curves": curves, "anchors": anchors}
    if args.study in ("feedback", "other"):
        document["paired"] = paired_differences(runs)
    return {**document, "runs": runs}


# ---------------------------------------------------------------------------------------------------- figures
def plot_curves(document: dict[str, Any], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    envs = list(dict.fromkeys(key.split("/")[0] for key in document["curves"]))
    figure, axes = plt.subplots(1, len(envs), figsize=(6.5 * len(envs), 4.2), squeeze=False)
    labels = list(dict.fromkeys(key.split("/")[1] for key in document["curves"]))
    for axis, env_id in zip(axes[0], envs, strict=True):
        for label in labels:
            points = document["curves"].get(f"{env_id}/{label}")
            if not points:
                continue
            colour = f"C{labels.index(label)}"
            x = np.array([p["env_steps"] for p in points]) / 1000
            n = points[0]["n"]
            axis.plot(x, [p["estimate"] for p in points], color=colour, label=f"{label} ({n} seeds)",
                      marker="o" if len(x) < 5 else None, ms=3)
            axis.fill_between(x, [p["low"] for p in points], [p["high"] for p in points], color=colour, alpha=0.15)
        for threshold, style in zip(THRESHOLDS.get(env_id, ()), (":", "--"), strict=False):
            axis.axhline(threshold, color="k", ls=style, lw=0.8, label=f"threshold {threshold:g}")
        axis.set_title(f"{env_id}: validation return (IQM over seeds, 95 % CI)", fontsize=9)
        axis.set_xlabel("env steps (thousands)")
        axis.set_ylabel("return")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


#: the cameras of the films: both models' tracking camera
CAMERAS: dict[str, dict[str, Any]] = {env_id: {"camera_name": "track"} for env_id in ALL_ENVS}
FILM_SECONDS = 5.0        # the video: the episode's last 5 simulated seconds, in real time


class _FrameGrabber(gym.Wrapper):
    """Keeps ``(step, frame)`` after each env step whose index is in ``steps``."""

    def __init__(self, env: gym.Env, steps: set[int]) -> None:
        super().__init__(env)
        self.steps, self.count, self.frames = steps, 0, []

    def step(self, action: Any) -> Any:
        result = self.env.step(action)
        if self.count in self.steps:
            self.frames.append((self.count, self.env.render()))
        self.count += 1
        return result


def _best_run(document: dict[str, Any], env_id: str) -> dict[str, Any]:
    """The final policy to film: the learner with the highest IQM (not the random control), its best seed."""
    rows = [r for r in document["summary"] if r["env"] == env_id and r["learner"] != "random"
            and (r["learner"] in LEARNERS or r["learner"] in RESIDUAL_LEARNERS)]
    best = max(rows, key=lambda r: r["final_return"]["estimate"])
    return max((r for r in document["runs"] if r["env"] == env_id and r["learner"] == best["learner"]),
               key=lambda r: r["final_return"])


def _rhythmic_film(document: dict[str, Any], root: Path, run: dict[str, Any], seed: int
                   ) -> tuple[list[tuple[int, np.ndarray]], float, float, float]:
    """(frames of the last :data:`FILM_SECONDS` s, return, dt, period) of a rhythmic run's final policy."""
    from rdmp_gym.agents.runs import RunDirectory
    from rdmp_gym.envs.blackbox import make_blackbox

    env_id, label = run["env"], run["learner"]
    config = _rhythmic_config(env_id, label, run["seed"], argparse.Namespace(
        **{k: document["settings"][k] for k in ("updates", "rollouts", "eval_episodes")}))
    env = make_blackbox(env_id, render_mode="rgb_array", env_kwargs={"width": 320, "height": 240, **CAMERAS[env_id]},
                        **LEARNERS[label][2])
    observation, _ = env.reset(seed=seed)
    action = trained_actions(RunDirectory(root / env_id / f"{label}-{run['seed']}"), config, "last",
                             observation[None], env.action_space.shape[0])[0]
    window = round(FILM_SECONDS / env.dt)
    grabber = env.env = _FrameGrabber(env.env, set(range(env.n_steps - window, env.n_steps)))
    env.reset(seed=seed)
    _, episode_return, _, _, _ = env.step(np.asarray(action, dtype=np.float32))
    env.close()
    return grabber.frames, float(episode_return), env.dt, env.dmp.period


def _residual_film(document: dict[str, Any], root: Path, run: dict[str, Any], seed: int
                   ) -> tuple[list[tuple[int, np.ndarray]], float, float, float]:
    """(frames of the last :data:`FILM_SECONDS` s, return, dt, period) of a residual run's final deterministic
    policy."""
    from rdmp_gym.envs.blackbox import RESIDUAL_ID
    from stable_baselines3 import PPO, SAC

    env_id, label = run["env"], run["learner"]
    algo, scale = RESIDUAL_LEARNERS[label]
    kind = {"ppo": PPO, "sac": SAC}[algo]
    model = kind.load(str(root / env_id / f"{label}-{run['seed']}.zip"), device="cpu")
    env = gym.make(RESIDUAL_ID, env_id=env_id, scale=scale, render_mode="rgb_array",
                   env_kwargs={"width": 320, "height": 240, **CAMERAS[env_id]})
    box = env.unwrapped.blackbox
    window = round(FILM_SECONDS / box.dt)
    observation, _ = env.reset(seed=seed)
    frames, total, done, k = [], 0.0, False, 0
    while not done:
        action, _ = model.predict(observation, deterministic=True)
        observation, reward, terminated, truncated, _ = env.step(action)
        total, done = total + float(reward), terminated or truncated
        if k >= box.n_steps - window:
            frames.append((k, env.render()))
        k += 1
    env.close()
    return frames, total, box.dt, box.dmp.period


def gait_film(document: dict[str, Any], root: Path, env_id: str, strip: Path, video: Path, frames: int = 6
              ) -> dict[str, Any]:
    """The best run's final policy on the first test context: ``frames`` frames over the last cycle, or the last
    ``frames`` steps where a cycle is shorter (``strip``, a PNG), and the last :data:`FILM_SECONDS` s in real time
    (``video``, an MP4)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from rdmp_gym.envs.recording import write_video

    run = _best_run(document, env_id)
    film = _residual_film if run["learner"] in RESIDUAL_LEARNERS else _rhythmic_film
    shots, episode_return, dt, period = film(document, root, run, int(final_test_seeds(1)[0]))
    write_video([image for _, image in shots], video, fps=1.0 / dt)
    cycle = shots[-max(round(period / dt), frames):]          # the last cycle (at least ``frames`` steps)
    picks = np.linspace(0, len(cycle), frames, endpoint=False).astype(int)
    figure, axes = plt.subplots(1, frames, figsize=(2.6 * frames, 2.3))
    for axis, pick in zip(np.atleast_1d(axes), picks, strict=True):
        step, image = cycle[pick]
        axis.imshow(image)
        axis.set_title(f"t = {(step + 1) * dt:.2f} s", fontsize=8)
        axis.set_axis_off()
    figure.suptitle(f"{env_id}, {run['learner']} seed {run['seed']}: final policy, return {episode_return:.0f} "
                    f"(test context 0)", fontsize=9)
    figure.tight_layout()
    figure.savefig(strip, dpi=100)
    plt.close(figure)
    return {"env": env_id, "learner": run["learner"], "seed": run["seed"], "return": episode_return,
            "strip": strip.name, "video": video.name}


def draw_figures(args: argparse.Namespace, root: Path, out: Path) -> None:
    """The study's learning curves and, per env, the film of its best run (under docs/assets with ``--save``)."""
    stem = {"main": "locomotion"}.get(args.study, f"locomotion_{args.study}")
    document = json.loads((out / f"{stem}.json").read_text())
    plot_curves(document, out / f"{stem}.png")
    assets = ROOT / "docs" / "assets" if args.save else out
    if args.save:
        (assets / f"{stem}.png").write_bytes((out / f"{stem}.png").read_bytes())
    suffix = "" if args.study == "main" else f"_{args.study}"
    for env_id in dict.fromkeys(r["env"] for r in document["runs"]):
        name = env_id.split("-")[0].lower()
        try:
            made = gait_film(document, root, env_id, assets / f"{name}_gait{suffix}.png",
                             assets / f"{name}_gait{suffix}.mp4")
        except FileNotFoundError as error:        # the runs' folders are not committed: train (or copy) them first
            print(f"{env_id}: no film ({error})")
            continue
        print(f"film: {made}")


# ---------------------------------------------------------------------------------------------------- main
def main() -> None:
    import torch

    torch.set_num_threads(1)
    args = _parse()
    root = Path(args.run_dir)
    out = results_dir(args.save)
    if args.figures:
        draw_figures(args, root, out)
        return
    name = {"main": "locomotion.json"}.get(args.study, f"locomotion_{args.study}.json")
    if not args.summary_only:
        for env_id, label, seed in _jobs(args):
            path = _result_path(root, env_id, label, seed)
            if path.is_file():
                continue
            began = time.perf_counter()
            record = run_job(env_id, label, seed, args, root)
            print(f"{env_id} {label} seed {seed}: final return {record['final_return']:.1f} "
                  f"({time.perf_counter() - began:.0f} s)", flush=True)
            document = gather(args, root)
            (out / name).write_text(json.dumps(document, indent=1) + "\n")
    document = gather(args, root)
    (out / name).write_text(json.dumps(document, indent=1) + "\n")
    print(markdown(document["summary"], document["anchors"]))
    print(f"wrote {out / name}")


if __name__ == "__main__":
    main()

"""Sample efficiency: step-based SAC (``ArmarWipeStep-v1``, residual coupling on the DMP) against episodic PI²
(``ArmarWipe-v1``, DMP parameters) on the same fixed contexts (with the cup where the context has one), by the
number of episodes (one episode = one DMP rollout = ``n_steps`` control steps for SAC).

For every seed the context of ``ArmarWipe`` reset with that seed is fixed for training and evaluation.
PI² evaluates its mean after every update; SAC is evaluated (deterministic policy) every ``--every``
episodes. Prints a table; writes ``step.json`` (``runs/benchmarks/``, or ``benchmarks/results/`` with
``--save``).

    python benchmarks/bench_step.py --seeds 2 --episodes 20 --save
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import torch
from output import add_save_argument, results_dir
from rdmp_gym.agents.tasks import ResetOptions
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs import ENV_ID, STEP_ID
from stable_baselines3 import SAC
from stable_baselines3.common.logger import Logger


def _evaluate_sac(model: SAC, env: gym.Env) -> tuple[float, float]:
    obs, _ = env.reset()
    total, done, info = 0.0, False, {}
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        done = terminated or truncated
    return total, info["coverage"]


def _sac(seed: int, options: dict, args: argparse.Namespace) -> list[dict]:
    env = ResetOptions(gym.make(STEP_ID, n_periods=args.n_periods), options)
    probe = ResetOptions(gym.make(STEP_ID, n_periods=args.n_periods), options)
    steps = env.unwrapped.task.n_steps
    model = SAC("MlpPolicy", env, learning_starts=steps, seed=seed, device="cpu", verbose=0)
    model.set_logger(Logger(None, []))
    curve = []
    for episodes in range(0, args.episodes + 1, args.every):
        if episodes:
            model.learn(args.every * steps, reset_num_timesteps=False)
        ret, coverage = _evaluate_sac(model, probe)
        curve.append({"episodes": episodes, "return": ret, "coverage": coverage})
    env.close()
    probe.close()
    return curve


def _pi2(seed: int, options: dict, args: argparse.Namespace, scratch: Path) -> list[dict]:
    config = TrainConfig(agent="pi2", updates=args.episodes // args.rollouts, rollouts=args.rollouts, seed=seed,
                         workers=1, env_id=ENV_ID, env_kwargs={"n_periods": args.n_periods},
                         reset_options=options, eval_episodes=1)
    run = train(config, scratch / f"pi2-{seed}")
    return [{"episodes": r["episodes"], "return": r["eval_return_mean"], "coverage": r["eval_coverage"]}
            for r in run.read_log()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2, help="seeds (and fixed contexts) 0..n-1")
    parser.add_argument("--episodes", type=int, default=30, help="training episodes per learner")
    parser.add_argument("--rollouts", type=int, default=10, help="PI² episodes per update")
    parser.add_argument("--every", type=int, default=10, help="SAC evaluation interval (episodes)")
    parser.add_argument("--n-periods", type=float, default=2.0, help="wiping periods after the transient")
    add_save_argument(parser)
    args = parser.parse_args()
    torch.set_num_threads(1)
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for seed in range(args.seeds):
            probe = gym.make(ENV_ID, n_periods=args.n_periods)
            options = {"context": probe.reset(seed=seed)[1]["context"].tolist()}
            probe.close()
            for learner in ("pi2", "sac"):
                began = time.perf_counter()
                curve = (_pi2(seed, options, args, Path(scratch)) if learner == "pi2"
                         else _sac(seed, options, args))
                rows.append({"learner": learner, "seed": seed, "curve": curve,
                             "wall_s": round(time.perf_counter() - began, 1)})
                print(f"seed {seed} {learner}: " + ", ".join(f"{p['episodes']} ep {p['return']:.3f}/"
                                                              f"{p['coverage']:.3f}" for p in curve))
    print(f"\n{'learner':8s} {'episodes':>8s} {'return (mean over seeds)':>26s} {'coverage':>9s}")
    for learner in ("pi2", "sac"):
        curves = [row["curve"] for row in rows if row["learner"] == learner]
        for index, point in enumerate(curves[0]):
            returns = [c[index]["return"] for c in curves if index < len(c)]
            coverage = [c[index]["coverage"] for c in curves if index < len(c)]
            print(f"{learner:8s} {point['episodes']:8d} {np.mean(returns):26.3f} {np.mean(coverage):9.3f}")
    out = results_dir(args.save) / "step.json"
    out.write_text(json.dumps({"settings": vars(args), "runs": rows}, indent=1) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

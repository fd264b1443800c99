"""Step-based RL on a task's step twin, under the episodic learners' protocol: the same budget in episodes, the same
validation and test contexts (reset seeds of ``rdmp_gym.agents.protocol``), so its rows stand beside
``bench_agents.py``'s on the episodic env.

For every agent (stable-baselines3 ``ppo`` or ``sac``, default settings, ``MlpPolicy``) and seed: training on random
contexts (the env's own stream after ``reset(seed=seed)``) for ``--episodes`` episodes of the twin
(``episodes x n_steps`` env steps), the deterministic policy evaluated on the validation contexts every
``--eval-every`` episodes (the learning curve), then the final policy once on the test contexts, which no run
trains or selects on. Per agent: the interquartile mean over seeds of each seed's test success rate with a 95 %
bootstrap interval, the mean return and the failure causes. Every finished run is cached in ``--run-dir`` (a rerun
skips it), so a long study resumes where it stopped.

    # PPO on both robots' drumming twins (150 episodes = 150,000 env steps per run):
    python benchmarks/bench_step_twin.py --env-id rdmp_gym/ArmarDrumStep-v1 --agents ppo --seeds 10 \\
        --episodes 150 --run-dir runs/step_twin_armar --name step_twin_drum_armar --save
"""

from __future__ import annotations

import argparse
import json
import os
import time
from collections import Counter
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import gymnasium as gym
import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the ids)
import torch
from output import add_save_argument, results_dir
from rdmp_gym.agents.protocol import final_test_seeds, interval, validation_seeds
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.logger import Logger

AGENTS = {"ppo": PPO, "sac": SAC}


def _parse(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--env-id", required=True, help="a step-based env id (e.g. rdmp_gym/ArmarDrumStep-v1)")
    parser.add_argument("--agents", nargs="+", default=["ppo"], choices=sorted(AGENTS))
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--episodes", type=int, default=150, help="training episodes per run")
    parser.add_argument("--eval-every", type=int, default=50, help="episodes between validation evaluations")
    parser.add_argument("--val-contexts", type=int, default=5)
    parser.add_argument("--test-contexts", type=int, default=20)
    parser.add_argument("--run-dir", default="runs/step_twin", help="cache of finished runs (one JSON per run)")
    parser.add_argument("--name", default="step_twin")
    add_save_argument(parser)
    args = parser.parse_args(argv)
    for name in ("seeds", "episodes", "eval_every", "val_contexts", "test_contexts"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')}: expected an integer >= 1, got {getattr(args, name)}")
    return args


def rollout(model: PPO | SAC, env: gym.Env, seed: int) -> dict:
    """One deterministic episode of ``model`` in the context of reset seed ``seed``: return, success, causes."""
    observation, _ = env.reset(seed=int(seed))
    total, done, info = 0.0, False, {}
    while not done:
        action, _ = model.predict(observation, deterministic=True)
        observation, reward, terminated, truncated, info = env.step(action)
        total += float(reward)
        done = terminated or truncated
    return {"return": total, "success": bool(info.get("is_success", False)),
            "causes": list(info.get("failure_causes", ()))}


def _scores(model: PPO | SAC, env: gym.Env, seeds: np.ndarray) -> dict:
    episodes = [rollout(model, env, seed) for seed in seeds]
    return {"success": [e["success"] for e in episodes], "return": [e["return"] for e in episodes],
            "causes": [e["causes"] for e in episodes]}


def episode_steps(env: gym.Env) -> int:
    """Control steps of one episode of a step twin (its episodic face's, or the time limit's)."""
    inner = env.unwrapped
    for face in (getattr(inner, "episodic", None), getattr(inner, "task", None)):
        if hasattr(face, "n_steps"):
            return int(face.n_steps)
    limit = getattr(env.spec, "max_episode_steps", None)
    if limit is None:
        raise ValueError("env_id: the env says neither its episode's steps nor a time limit")
    return int(limit)


def train_run(agent: str, seed: int, args: argparse.Namespace) -> dict:
    """One training run (see the module docstring); its curve and test scores."""
    torch.manual_seed(seed)
    env, probe = gym.make(args.env_id), gym.make(args.env_id)
    env.reset(seed=seed)
    steps = episode_steps(env)
    extra = {"learning_starts": steps} if agent == "sac" else {}
    model = AGENTS[agent]("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **extra)
    model.set_logger(Logger(None, []))
    start, curve, done = time.perf_counter(), [], 0
    validation = validation_seeds(args.val_contexts)
    while True:
        scores = _scores(model, probe, validation)
        curve.append({"episodes": done, "env_steps": done * steps, "val_success": float(np.mean(scores["success"])),
                      "val_return": float(np.mean(scores["return"]))})
        if done >= args.episodes:
            break
        chunk = min(args.eval_every, args.episodes - done)
        model.learn(chunk * steps, reset_num_timesteps=False)
        done += chunk
    test = _scores(model, probe, final_test_seeds(args.test_contexts))
    env.close()
    probe.close()
    return {"agent": agent, "seed": seed, "episodes": args.episodes, "env_steps": args.episodes * steps,
            "seconds": round(time.perf_counter() - start, 1), "curve": curve, "test": test}


def _cached(path: Path, args: argparse.Namespace) -> dict | None:
    if not path.is_file():
        return None
    run = json.loads(path.read_text())
    same = (run.get("env_id") == args.env_id and run["episodes"] == args.episodes
            and len(run["test"]["success"]) == args.test_contexts and len(run["curve"]) > 0)
    return run if same else None


def summary(runs: list[dict]) -> list[dict]:
    """Per agent: test success (IQM over seeds, 95 % interval), mean test return, failure causes counted."""
    rows = []
    for agent in dict.fromkeys(run["agent"] for run in runs):
        mine = [run for run in runs if run["agent"] == agent]
        success = [float(np.mean(run["test"]["success"])) for run in mine]
        causes = Counter(cause for run in mine for episode in run["test"]["causes"] for cause in episode)
        rows.append({"agent": agent, "seeds": len(mine), "success": vars(interval(success)),
                     "return_mean": float(np.mean([np.mean(run["test"]["return"]) for run in mine])),
                     "causes": dict(causes.most_common()),
                     "env_steps": mine[0]["env_steps"], "seconds": float(np.sum([run["seconds"] for run in mine]))})
    return rows


def main(argv: list[str] | None = None) -> None:
    args = _parse(argv)
    cache = Path(args.run_dir)
    cache.mkdir(parents=True, exist_ok=True)
    runs = []
    for agent in args.agents:
        for seed in range(args.seeds):
            path = cache / f"{agent}-{seed}.json"
            run = _cached(path, args)
            if run is None:
                run = {**train_run(agent, seed, args), "env_id": args.env_id}
                path.write_text(json.dumps(run))
            runs.append(run)
            print(f"{agent} seed {seed}: test success {np.mean(run['test']['success']):.2f} ({run['seconds']:.0f} s)",
                  flush=True)
    rows = summary(runs)
    settings = {key: value for key, value in vars(args).items() if key != "save"}
    settings["test_seeds"] = final_test_seeds(args.test_contexts).tolist()
    out = results_dir(args.save) / f"{args.name}.json"
    out.write_text(json.dumps({"settings": settings, "summary": rows, "runs": runs}, indent=1) + "\n")
    print("| agent | seeds | test success (IQM, 95 % CI) | return | env steps | causes |")
    print("|---|---|---|---|---|---|")
    for row in rows:
        s = row["success"]
        print(f"| {row['agent']} | {row['seeds']} | {s['estimate']:.2f} [{s['low']:.2f}, {s['high']:.2f}] | "
              f"{row['return_mean']:.2f} | {row['env_steps']} | {row['causes']} |")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

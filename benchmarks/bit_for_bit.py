"""Digests of the numbers the package publishes, to check that a refactor changes none of them bit for bit.

Each entry is a SHA-256 of the exact bytes of a result: the fitted DMPs of the built-in demonstrations (the
library's defaults and the settings the environments pin), episodic returns and infos of the published task
versions (v1, v2, v2 with the cup clearance, v3 on both robots, drumming on both robots, the step twins) on fixed
reset seeds and actions, and short learner runs (a few updates of every learner, one worker).

    python benchmarks/bit_for_bit.py --out runs/bit_for_bit.json            # write the digests
    python benchmarks/bit_for_bit.py --check benchmarks/results/bit_for_bit.json   # compare, exit 1 on a change

``--only fits,envs,learners`` restricts the groups (the learners take a few minutes on 2 cores).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

GROUPS = ("fits", "envs", "learners")
RESET_SEEDS = (7000, 7003, 7010, 7021)
LEARNERS = ("pi2", "cpi2", "creps", "cmaes", "bbrl")
#: the log columns a learner run is compared on: the counters, the returns, success and validity of the rollouts and
#: of the policy on the validation contexts, and the wiping task's coverage (columns a refactor may add or rename
#: beside them do not change the digest)
LOG_KEYS = ("update", "episodes", "exploration", "return_mean", "return_best", "success", "valid", "coverage",
            "eval_return_mean", "eval_return_best", "eval_success", "eval_valid", "eval_coverage", "best_eval_return")


def _digest(*arrays: Any) -> str:
    h = hashlib.sha256()
    for value in arrays:
        h.update(np.ascontiguousarray(np.asarray(value, dtype=np.float64)).tobytes())
    return h.hexdigest()[:16]


def _info_numbers(info: dict) -> list[float]:
    keys = sorted(k for k, v in info.items() if isinstance(v, (int, float, np.floating, np.integer, bool)))
    return [float(info[k]) for k in keys] + [float(v) for k in sorted(info.get("reward_terms", {}))
                                             for v in [info["reward_terms"][k]]]


def fits() -> dict[str, str]:
    """The DMPs fitted to the four built-in demonstrations, with the library's defaults and the envs' settings."""
    from rdmp_gym import RhythmicDMP, wiping_demonstration

    out = {}
    for style in (1, 2, 3, 4):
        demo = wiping_demonstration(style=style, rng=0)
        dmp = RhythmicDMP.fit(demo)
        out[f"fit/default/style{style}"] = _digest(dmp.rollout(demo.t))
    import rdmp_gym.envs.tasks.wiping.task as wipe_env

    for style in (1, 2):
        dmp = wipe_env._fit_style(style, 40, 40, "trajectory")
        out[f"fit/env/style{style}"] = _digest(dmp.rollout(np.arange(0, 12, 0.01)))
    return out


def _episodes(env_id: str, **kwargs: Any) -> str:
    import gymnasium as gym

    env = gym.make(env_id, **kwargs)
    numbers = []
    rng = np.random.default_rng(0)
    for seed in RESET_SEEDS:
        for scale in (0.0, 0.3):
            obs, _ = env.reset(seed=seed)
            action = scale * rng.uniform(-1, 1, env.action_space.shape)
            _, reward, _, _, info = env.step(action.astype(np.float32))
            numbers += [reward, *obs, *_info_numbers(info)]
    env.close()
    return _digest(numbers)


def _step_episodes(env_id: str) -> str:
    import gymnasium as gym

    env = gym.make(env_id)
    numbers = []
    for seed in RESET_SEEDS[:2]:
        obs, _ = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        done = False
        total = 0.0
        while not done:
            obs, reward, terminated, truncated, info = env.step(0.3 * rng.uniform(-1, 1, 3))
            total += reward
            done = terminated or truncated
        numbers += [total, *obs, *_info_numbers(info)]
    env.close()
    return _digest(numbers)


def envs() -> dict[str, str]:
    """Returns, observations and info figures of the published task versions."""
    import rdmp_gym.envs  # noqa: F401  (registers the ids)

    return {"env/v1": _episodes("rdmp_gym/ArmarWipe-v1"),
            "env/v2": _episodes("rdmp_gym/ArmarWipe-v2"),
            "env/v2_clearance": _episodes("rdmp_gym/ArmarWipe-v2", cup_clearance=0.01),
            "env/step_v1": _step_episodes("rdmp_gym/ArmarWipeStep-v1"),
            "env/step_v2": _step_episodes("rdmp_gym/ArmarWipeStep-v2"),
            "env/v3": _episodes("rdmp_gym/ArmarWipe-v3"),
            "env/panda_v3": _episodes("rdmp_gym/PandaWipe-v3"),
            "env/step_v3": _step_episodes("rdmp_gym/ArmarWipeStep-v3"),
            "env/panda_step_v3": _step_episodes("rdmp_gym/PandaWipeStep-v3"),
            "env/drum": _episodes("rdmp_gym/ArmarDrum-v1"),
            "env/panda_drum": _episodes("rdmp_gym/PandaDrum-v1"),
            "env/drum_step": _step_episodes("rdmp_gym/ArmarDrumStep-v1"),
            "env/panda_drum_step": _step_episodes("rdmp_gym/PandaDrumStep-v1")}


def learners() -> dict[str, str]:
    """Three updates of every learner on ArmarWipe-v2 (one worker, seed 0): the saved state's numbers."""
    from rdmp_gym.agents.learners import CONTEXTUAL
    from rdmp_gym.agents.training import TrainConfig, train

    out = {}
    for agent in LEARNERS:
        with tempfile.TemporaryDirectory() as tmp:
            config = TrainConfig(agent=agent, updates=3, rollouts=6, seed=0, workers=1,
                                 env_id="rdmp_gym/ArmarWipe-v2", eval_episodes=2, eval_every=3,
                                 shared_context=agent not in CONTEXTUAL)
            train(config, Path(tmp) / "run")
            rows = [json.loads(line) for line in (Path(tmp) / "run" / "log.jsonl").read_text().splitlines()]
            numbers = [float(row[key]) for row in rows for key in LOG_KEYS if row.get(key) is not None]
            out[f"learner/{agent}"] = _digest(numbers)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, help="write the digests to this JSON file")
    parser.add_argument("--check", type=Path, help="compare with the digests in this JSON file")
    parser.add_argument("--only", default=",".join(GROUPS), help="comma-separated groups: " + ", ".join(GROUPS))
    args = parser.parse_args(argv)
    chosen = [g for g in args.only.split(",") if g]
    unknown = set(chosen) - set(GROUPS)
    if unknown:
        parser.error(f"--only: unknown groups {sorted(unknown)}")
    digests: dict[str, str] = {}
    for group in chosen:
        digests.update(globals()[group]())
        print(f"{group}: done", flush=True)
        if args.out:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(json.dumps(digests, indent=1) + "\n")
    for key, value in digests.items():
        print(f"{key:28s} {value}")
    if args.check:
        expected = json.loads(args.check.read_text())
        changed = [k for k, v in digests.items() if k in expected and expected[k] != v]
        missing = [k for k in digests if k not in expected]
        if missing:
            print("not in the baseline: " + ", ".join(missing))
        print("changed: " + (", ".join(changed) if changed else "none"))
        return 1 if changed else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())

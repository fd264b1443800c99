"""Per-step credit against episode credit in ``bbrl`` on a toy where one segment of the movement matters and the
context decides which.

The toy (no simulation): ``n`` action dimensions, dimension ``i`` acts at control step ``i`` only (an identity
activation, the case most favourable to per-step credit). A context ``s ~ U[-1, 1]`` decides which half of the
movement is judged: the first half where ``s > 0``, the second half otherwise. The cost of step ``i`` is
``(a_i - 0.4 - 0.3 s - o_i)^2`` where its half is judged, 0 elsewhere; the episode cost is their sum. Two targets:
``flat`` (``o = 0``: every dimension wants the same value, a shape that ``bbrl``'s smooth exploration, correlated
between neighbouring dimensions, already searches well) and ``rough`` (``o_i`` a fixed draw of N(0, 0.3²) per
dimension: a shape the smooth exploration does not give). The learner starts at ``a = 0`` and must learn a
context-dependent mean for each half.

Compared per seed (same contexts, same seeds): ``credit="step"`` (each dimension judged by the cost-to-go from when it
acts) and ``credit="episode"``, each with the context baseline as the learner has it (a ridge fit on the context),
with the network baseline (``baseline="network"``), and with antithetic pairs (two rollouts per context, judged
against their pair's mean: an exact baseline of the context); and the random-return control. Reported: the
interquartile mean over seeds of the held-out loss after the updates, with a 95 % bootstrap interval.

    python benchmarks/bench_credit_toy.py --save         # 10 seeds, about 6 CPU minutes
    python benchmarks/bench_credit_toy.py --rough 0.5 --name credit_toy_rough0.5 --save   # rougher exploration
"""

from __future__ import annotations

import argparse
import json
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import torch
from output import add_save_argument, results_dir
from rdmp_gym.agents.learners import EpisodeBatch, SearchSpace, make_learner
from rdmp_gym.agents.protocol import interval

#: condition -> (bbrl options, antithetic pairs of contexts, random returns)
CONDITIONS: dict[str, tuple[dict, bool, bool]] = {
    "step": ({"credit": "step"}, False, False),
    "episode": ({"credit": "episode"}, False, False),
    "step, network baseline": ({"credit": "step", "baseline": "network"}, False, False),
    "episode, network baseline": ({"credit": "episode", "baseline": "network"}, False, False),
    "step, antithetic pairs": ({"credit": "step", "antithetic": True}, True, False),
    "episode, antithetic pairs": ({"credit": "episode", "antithetic": True}, True, False),
    "random returns": ({"credit": "episode"}, False, True),
}


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dims", type=int, default=32, help="action dimensions = control steps (even)")
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--updates", type=int, default=30)
    parser.add_argument("--rollouts", type=int, default=10, help="rollouts per update (even)")
    parser.add_argument("--rough", type=float, default=None,
                        help="bbrl's share of independent (not smooth) exploration (default: bbrl's own)")
    parser.add_argument("--name", default="credit_toy", help="the results file's name (.json)")
    add_save_argument(parser)
    args = parser.parse_args()
    if args.dims < 2 or args.dims % 2 or args.rollouts < 2 or args.rollouts % 2:
        parser.error("--dims and --rollouts: expected even integers >= 2")
    return args


def judged(contexts: np.ndarray, n: int) -> np.ndarray:
    """``[k, n]`` bool: the dimensions whose step is judged in each context ``[k, 1]``."""
    first = (contexts[:, 0] > 0)[:, None]
    return np.where(np.arange(n) < n // 2, first, ~first)


TARGETS = ("flat", "rough")


def offsets(target: str, n: int) -> np.ndarray:
    """``[n]`` the per-dimension part ``o`` of the target (the same for every seed)."""
    return np.zeros(n) if target == "flat" else 0.3 * np.random.default_rng(7).standard_normal(n)


def cost_traces(actions: np.ndarray, contexts: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """``[k, n]`` the per-step costs of ``actions [k, n]`` in ``contexts [k, 1]``."""
    n = actions.shape[1]
    return judged(contexts, n) * (actions - (0.4 + 0.3 * contexts + offset)) ** 2


def run(target: str, condition: str, seed: int, args: argparse.Namespace) -> dict:
    """One learner on the toy: the held-out loss before and after, and the last update's KL."""
    options, paired, random_returns = CONDITIONS[condition]
    options = options if args.rough is None else {**options, "rough": args.rough}
    n = args.dims
    offset = offsets(target, n)
    space = SearchSpace({"periodic": slice(0, n)}, 1, np.zeros(1), np.ones(1), time_weights=np.eye(n))
    learner = make_learner("bbrl", np.zeros(n), args.rollouts, np.random.default_rng(seed), options, space=space)
    rng = np.random.default_rng(1000 + seed)
    held_out = rng.uniform(-1, 1, (200, 1))

    def loss() -> float:
        return float(np.mean(np.sum(cost_traces(learner.policy_actions(held_out), held_out, offset), axis=1)))

    before = loss()
    for _ in range(args.updates):
        contexts = rng.uniform(-1, 1, (args.rollouts // 2 if paired else args.rollouts, 1))
        contexts = np.repeat(contexts, 2, axis=0) if paired else contexts
        actions = learner.ask(contexts)
        traces = cost_traces(actions, contexts, offset)
        returns = rng.standard_normal(len(actions)) if random_returns else -traces.sum(axis=1)
        k = len(actions)
        learner.tell(EpisodeBatch(actions, returns, traces, np.full(k, np.nan), np.full(k, np.nan),
                                  np.ones(k, dtype=bool), np.zeros(k, dtype=np.int64)))
    return {"target": target, "condition": condition, "seed": seed, "before": before, "after": loss(),
            "last_kl": learner.last_kl}


def main() -> None:
    args = _parse()
    torch.set_num_threads(1)
    runs = [run(target, condition, seed, args) for target in TARGETS for condition in CONDITIONS
            for seed in range(args.seeds)]
    summary = []
    print(f"| target | condition | held-out loss after {args.updates} updates, IQM [95 % CI] | seeds where `step` "
          f"beats `episode` |")
    print("|---|---|---|---|")
    for target in TARGETS:
        def losses(condition: str, target: str = target) -> np.ndarray:
            return np.array([r["after"] for r in runs if r["target"] == target and r["condition"] == condition])

        for condition in CONDITIONS:
            after = losses(condition)
            wins = int(np.sum(after < losses(condition.replace("step", "episode")))) \
                if condition.startswith("step") else None
            estimate = interval(after)
            summary.append({"target": target, "condition": condition, "after": estimate.to_dict(),
                            "wins_over_episode": wins})
            text = f"{estimate.estimate:.3f} [{estimate.low:.3f}, {estimate.high:.3f}]"
            print(f"| {target} | {condition} | {text} | {'' if wins is None else f'{wins}/{args.seeds}'} |")
        start = np.mean([r["before"] for r in runs if r["target"] == target])
        print(f"| {target} | the start (a = 0) | {start:.3f} | |")
    path = results_dir(args.save) / f"{args.name}.json"
    path.write_text(json.dumps({"settings": {k: v for k, v in vars(args).items() if k != "save"},
                                "summary": summary, "runs": runs}, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

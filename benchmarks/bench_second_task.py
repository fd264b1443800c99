"""The learners' settings on a second task: ``rdmp_gym/DMPTracking-v0`` (re-centre a wiping pattern by a context
shift drawn per episode, physics-free), with the same options as on ArmarWipe-v2 and no task-specific structure.

Per learner and seed: one run of ``budget`` episodes on random training contexts, then its final policy on the
test contexts (``final_test_seeds``); the score is the test return, minus the mean squared tracking error (cm²).
Printed and saved: the IQM over seeds with a 95 % stratified-bootstrap interval, the imitation's return and the
probability that a run of ``bbrl`` beats a run of each other learner on a test context.

    python benchmarks/bench_second_task.py --save      # 10 seeds x 3 learners x 1000 episodes, about 2 min
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np
import rdmp_gym.envs  # noqa: F401  (registers the envs)
from output import add_save_argument, results_dir
from rdmp_gym.agents.field_metrics import probability_of_improvement, stratified_interval
from rdmp_gym.agents.pool import Evaluator
from rdmp_gym.agents.protocol import context_observations, final_test_seeds
from rdmp_gym.agents.report import trained_actions
from rdmp_gym.agents.tasks import TaskSpec
from rdmp_gym.agents.training import TrainConfig, train
from rdmp_gym.envs import TRACKING_ID
from tqdm import tqdm


def _parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--agents", nargs="+", default=["bbrl", "cpi2", "random"])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--budget", type=int, default=1000, help="training episodes per run")
    parser.add_argument("--rollouts", type=int, default=10)
    parser.add_argument("--test-contexts", type=int, default=50)
    parser.add_argument("--context-range", type=float, default=0.05,
                        help="the shift of each context is drawn from +-this (m) along x and y")
    add_save_argument(parser)
    return parser.parse_args()


def _test_returns(config: TrainConfig, scratch: Path, tester: Evaluator, seeds: np.ndarray,
                  observations: np.ndarray) -> np.ndarray:
    run = train(config, scratch / f"{config.agent}-{config.seed}")
    actions = trained_actions(run, config, "last", observations, tester.n_actions)
    return tester.run(actions, seeds).returns


def main() -> None:
    import torch

    torch.set_num_threads(1)
    args = _parse()
    seeds = final_test_seeds(args.test_contexts)
    scores: dict[str, list[list[float]]] = {}
    env_kwargs = {"context_range": args.context_range}
    with Evaluator(TaskSpec(TRACKING_ID, env_kwargs), 1) as tester, tempfile.TemporaryDirectory() as scratch:
        observations = context_observations(tester.env, seeds)
        imitation = tester.run(np.zeros((len(seeds), tester.n_actions)), seeds).returns
        for agent in args.agents:
            for seed in tqdm(range(args.seeds), desc=agent, unit="run"):
                config = TrainConfig(agent=agent, env_id=TRACKING_ID, updates=args.budget // args.rollouts,
                                     rollouts=args.rollouts, seed=seed, workers=1, env_kwargs=env_kwargs,
                                     eval_episodes=4, eval_every=10, shared_context=False)
                scores.setdefault(agent, []).append(
                    _test_returns(config, Path(scratch), tester, seeds, observations).tolist())
    table = {agent: stratified_interval(np.array(rows)).to_dict() for agent, rows in scores.items()}
    improvement = {other: probability_of_improvement(np.array(scores["bbrl"]), np.array(scores[other])).to_dict()
                   for other in scores if other != "bbrl"} if "bbrl" in scores else {}
    print(f"{'learner':>10} {'test return (-MSE, cm²), IQM [95 % CI]':>40}   P(bbrl > learner)")
    print(f"{'imitation':>10} {np.mean(imitation):>40.3f}")
    for agent, entry in table.items():
        cell = f"{entry['estimate']:.3f} [{entry['low']:.3f}, {entry['high']:.3f}]"
        chance = improvement.get(agent)
        print(f"{agent:>10} {cell:>40}   " + ("-" if chance is None else f"{chance['estimate']:.2f}"))
    document = {"settings": {**vars(args), "env_id": TRACKING_ID, "final_test_seeds": seeds.tolist()},
                "imitation": imitation.tolist(), "scores": scores, "summary": table, "improvement": improvement}
    path = results_dir(args.save) / "second_task.json"
    path.write_text(json.dumps(document, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()

"""``rdmp-gym cycles``: train a policy that reacts cycle by cycle and score it on the test contexts.

    rdmp-gym cycles --env rdmp_gym/PandaWipe-v3 --out runs/cycles_panda            # the cycle-by-cycle search
    rdmp-gym cycles --env rdmp_gym/ArmarDrum-v1 --agent sac --episodes 300 --out runs/cycles_sac

It runs on the cycle-level face of the env (:mod:`rdmp_gym.envs.cycle_env`) and writes ``run.json`` (the curve on
the validation contexts, the best policy's scores on the test contexts) and ``curve.png`` to ``--out``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import tyro
from rdmp_gym.envs.registration import LATEST_ENV_ID
from tqdm.auto import tqdm

from .cycle_training import CycleRun, failure_counts, train_cycle_search
from .learners.cycle_search import CycleSearchConfig

__all__ = ["CycleCommand", "command_cycles", "parse_cycles"]


@dataclass(frozen=True)
class CycleCommand:
    """Train a policy that reacts cycle by cycle (cycle-by-cycle search, SAC or PPO) and score it on test contexts."""

    out: Path
    """the run's directory (run.json, curve.png)"""
    env: str = LATEST_ENV_ID
    """an episodic task id (rdmp_gym/{Robot}{Task}-vN) or its cycle face's id (default: the current wiping task)"""
    agent: Literal["cycle", "sac", "ppo"] = "cycle"
    """cycle: the cycle-by-cycle search; sac, ppo: stable-baselines3 on the cycle face"""
    episodes: int = 1000
    """training episodes"""
    rollouts: int = 16
    """episodes per update"""
    seed: int = 0
    """the run's seed (the same seed gives the same numbers)"""
    workers: int = 2
    """processes that run the search's episodes"""
    validation: int = 20
    """validation contexts (the curve and the choice of the best policy)"""
    test: int = 50
    """test contexts (never used for training or selection)"""
    validation_pool: int = 400
    """validation contexts sorted by kind before the stratified choice (400: as for the other learners)"""


def parse_cycles(argv: Sequence[str]) -> CycleCommand:
    """The command line ``argv`` (after ``cycles``) as a :class:`CycleCommand`."""
    return tyro.cli(CycleCommand, args=list(argv), prog="rdmp-gym cycles")


def _run(command: CycleCommand) -> CycleRun:
    bar = tqdm(total=command.episodes, unit="episode", desc=command.agent)

    def progress(episodes: int, row: dict[str, float]) -> None:
        bar.update(episodes - bar.n)
        bar.set_postfix(validation_success=f"{row['validation_success']:.2f}")

    try:
        if command.agent == "cycle":
            return train_cycle_search(command.env, episodes=command.episodes, rollouts=command.rollouts,
                                      seed=command.seed, workers=command.workers, config=CycleSearchConfig(),
                                      validation=command.validation, test=command.test, progress=progress,
                                      validation_pool=command.validation_pool)
        from .cycle_sb3 import train_cycle_sb3

        return train_cycle_sb3(command.env, command.agent, episodes=command.episodes, seed=command.seed,
                               rollouts=command.rollouts, validation=command.validation, test=command.test,
                               progress=progress, validation_pool=command.validation_pool)
    finally:
        bar.close()


def _plot(run: CycleRun, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(6, 3.5))
    axis.plot([row["episodes"] for row in run.curve], [row["validation_success"] for row in run.curve], "o-")
    axis.set_xlabel("training episodes")
    axis.set_ylabel("validation success rate")
    axis.set_ylim(-0.02, 1.02)
    axis.set_title(f"{run.env_id}, seed {run.seed}: test success {run.test['success_rate']:.2f}")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def command_cycles(argv: Sequence[str]) -> None:
    """Run ``rdmp-gym cycles``."""
    command = parse_cycles(argv)
    if command.episodes < 2 * command.rollouts:
        raise ValueError(f"episodes: expected at least 2 x rollouts ({2 * command.rollouts}), got {command.episodes}")
    command.out.mkdir(parents=True, exist_ok=True)
    run = _run(command)
    run.save(command.out / "run.json")
    _plot(run, command.out / "curve.png")
    causes = failure_counts(run.test["failures"])
    print(f"{run.env_id} ({command.agent}, seed {command.seed}): test success {run.test['success_rate']:.2f} on "
          f"{len(run.test['seeds'])} contexts (best policy after {run.best_episodes} episodes), mean return "
          f"{run.test['mean_return']:.3f}, failures {causes}; {run.wall_seconds:.0f} s -> {command.out}")

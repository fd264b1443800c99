"""The cycle-face benchmark (``benchmarks/bench_cycle_search.py``): every ``--agent`` reaches its trainer with
arguments the trainer accepts (fake trainers bound to the real signatures, so no learning runs here), and the
cycle search's settings are refused by name where the learner has none."""

import argparse
import inspect
from pathlib import Path

import bench_cycle_search
import pytest
from rdmp_gym.agents import cycle_sb3, cycle_training, reacting


class _Run:
    """What ``_run_seed`` reads of a trained run."""

    def __init__(self) -> None:
        self.test = {"failures": [], "success_rate": 0.5}
        self.best_episodes, self.wall_seconds = 10, 1.0

    def save(self, path: Path) -> None:
        path.write_text("{}")


def _fake(real, calls: list):
    def train(*args, **kwargs):
        calls.append(inspect.signature(real).bind(*args, **kwargs))          # TypeError on an unknown argument
        return _Run()
    return train


@pytest.mark.parametrize("agent", ["cycle", "reacting", "sac", "ppo"])
def test_each_agent_calls_its_trainer_with_arguments_it_accepts(agent, tmp_path, monkeypatch):
    calls: list = []
    monkeypatch.setattr(bench_cycle_search, "train_cycle_search",
                        _fake(cycle_training.train_cycle_search, calls))
    monkeypatch.setattr(reacting, "train_reacting", _fake(reacting.train_reacting, calls))
    monkeypatch.setattr(cycle_sb3, "train_cycle_sb3", _fake(cycle_sb3.train_cycle_sb3, calls))
    args = argparse.Namespace(agent=agent, env="rdmp_gym/ArmarDrum-v2", episodes=20, rollouts=10, open_loop=0.6,
                              workers=1, validation=2, test=3, random_returns=False, set=[], run_dir=tmp_path)
    bench_cycle_search._run_seed(args, 4, tmp_path / "seed_4.json")
    assert len(calls) == 1 and (tmp_path / "seed_4.json").exists()
    bound = calls[0].arguments
    assert bound["episodes"] == 20 and bound["seed"] == 4 and bound["test"] == 3
    if agent in ("sac", "ppo"):
        assert bound["algorithm"] == agent


@pytest.mark.parametrize("flags", [["--set", "pooled=false"], ["--random-returns"]])
def test_sac_and_ppo_refuse_the_cycle_searchs_settings_by_name(flags, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("sys.argv", ["bench_cycle_search.py", "--agent", "sac", "--run-dir", str(tmp_path), *flags])
    with pytest.raises(SystemExit):
        bench_cycle_search.main()
    assert "--set and --random-returns" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())                                   # nothing trained

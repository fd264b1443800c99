"""Import costs, in a fresh interpreter: torch loads only with the learners that use it (bbrl, PPO, SAC); the
learners load neither gymnasium nor MuJoCo (the env's package loads with the env)."""

import json
import subprocess
import sys

import pytest

WATCHED = ("torch", "gymnasium", "mujoco", "rdmp_gym.envs")

# Run in this order in one fresh interpreter, each stage's imports on top of the previous stages': the learners, then
# the agents package, the training loop, the CLI and the registry (which import the learners too), then bbrl built.
# A stage's check reads what is loaded after it: a module the test of a stage refuses is loaded by no earlier stage.
STAGES = {
    "learners": ("import rdmp_gym.agents.learners\nfrom rdmp_gym.agents.learners import contextual, make_learner\n"
                 "from rdmp_gym.agents.registry import REGISTRY\nassert {'cpi2', 'creps', 'cmaes'} <= set(REGISTRY)"),
    "agents": ("import rdmp_gym.agents\n"
               "import rdmp_gym.agents.training, rdmp_gym.agents.learners, rdmp_gym.agents.cli\n"
               "from rdmp_gym.agents import TrainConfig\n"
               "config = TrainConfig(agent='bbrl', options={'sigma_factors': {'approach': 3}})\n"
               "from rdmp_gym.agents.registry import REGISTRY\nassert {'bbrl', 'ppo', 'sac', 'cpi2'} <= set(REGISTRY)"),
    "bbrl": ("from rdmp_gym.agents.registry import agent_spec\nimport rdmp_gym.agents.learners\n"
             "agent_spec('bbrl').load()"),
}


@pytest.fixture(scope="module")
def loaded() -> dict[str, list[str]]:
    """Per stage of :data:`STAGES`, the :data:`WATCHED` modules loaded after it (one fresh interpreter for all)."""
    lines = ["import json, sys", "loaded = {}"]
    for name, code in STAGES.items():
        lines += [code, f"loaded[{name!r}] = [m for m in {WATCHED!r} if m in sys.modules]"]
    lines.append("print(json.dumps(loaded))")
    result = subprocess.run([sys.executable, "-c", "\n".join(lines)], capture_output=True, text=True, check=True,
                            timeout=300)
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_the_learners_load_no_gymnasium_or_mujoco(loaded):
    assert [m for m in loaded["learners"] if m != "torch"] == []


def test_the_agents_package_the_training_loop_and_the_registry_do_not_load_torch(loaded):
    assert "torch" not in loaded["agents"]


def test_building_bbrl_loads_torch(loaded):
    assert "torch" in loaded["bbrl"]

"""Import costs, in a fresh interpreter: torch loads only with the learners that use it (bbrl, PPO, SAC); the
learners load neither gymnasium nor MuJoCo (the env's package loads with the env)."""

import subprocess
import sys


def _loaded(code: str, modules: tuple[str, ...]) -> list[str]:
    """The ``modules`` that running ``code`` in a fresh interpreter imports."""
    probe = f"import sys\n{code}\nprint(' '.join(m for m in {modules!r} if m in sys.modules))"
    result = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=300)
    return result.stdout.strip().splitlines()[-1].split() if result.stdout.strip() else []


def _loads_torch(code: str) -> bool:
    return _loaded(code, ("torch",)) == ["torch"]


def test_the_agents_package_the_training_loop_and_the_registry_do_not_load_torch():
    code = ("import rdmp_gym.agents\nimport rdmp_gym.agents.training, rdmp_gym.agents.learners, rdmp_gym.agents.cli\n"
            "from rdmp_gym.agents import TrainConfig\n"
            "config = TrainConfig(agent='bbrl', options={'sigma_factors': {'approach': 3}})\n"
            "from rdmp_gym.agents.registry import REGISTRY\nassert {'bbrl', 'ppo', 'sac', 'cpi2'} <= set(REGISTRY)")
    assert not _loads_torch(code)


def test_building_bbrl_loads_torch():
    assert _loads_torch("from rdmp_gym.agents.registry import agent_spec\n"
                        "import rdmp_gym.agents.learners\nagent_spec('bbrl').load()")


def test_the_learners_load_no_gymnasium_or_mujoco():
    code = ("import rdmp_gym.agents.learners\nfrom rdmp_gym.agents.learners import contextual, make_learner\n"
            "from rdmp_gym.agents.registry import REGISTRY\nassert {'cpi2', 'creps', 'cmaes'} <= set(REGISTRY)")
    assert _loaded(code, ("gymnasium", "mujoco", "rdmp_gym.envs")) == []

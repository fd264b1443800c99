"""Each helper of the agents layer in one home: no two modules define the same function (a file's SHA-256, the
interquartile mean), so a fix to one cannot miss the other."""

import ast
import hashlib
from collections import defaultdict
from pathlib import Path

import numpy as np
from rdmp_gym.agents import field_metrics, protocol, runs, training

AGENTS = Path(__file__).resolve().parent.parent / "agents"
DISPATCHERS = {"policy_from_state"}     # learners/__init__.py picks the learner's own policy_from_state


def test_no_two_agents_modules_define_the_same_function() -> None:
    homes = defaultdict(list)
    for path in sorted(AGENTS.rglob("*.py")):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                homes[node.name.lstrip("_")].append(str(path.relative_to(AGENTS)))
    assert {name: files for name, files in homes.items() if len(files) > 1 and name not in DISPATCHERS} == {}


def test_the_shared_helpers_come_from_their_one_home(tmp_path) -> None:
    assert training.sha256_file is runs.sha256_file and field_metrics.iqm is protocol.iqm
    path = tmp_path / "blob"
    path.write_bytes(np.random.default_rng(0).bytes(3 << 20))        # more than one block
    assert runs.sha256_file(path) == hashlib.sha256(path.read_bytes()).hexdigest()
    scores = np.random.default_rng(1).normal(size=(9, 4))
    assert protocol.iqm(scores) == protocol.iqm(scores.ravel()) == field_metrics.stratified_interval(scores).estimate

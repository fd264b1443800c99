"""The robot is a parameter: a robot described in one place (here a 4-DoF arm written in this file) wipes the table,
and no module outside a robot's own folder names a robot's bodies, joints, sites or geoms."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from mini_arm import MINI
from rdmp_gym.envs.robots import ROBOTS, RobotDescription, register_robot
from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv

ENVS = Path(__file__).resolve().parent.parent / "envs"

def test_a_robot_described_alone_wipes_the_table():
    env = ArmarWipeEnv(robot=MINI, version=3, n_periods=2.0, obstacle=False)
    assert env.action_space.shape == gym.make("rdmp_gym/ArmarWipe-v3").action_space.shape
    for seed in (0, 1):
        env.reset(seed=seed)
        _, reward, terminated, _, info = env.step(np.zeros(env.action_space.shape, np.float32))
        assert terminated and info["valid"], info["invalid_reason"]
        assert np.isfinite(reward)
        assert info["force_in_band_fraction"] > 0.9
        assert info["coverage"] > 0.5
        assert info["arm_collision_fraction"] == 0.0 and info["self_collision_fraction"] == 0.0


def test_a_registered_robot_is_chosen_by_name_in_gym_make(monkeypatch):
    monkeypatch.setitem(ROBOTS, "mini", MINI)
    env = gym.make("rdmp_gym/ArmarWipeStep-v3", robot="mini", n_periods=1.0, obstacle=False)
    env.reset(seed=3)
    _, reward, _, _, _ = env.step(np.zeros(3))
    assert np.isfinite(reward)
    assert env.unwrapped.task.robot is MINI
    with pytest.raises(TypeError):
        register_robot("mini")


@pytest.mark.parametrize(("field", "value"), [("joints", ("yaw", "shoulder", "knee")), ("ft_site", "nowhere"),
                                              ("arm_root", "arm"), ("hand_geoms", ("claw",))])
def test_a_wrong_name_in_a_description_is_refused_by_field(field, value):
    import dataclasses

    wrong = dataclasses.replace(MINI, **{field: value}) if field != "joints" else dataclasses.replace(
        MINI, joints=value, posture=np.zeros(3), mobility=np.ones(3))
    with pytest.raises(ValueError, match=field):
        ArmarWipeEnv(robot=wrong, version=3)


def _names(robot: RobotDescription) -> set[str]:
    names = {*robot.joints, robot.root_body, robot.arm_root, *robot.body_links, robot.tool_mount.body, robot.ft_site,
             *robot.hand_geoms}
    if robot.body_clearance is not None:
        clearance = robot.body_clearance
        names |= {clearance.box_body, clearance.box, *clearance.capsule_bodies, *clearance.capsules}
    return names


@pytest.mark.parametrize("robot", sorted(ROBOTS))
def test_no_module_outside_a_robots_folder_names_its_parts(robot):
    names = _names(ROBOTS[robot])
    pattern = re.compile("[\"'](" + "|".join(map(re.escape, names)) + ")[\"']")
    found = [f"{path.relative_to(ENVS)}: {match.group(0)}" for path in ENVS.rglob("*.py")
             if "robots" not in path.relative_to(ENVS).parts for match in pattern.finditer(path.read_text())]
    assert not found


def test_contexts_beyond_a_robots_reach_are_refused_by_name():
    import dataclasses

    small = dataclasses.replace(MINI, workspace=(np.array([-0.1, -0.1, -0.05]), np.array([0.1, 0.1, 0.3])))
    with pytest.raises(ValueError, match="context_ranges"):
        ArmarWipeEnv(robot=small, version=3)

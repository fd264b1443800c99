"""The robot is a parameter: a robot described in one place (here a 4-DoF arm written in this file) wipes the table,
and no module outside a robot's own folder names a robot's bodies, joints, sites or geoms."""

from __future__ import annotations

import re
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np
import pytest
import rdmp_gym.envs  # noqa: F401  (registers the ids)
from rdmp_gym.envs.robots import ROBOTS, RobotDescription, ToolMount, register_robot
from rdmp_gym.envs.wipe_env import ArmarWipeEnv

ENVS = Path(__file__).resolve().parent.parent / "envs"

# A base yaw and three pitch joints: enough to hold the sponge flat anywhere over the patch.
MINI_ARM = """
<mujoco model="mini_arm">
  <compiler angle="radian" autolimits="true"/>
  <default>
    <default class="mini">
      <joint damping="1" armature="0.05"/>
      <geom type="capsule" size="0.03" contype="6" conaffinity="1" mass="0.5"/>
      <position kp="400" dampratio="1"/>
    </default>
  </default>
  <worldbody>
    <body name="base" childclass="mini">
      <geom name="base" type="box" size="0.08 0.08 0.4" pos="0 0 0.4" contype="2" conaffinity="5" mass="10"/>
      <body name="turret" pos="0 0 0.8" gravcomp="1">
        <geom name="turret" type="sphere" size="0.05" contype="2" conaffinity="5" mass="1"/>
        <joint name="yaw" axis="0 0 1" range="-1.5 1.5"/>
        <body name="upper" pos="0 0 0.25" gravcomp="1">
          <joint name="shoulder" axis="0 1 0" range="-2.0 2.0"/>
          <geom name="upper" fromto="0 0 0 0.4 0 0"/>
          <body name="fore" pos="0.4 0 0" gravcomp="1">
            <joint name="elbow" axis="0 1 0" range="-0.2 2.8"/>
            <geom name="fore" fromto="0 0 0 0.4 0 0"/>
            <body name="wrist" pos="0.4 0 0" gravcomp="1">
              <joint name="wrist" axis="0 1 0" range="-2.5 2.5"/>
              <geom name="wrist" fromto="0 0 0 0 0 -0.06" size="0.025"/>
              <site name="ft" pos="0 0 -0.06"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <position class="mini" joint="yaw" ctrlrange="-1.5 1.5"/>
    <position class="mini" joint="shoulder" ctrlrange="-2.0 2.0"/>
    <position class="mini" joint="elbow" ctrlrange="-0.2 2.8"/>
    <position class="mini" joint="wrist" ctrlrange="-2.5 2.5"/>
  </actuator>
</mujoco>
"""

MINI = RobotDescription(
    name="mini", spec=lambda: mujoco.MjSpec.from_string(MINI_ARM), joints=("yaw", "shoulder", "elbow", "wrist"),
    root_body="base", arm_root="upper", body_links=("base",), ft_site="ft", hand_geoms=("wrist",),
    tool_mount=ToolMount("wrist", (0.0, 0.0, -0.09), (0.70710678, 0.0, -0.70710678, 0.0)),
    posture=np.array([0.0, -0.85, 1.88, -1.0]), mobility=np.ones(4), max_joint_speed=3.0, max_joint_accel=10.0,
    workspace=(np.array([-0.35, -0.40, -0.05]), np.array([0.35, 0.40, 0.30])), base_pos=(0.05, -0.28, 0.0))


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

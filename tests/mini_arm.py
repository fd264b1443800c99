"""A robot described in a test file: a 4-DoF arm (a base yaw and three pitch joints), enough to hold a tool level
anywhere over the table; the robot and task seams' tests run it beside ARMAR-III and the Panda."""

from __future__ import annotations

import mujoco
import numpy as np
from rdmp_gym.envs.robots import RobotDescription, ToolMount

__all__ = ["MINI"]

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

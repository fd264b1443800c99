"""Franka Emika Panda: a fixed-base 7-DoF arm on a pedestal beside the table, the sponge on its flange.

The model is not copied here: :func:`panda_spec` loads the Franka Panda MJCF that ``gymnasium-robotics`` ships
(``gymnasium_robotics/envs/assets/kitchen_franka/franka_assets``: MIT, adapted from Vikash Kumar's Apache-2.0
model, https://github.com/vikashplus/franka) from the installed package at run time (``pip install
"rdmp-gym[panda]"``), and takes from it the kinematics (link frames, joint axes and ranges), the link masses and
inertias (MuJoCo computes them from the collision meshes and the masses the file gives) and the visual meshes.
It then builds the robot alone for the wiping task:

- the Franka Hand and its fingers are left out: the sponge replaces the gripper, on a 1 cm tool plate on the
  flange (``flange``, 0.107 m beyond joint 7), whose body carries the wrist force/torque site ``ft_site`` (its
  subtree is the plate and the sponge);
- simple collision geometry: capsules on the links (about the collision meshes' convex hulls), a box on the
  base link and on the pedestal; the visual meshes are visual only;
- one position servo per joint, ctrl-limited to the joint's range, force-limited to Franka's published joint
  torques (87 N m on joints 1-4, 12 N m on 5-7), critically damped; gravity compensation on the moving links
  (the real controller compensates gravity too);
- a pedestal (the robot's root, origin on the floor) that raises the base to ``PEDESTAL_HEIGHT``.

Collision filtering follows the arena's bit masks (``envs/assets/arena.xml``): every robot geom collides with the
table and the floor (contype 2, conaffinity 1); the moving links have contype 2|4, the pedestal and the base link
conaffinity 1|4, so the arm collides with them but not with itself.

Franka's published limits (https://frankaemika.github.io/docs/control_parameters.html#limits-for-panda): joint
speed 2.175 rad/s (joints 1-4) and 2.61 rad/s (5-7), joint acceleration 15, 7.5, 10, 12.5, 15, 20, 20 rad/s². A
description holds one number each, so the task uses the smallest: 2.175 rad/s and 7.5 rad/s².
"""

from __future__ import annotations

import importlib.util
from functools import lru_cache
from pathlib import Path

import mujoco
import numpy as np

from ..description import RobotDescription, ToolMount

__all__ = ["PANDA", "PEDESTAL_HEIGHT", "franka_assets", "panda_spec"]

#: height (m) of the pedestal's top, where the Panda's base link stands (the table's top is at 0.90 m)
PEDESTAL_HEIGHT = 0.85
#: the extra that installs the model's package
_EXTRA = 'pip install "rdmp-gym[panda]"'
_SOURCE = ("envs", "assets", "kitchen_franka", "franka_assets")
_LINKS = tuple(f"panda0_link{i}" for i in range(8))

#: Franka's joint torque limits (N m)
TORQUE_LIMIT = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
#: servo stiffness (N m / rad) per joint [E]: stiff enough to track a 1 Hz wiping motion under the contact
#: force, within the torque limits
SERVO_KP = (1200.0, 1200.0, 1000.0, 1000.0, 300.0, 300.0, 200.0)

# Collision capsules (link frame: from [3], to [3], radius), fitted to the collision meshes' hulls [E]
_CAPSULES: dict[int, tuple[tuple[tuple[float, ...], tuple[float, ...], float], ...]] = {
    1: (((0, 0, -0.12), (0, 0, 0), 0.06), ((0, -0.08, 0), (0, 0, 0), 0.06)),
    2: (((0, 0, 0), (0, -0.14, 0), 0.06), ((0, 0, 0), (0, 0, 0.08), 0.06)),
    3: (((0, 0, -0.07), (0, 0, 0), 0.06), ((0, 0, 0), (0.0825, 0, 0), 0.06),
        ((0.0825, 0, 0), (0.0825, 0.06, 0), 0.06)),
    4: (((0, 0, 0), (0, 0, 0.06), 0.06), ((0, 0, 0), (-0.0825, 0, 0), 0.06),
        ((-0.0825, 0, 0), (-0.0825, 0.07, 0), 0.06)),
    5: (((0, 0, -0.22), (0, 0, 0), 0.06), ((0, 0.08, -0.18), (0, 0.08, 0), 0.05)),
    6: (((0, 0, 0), (0.088, 0, 0), 0.06),),
    7: (((0, 0, 0.06), (0.02, 0.02, 0.07), 0.05),),
}
# the base link's box (centre, half sizes) about its collision mesh (x in [-0.154, 0.072], |y| < 0.095, z < 0.14)
_BASE_BOX = ((-0.041, 0.0, 0.07), (0.115, 0.095, 0.07))
_FLANGE = 0.107          # flange beyond joint 7 (m)
_PLATE = 0.01            # tool plate thickness (m)


def franka_assets() -> Path:
    """The folder of the Franka Panda MJCF in the installed ``gymnasium-robotics`` (found without importing it).

    Raises ModuleNotFoundError naming the extra when the package is missing."""
    try:
        found = importlib.util.find_spec("gymnasium_robotics")
    except ImportError:                     # a finder that refuses the name
        found = None
    if found is None or not found.submodule_search_locations:
        raise ModuleNotFoundError(f"robot 'panda': its model comes from the package gymnasium-robotics, which is not "
                                  f"installed; install it with {_EXTRA}", name="gymnasium_robotics")
    folder = Path(next(iter(found.submodule_search_locations))).joinpath(*_SOURCE)
    missing = [n for n in ("chain.xml", "assets.xml") if not (folder / n).is_file()]
    if missing:
        raise ModuleNotFoundError(f"robot 'panda': the installed gymnasium-robotics lacks {missing} in {folder}; "
                                  f"install a version >= 1.4 with {_EXTRA}", name="gymnasium_robotics")
    return folder


def _source_spec(folder: Path) -> mujoco.MjSpec:
    """The package's Panda (arm, hand and fingers) as it is, with its mesh files resolved to absolute paths."""
    xml = (f'<mujoco model="panda_source"><include file="{folder / "assets.xml"}"/>'
           f'<worldbody><include file="{folder / "chain.xml"}"/></worldbody></mujoco>')
    spec = mujoco.MjSpec.from_string(xml)
    meshes = folder / "meshes"
    for mesh in spec.meshes:
        # assets.xml's meshdir is relative to the package's kitchen scene; take the file's last two parts
        # (collision/link0.stl) whatever MuJoCo resolved them against
        mesh.file = str(meshes.joinpath(*Path(mesh.file).parts[-2:]))
    spec.meshdir = ""
    return spec


@lru_cache(maxsize=1)
def _source(folder: str) -> dict:
    """What the task takes from the package's model: per link its frame in the parent (pos, quat), the joint's
    axis and range, and its mass, centre of mass and principal inertia computed from the collision mesh (the hand
    and the fingers left out); the visual mesh files."""
    spec = _source_spec(Path(folder))
    for body in [b for b in spec.bodies if "finger" in b.name]:
        spec.delete(body)
    for geom in list(spec.geoms):
        if geom.classname.name == "panda_viz" or (geom.type == mujoco.mjtGeom.mjGEOM_MESH
                                                  and geom.meshname.startswith("hand")):
            spec.delete(geom)
    meshes = {m.name: m.file for m in spec.meshes}
    for mesh in [m for m in spec.meshes if m.name.endswith("_viz") or m.name.startswith(("hand", "finger"))]:
        spec.delete(mesh)
    model = spec.compile()
    links = []
    for name in _LINKS:
        b = model.body(name)
        joint = int(model.body_jntadr[b.id])
        links.append({"pos": b.pos.copy(), "quat": b.quat.copy(), "mass": float(model.body_mass[b.id]),
                      "ipos": model.body_ipos[b.id].copy(), "iquat": model.body_iquat[b.id].copy(),
                      "inertia": model.body_inertia[b.id].copy(),
                      "axis": None if joint < 0 else model.jnt_axis[joint].copy(),
                      "range": None if joint < 0 else model.jnt_range[joint].copy()})
    visual = {i: meshes[f"link{i}_viz"] for i in range(8)}
    return {"links": links, "visual": visual}


def _vec(values) -> str:
    return " ".join(f"{float(v):.10g}" for v in values)


def panda_mjcf(folder: Path | None = None, visual: bool = True) -> str:
    """The MJCF text of the Panda for the wiping task (the module docstring says what it holds)."""
    source = _source(str(franka_assets() if folder is None else folder))
    links = source["links"]
    assets = ("".join(f'<mesh name="link{i}_viz" file="{path}"/>' for i, path in source["visual"].items())
              if visual else "")

    def inertial(link: dict) -> str:
        return (f'<inertial pos="{_vec(link["ipos"])}" quat="{_vec(link["iquat"])}" mass="{link["mass"]:.10g}" '
                f'diaginertia="{_vec(link["inertia"])}"/>')

    def mesh(i: int) -> str:
        return f'<geom class="visual" mesh="link{i}_viz"/>' if visual else ""

    box_pos, box_half = _BASE_BOX
    body = (f'<body name="link0" pos="0 0 {PEDESTAL_HEIGHT}">{inertial(links[0])}{mesh(0)}'
            f'<geom name="link0" class="body" type="box" pos="{_vec(box_pos)}" size="{_vec(box_half)}"/>')
    tail = "</body>"
    for i in range(1, 8):
        link = links[i]
        capsules = "".join(f'<geom name="link{i}{"" if k == 0 else chr(ord("a") + k)}" class="arm" type="capsule" '
                           f'fromto="{_vec((*a, *b))}" size="{r}"/>' for k, (a, b, r) in enumerate(_CAPSULES[i]))
        body += (f'<body name="link{i}" pos="{_vec(link["pos"])}" quat="{_vec(link["quat"])}" gravcomp="1">'
                 f'{inertial(link)}<joint name="joint{i}" axis="{_vec(link["axis"])}" range="{_vec(link["range"])}"/>'
                 f'{mesh(i)}{capsules}')
        tail += "</body>"
    # the tool plate on the flange: its body is the F/T sensor's (the plate and the sponge below it)
    body += (f'<body name="flange" pos="0 0 {_FLANGE}" gravcomp="1">'
             f'<inertial pos="0 0 {_PLATE / 2}" mass="0.1" diaginertia="4e-5 4e-5 6e-5"/>'
             f'<site name="ft_site" group="4" size="0.012" rgba="0.9 0.2 0.2 1"/>'
             f'<geom name="flange" class="arm" type="cylinder" size="0.0315 {_PLATE / 2}" pos="0 0 {_PLATE / 2}" '
             f'material="panda_dark"/></body>')
    actuators = "".join(
        f'<position name="joint{i}" class="panda" joint="joint{i}" kp="{SERVO_KP[i - 1]:g}" '
        f'ctrlrange="{_vec(links[i]["range"])}" forcerange="{-TORQUE_LIMIT[i - 1]:g} {TORQUE_LIMIT[i - 1]:g}"/>'
        for i in range(1, 8))
    return f"""<mujoco model="panda">
  <compiler angle="radian" autolimits="true"/>
  <asset>
    <material name="panda_white" rgba="0.95 0.95 0.93 1"/>
    <material name="panda_dark" rgba="0.25 0.27 0.30 1"/>
    {assets}
  </asset>
  <default>
    <default class="panda">
      <geom contype="2" conaffinity="1" condim="3" friction="0.5 0.005 0.0001" group="3" rgba="0.5 0.6 0.7 1"/>
      <joint damping="1" armature="0.1" limited="true"/>
      <position dampratio="1" ctrllimited="true" forcelimited="true"/>
      <default class="visual">
        <geom type="mesh" contype="0" conaffinity="0" group="1" mass="0" material="panda_white"/>
      </default>
      <default class="arm">
        <geom contype="6" conaffinity="1"/>
      </default>
      <default class="body">
        <geom contype="2" conaffinity="5"/>
      </default>
    </default>
  </default>
  <worldbody>
    <body name="pedestal" childclass="panda">
      <inertial pos="0 0 {PEDESTAL_HEIGHT / 2}" mass="60" diaginertia="4 4 1"/>
      <geom name="pedestal" class="body" type="box" size="0.13 0.11 {PEDESTAL_HEIGHT / 2}"
            pos="-0.04 0 {PEDESTAL_HEIGHT / 2}" group="1" material="panda_dark"/>
      {body}{tail}
    </body>
  </worldbody>
  <actuator>{actuators}</actuator>
</mujoco>"""


def panda_spec() -> mujoco.MjSpec:
    """A fresh ``MjSpec`` of the Panda for the wiping task, from the installed ``gymnasium-robotics``."""
    return mujoco.MjSpec.from_string(panda_mjcf())


PANDA = RobotDescription(
    name="panda",
    spec=panda_spec,
    joints=tuple(f"joint{i}" for i in range(1, 8)),
    root_body="pedestal",
    arm_root="link1",
    body_links=("pedestal", "link0"),
    # the pad below the flange: its +x (away from the face) along the flange's -z, its long side along the flange's x
    tool_mount=ToolMount("flange", (0.0, 0.0, _PLATE + 0.02), (0.70710678, 0.0, 0.70710678, 0.0)),
    ft_site="ft_site",
    hand_geoms=("flange", "link7"),
    posture=np.array([-0.07, 0.55, -0.02, -2.34, 0.05, 1.32, 0.0]),
    mobility=np.ones(7),
    max_joint_speed=2.175,
    max_joint_accel=7.5,
    workspace=(np.array([-0.22, -0.30, -0.05]), np.array([0.27, 0.38, 0.30])),
    base_pos=(0.03, -0.23, 0.0),
    joint_labels=tuple(f"j{i}" for i in range(1, 8)),
)

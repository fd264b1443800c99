"""Robot descriptions: the Franka Panda (model from gymnasium-robotics, loaded at run time) composes into the wiping
scene with the joints, limits and servos it describes, wipes the held-out contexts like ARMAR-III, and a description
that names a body, joint, site or geom its MJCF lacks is refused by the field's name."""

import dataclasses
import os
import subprocess
import sys
import xml.etree.ElementTree as ElementTree

import mujoco
import numpy as np
import pytest
from rdmp_gym.envs.rhythmic_env import RhythmicTaskEnv
from rdmp_gym.envs.robots import ROBOTS, get_robot
from rdmp_gym.envs.robots import panda as panda_module
from rdmp_gym.envs.robots.panda import PANDA, TORQUE_LIMIT, franka_assets
from rdmp_gym.envs.task_scene import ROBOT_PREFIX, TOOL_PREFIX


@pytest.fixture(scope="module")
def assets():
    pytest.importorskip("gymnasium_robotics")
    return franka_assets()


@pytest.fixture(scope="module")
def staged(assets):
    """The wiping task's scene on the Panda and where the task's parts are in it."""
    face = RhythmicTaskEnv("wipe", "panda", version=3)
    return face.scene, face.task.parts


@pytest.fixture(scope="module")
def scene(staged):
    return staged[0]


@pytest.fixture(scope="module")
def env(assets):
    from rdmp_gym.envs.tasks.wiping.env import ArmarWipeEnv

    return ArmarWipeEnv(robot="panda", version=3, obstacle=True)


def _body_of(model, kind, name):
    return int(model.site_bodyid[model.site(name).id]) if kind == "site" else model.body(name).id


def _subtree(model, root):
    return {b for b in range(model.nbody) if _descends(model, b, root)}


def _descends(model, body, root):
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return False


def test_panda_is_registered_and_importing_it_needs_no_model():
    assert get_robot("panda") is PANDA and ROBOTS["panda"] is PANDA
    assert len(PANDA.joints) == 7 and PANDA.max_joint_speed == 2.175 and PANDA.max_joint_accel == 7.5


def test_without_gymnasium_robotics_the_envs_import_and_the_spec_names_the_extra(tmp_path):
    code = """
import sys
class _Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == "gymnasium_robotics":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _Block())
import rdmp_gym.envs
from rdmp_gym.envs.robots import get_robot
robot = get_robot("panda")
try:
    robot.spec()
except ModuleNotFoundError as error:
    print("ERROR", error)
"""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120,
                            env={**os.environ, "PYTHONPATH": ""})
    assert result.returncode == 0, result.stderr[-2000:]
    assert "ERROR" in result.stdout and 'pip install "rdmp-gym[panda]"' in result.stdout


def test_the_scene_composes_with_the_packaged_joint_ranges_and_one_limited_servo_per_joint(assets, scene):
    chain = ElementTree.parse(assets / "chain.xml").getroot()
    ranges = {j.get("name"): [float(v) for v in j.get("range").split()] for j in chain.iter("joint")}
    source = np.array([ranges[f"robot:panda0_joint{i}"] for i in range(1, 8)])
    np.testing.assert_allclose(np.c_[scene.joint_lower, scene.joint_upper], source)
    m = scene.model
    ids = scene.actuator_ids
    assert len(set(ids.tolist())) == 7 and np.all(m.actuator_ctrllimited[ids])
    np.testing.assert_allclose(m.actuator_ctrlrange[ids], source)
    np.testing.assert_allclose(m.actuator_forcerange[ids, 1], TORQUE_LIMIT)
    assert np.all(m.actuator_gainprm[ids, 0] > 0) and np.all(scene.servo_lead() > 0)
    # the posture is well inside the limits
    margin = np.minimum(PANDA.posture - scene.joint_lower, scene.joint_upper - PANDA.posture)
    assert margin.min() > 0.3


def test_collision_geometry_is_simple_and_filtered_like_the_arena(staged):
    scene, parts = staged
    m = scene.model
    root = m.body(ROBOT_PREFIX + PANDA.root_body).id
    robot = _subtree(m, root)
    tool = m.body(TOOL_PREFIX + "sponge").id
    for g in range(m.ngeom):
        if int(m.geom_bodyid[g]) not in robot or int(m.geom_bodyid[g]) == tool:
            continue
        colliding = m.geom_contype[g] or m.geom_conaffinity[g]
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
            assert not colliding, m.geom(g).name                # meshes are visual only
        elif colliding:
            assert m.geom_contype[g] & 2 and m.geom_conaffinity[g] & 1, m.geom(g).name    # the table and floor
    body = {m.body(ROBOT_PREFIX + n).id for n in PANDA.body_links}
    arm = _subtree(m, m.body(ROBOT_PREFIX + PANDA.arm_root).id)
    for g in range(m.ngeom):
        if int(m.geom_bodyid[g]) in body and m.geom_contype[g]:
            assert m.geom_conaffinity[g] & 4                    # the arm collides with the robot's body
        if int(m.geom_bodyid[g]) in arm and m.geom_contype[g] and int(m.geom_bodyid[g]) != tool:
            assert m.geom_contype[g] & 4 and not m.geom_conaffinity[g] & 4    # ... but not with itself
    # at rest in the posture, nothing of the robot touches anything but the sponge the table
    scene.set_arm_state(PANDA.posture)
    assert np.all(scene.data.sensordata[list(parts.self_contact_adr)] == 0)


def test_the_wrist_sensor_carries_the_plate_and_the_sponge_only(scene):
    m = scene.model
    flange = _body_of(m, "site", ROBOT_PREFIX + PANDA.ft_site)
    below = _subtree(m, flange)
    assert m.body(TOOL_PREFIX + "sponge").id in below
    assert all(not m.body(b).name.startswith(ROBOT_PREFIX + "link") for b in below)


def test_the_sponge_face_points_along_the_flange_axis(staged):
    scene, parts = staged
    scene.set_arm_state(PANDA.posture)
    d = scene.data
    flange_z = d.site_xmat[parts.ft_site].reshape(3, 3)[:, 2]
    face_normal = -d.site_xmat[parts.sponge_site].reshape(3, 3)[:, 0]
    np.testing.assert_allclose(face_normal, flange_z, atol=1e-9)
    np.testing.assert_allclose(face_normal, -parts.table_rotation[:, 2], atol=0.02)     # flat on the table


_WRONG = [("arm_root", "link9"), ("joints", tuple(f"joint{i}" for i in (1, 2, 3, 4, 5, 6, 8))), ("ft_site", "wrist"),
          ("hand_geoms", ("palm",)), ("body_links", ("torso",)),
          ("tool_mount", dataclasses.replace(PANDA.tool_mount, body="hand"))]


@pytest.mark.parametrize("field, value", _WRONG)
def test_a_description_naming_what_its_model_lacks_is_refused_by_the_field(assets, field, value):
    robot = dataclasses.replace(PANDA, **{field: value})
    with pytest.raises(ValueError, match=field):
        RhythmicTaskEnv("wipe", robot, version=3)


def test_missing_package_raises_a_clear_error(monkeypatch):
    monkeypatch.setattr(panda_module.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(ModuleNotFoundError, match=r'rdmp-gym\[panda\]'):
        franka_assets()


@pytest.mark.parametrize("seed, success", [(7000, False), (7006, True), (7009, True)])
def test_the_imitation_wipes_held_out_contexts_within_the_pandas_limits(env, seed, success):
    env.reset(seed=seed)
    *_, info = env.step(np.zeros(env.action_space.shape))
    assert info["valid"] and info["invalid_reason"] == ""
    assert info["force_in_band_fraction"] >= 0.9 and info["coverage"] > 0.8
    assert info["arm_collision_fraction"] == 0.0 and info["self_collision_fraction"] == 0.0
    assert info["peak_joint_accel"] < 0.6 * PANDA.max_joint_accel and info["joint_limit_fraction"] == 0.0
    # 7000: the imitation's pattern leaves 13 % of the patch (as on ARMAR-III, which covers 89 %)
    assert info["is_success"] is success and (success or info["failure_causes"] == ("coverage",))

"""The ARMAR-III wiping scene: model facts from armar3.md, batched kinematics and the path IK."""

import mujoco
import numpy as np
import pytest
from rdmp_gym.envs.ik import PathIK
from rdmp_gym.envs.kinematics import ChainKinematics
from rdmp_gym.envs.robots import ARMAR3
from rdmp_gym.envs.tasks.wiping.legacy.scene import WipeScene
from rdmp_gym.envs.tasks.wiping.scene import TablePose, control_frame, dirt_grid, table_frame

ARM_JOINTS = ARMAR3.joints

# armar3.md §3: joint ranges (the elbow's lower limit clamped to -pi/2) and link masses
LIMITS = {
    "hip_pitch": (-0.7854, 0.7854), "hip_roll": (-0.7854, 0.7854), "hip_yaw": (-0.7854, 0.7854),
    "r_shoulder1": (-1.8665, 1.3963), "r_shoulder2": (-0.2417, 1.6514), "r_upperarm": (-1.8869, 1.2905),
    "r_elbow": (-1.5708, 0.9599), "r_underarm": (-1.2156, 1.8893), "r_wrist1": (-0.5093, 0.5215),
    "r_wrist2": (-0.5393, 0.8878),
}
MASSES = {"r_shoulder1_link": 3.65, "r_shoulder2_link": 2.5, "r_upperarm_link": 1.557, "r_elbow_link": 1.157,
          "r_underarm_link": 2.266, "r_wrist1_link": 1.299, "r_wrist2_link": 0.2}


@pytest.fixture(scope="module")
def scene():
    return WipeScene()


def test_counts_and_options(scene):
    m = scene.model
    # 10 arm hinges + the sponge slide and its two tilt hinges + the obstacle's free joint
    assert m.nu == 10 and m.njnt == 14 and m.nq == 13 + 7
    assert [m.joint(j).name for j in scene.joint_ids] == list(ARM_JOINTS)
    # wrist force(3), torque(3), sponge touch(1), contact sensors sponge-table (found, force 3), robot-table
    # (found), arm-torso and arm-platform (found, distance), arm-obstacle (found)
    assert m.nsensor == 8 and m.nsensordata == 17
    assert [m.sensor(i).name for i in range(m.nsensor)] == ["wrist_force", "wrist_torque", "sponge_touch",
                                                            "sponge_table", "robot_table", "arm_torso",
                                                            "arm_platform", "arm_obstacle"]
    assert m.sensor("wrist_force").objid[0] == m.site("ft_site").id
    assert m.opt.timestep == pytest.approx(0.002)
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    for name in ARM_JOINTS:
        assert m.actuator(name).trnid[0] == m.joint(name).id
    assert np.all(m.actuator_ctrllimited[scene.actuator_ids])
    assert np.all(m.body_gravcomp[m.body("hip_pitch_link").id:m.body("sponge").id + 1] == 1)


def test_limits_and_masses(scene):
    m = scene.model
    for name, (low, high) in LIMITS.items():
        assert m.joint(name).range == pytest.approx([low, high], abs=1e-4)
        assert m.actuator(name).ctrlrange == pytest.approx([low, high], abs=1e-4)
    for name, mass in MASSES.items():
        assert m.body(name).mass[0] == pytest.approx(mass)
    assert 0.8 <= m.body("hand").mass[0] <= 1.0
    assert m.joint("sponge_slide").stiffness[0] == pytest.approx(2500)
    for name in ("sponge_tilt_y", "sponge_tilt_z"):               # the pad's compliant mount
        assert m.joint(name).stiffness[0] > 0 and m.joint(name).range[1] > 0.15


def collide(m, a, b):
    """Whether MuJoCo's bit masks let geoms ``a`` and ``b`` collide."""
    return bool((m.geom_contype[a] & m.geom_conaffinity[b]) or (m.geom_contype[b] & m.geom_conaffinity[a]))


def test_collision_filter(scene):
    """The moving arm (hand, fingers, thumb and sponge included) collides with the table, the floor, the
    robot's torso, head and platform and the obstacle; the arm's own links do not collide with each other."""
    m = scene.model
    arm = [m.geom(n).id for n in ("r_upperarm", "r_forearm", "palm", "fingers", "thumb", "sponge")]
    body = [m.geom(n).id for n in ("torso", "head", "platform")]
    environment = [m.geom(n).id for n in ("table_top", "floor", "obstacle")]
    for a in arm:
        assert all(collide(m, a, g) for g in body + environment), m.geom(a).name
        assert not any(collide(m, a, b) for b in arm if b != a)
    assert not any(collide(m, a, b) for a in body for b in body if a != b)
    assert collide(m, m.geom("obstacle").id, m.geom("table_top").id)


def test_zero_pose_forward_kinematics(scene):
    """armar3.md §3: shoulder (0.123, -0.232, 1.375), wrist (0.383, -0.319, 1.078), TCP (0.513, -0.319, 1.078)."""
    m, d = scene.model, scene.data
    mujoco.mj_resetData(m, d)
    mujoco.mj_kinematics(m, d)
    assert d.body("r_shoulder1_link").xpos == pytest.approx([0.123, -0.232, 1.375], abs=1e-3)
    assert d.body("r_elbow_link").xpos == pytest.approx([0.143, -0.312, 1.076], abs=1e-3)
    assert d.body("r_wrist1_link").xpos == pytest.approx([0.383, -0.319, 1.078], abs=1e-3)
    assert d.site("tcp").xpos == pytest.approx([0.513, -0.319, 1.078], abs=1e-3)
    # palm normal (-x_hand) points up, tilted 15 degrees towards the midline (+y)
    palm = -d.body("hand").xmat.reshape(3, 3)[:, 0]
    assert palm == pytest.approx([0.0, np.sin(np.radians(15)), np.cos(np.radians(15))], abs=1e-4)


def test_batched_kinematics_matches_mujoco(scene):
    m = mujoco.MjModel.from_xml_path(str(scene.xml_file))
    d = mujoco.MjData(m)
    kin = ChainKinematics(m, "sponge_tcp", ARM_JOINTS)
    q = np.random.default_rng(0).uniform(kin.lower, kin.upper, size=(25, kin.n))
    state = kin.forward(q)
    jac_pos, jac_rot = state.jacobian()
    for i in range(len(q)):
        d.qpos[kin.qpos_adr] = q[i]
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        jp, jr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        mujoco.mj_jacSite(m, d, jp, jr, kin.site_id)
        assert state.pos[i] == pytest.approx(d.site_xpos[kin.site_id], abs=1e-12)
        assert state.rot[i].ravel() == pytest.approx(d.site_xmat[kin.site_id], abs=1e-12)
        assert jac_pos[i] == pytest.approx(jp[:, kin.dof_adr], abs=1e-12)
        assert jac_rot[i] == pytest.approx(jr[:, kin.dof_adr], abs=1e-12)
    with pytest.raises(ValueError, match="q"):
        kin.forward(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="site"):
        ChainKinematics(m, "nope")


def test_path_ik_reaches_a_circle_flat_and_within_limits(scene):
    kin = ChainKinematics(scene.model, "sponge_tcp", ARM_JOINTS)
    ik = PathIK(kin, ARMAR3.posture, ARMAR3.mobility)
    t = np.linspace(0, 2 * np.pi, 300)
    path = np.c_[0.05 * np.cos(t), 0.05 * np.sin(t), np.zeros_like(t)]
    parts = scene.parts
    normal = parts.table_rotation[:, 2]
    sol = ik.solve(path @ parts.table_rotation.T + parts.table_origin, normal)
    assert sol.pos_error.max() < 1e-3
    assert np.degrees(sol.rot_error.max()) < 0.5
    assert np.all(sol.q >= kin.lower) and np.all(sol.q <= kin.upper)
    assert np.abs(np.diff(sol.q, axis=0)).max() < 0.05        # continuous along the path
    # normal_dq moves the sponge along the normal: check by finite differences
    state0 = kin.forward(sol.q[:5])
    state1 = kin.forward(sol.q[:5] + 1e-4 * sol.normal_dq[:5])
    assert (state1.pos - state0.pos) / 1e-4 == pytest.approx(np.tile(normal, (5, 1)), abs=5e-3)


def test_table_pose_and_dirt_grid(scene):
    parts, pose = scene.parts, TablePose(0.03, 0.05, -0.04)
    origin, rot = table_frame(parts, pose)
    assert origin[2] == pytest.approx(0.93)
    assert rot @ rot.T == pytest.approx(np.eye(3), abs=1e-12)
    assert control_frame(parts, pose)[0] == pytest.approx(parts.table_origin)     # height unknown to the controller
    assert control_frame(parts, pose)[1] == pytest.approx(rot)                    # tilt known
    assert parts.table_extent == pytest.approx((-0.14, 0.36, -0.45, 0.45))
    cells = dirt_grid(np.array([0.01, -0.02]), np.array([0.12, 0.10]), 0.01)
    assert cells.shape == (120, 2)
    assert cells.mean(axis=0) == pytest.approx([0.01, -0.02])
    with pytest.raises(ValueError, match="cell"):
        dirt_grid(np.zeros(2), np.ones(2), 0.0)
    with pytest.raises(ValueError, match="xml_file"):
        WipeScene(xml_file="/nonexistent/scene.xml")

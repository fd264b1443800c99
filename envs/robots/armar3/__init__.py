"""ARMAR-III (KIT): 3-DoF torso and 7-DoF right arm on a fixed platform, the sponge held beside the hand.

The model (``robot.xml``) is written here from the Simox ArmarIII files (kinematics, limits, link masses);
``legacy_scene.xml`` is the hand-merged scene that ``ArmarWipe-v1`` and ``-v2`` were published with.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np

from ..description import BodyClearanceGeoms, RobotDescription, ToolMount

__all__ = ["ARMAR3"]

_HERE = Path(__file__).resolve().parent


def _spec() -> mujoco.MjSpec:
    return mujoco.MjSpec.from_file(str(_HERE / "robot.xml"))


ARMAR3 = RobotDescription(
    name="armar3",
    spec=_spec,
    joints=("hip_pitch", "hip_roll", "hip_yaw",
            "r_shoulder1", "r_shoulder2", "r_upperarm", "r_elbow", "r_underarm", "r_wrist1", "r_wrist2"),
    root_body="platform",
    arm_root="r_upperarm_link",
    body_links=("torso", "platform"),
    # the pad rolled -70 deg about the hand's z and pitched 10 deg about its y, face out of the little-finger side
    # (a handshake posture keeps the forearm roll and the wrist inside their limits with the face down)
    tool_mount=ToolMount("hand", (-0.0472, 0.0805, 0.0924), (0.81603, 0.04999, 0.07139, -0.57139)),
    ft_site="ft_site",
    hand_geoms=("fingers", "thumb", "palm"),
    # the wiping posture at the nominal patch centre with the torso upright; every joint well inside its limits
    posture=np.array([0.0, 0.0, 0.0, -0.37, 0.10, 0.68, -0.53, 1.18, 0.0, 0.69]),
    # the torso moves little, the hip roll least
    mobility=np.array([0.1, 0.05, 0.1, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]),
    max_joint_speed=3.0,
    max_joint_accel=10.0,
    workspace=(np.array([-0.35, -0.40, -0.05]), np.array([0.35, 0.40, 0.30])),
    body_clearance=BodyClearanceGeoms("torso", "torso", ("r_underarm_link",), ("r_forearm",)),
    legacy_scene=str(_HERE / "legacy_scene.xml"),
)

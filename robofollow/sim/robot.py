"""The bimanual ALOHA as this project builds it: two ViperX 300 s arms facing the table.

Joint order of the 14-D state and action: [left 6, left gripper, right 6, right gripper];
the gripper value is normalised, 1 = open (fingers FINGER_TRAVEL apart from the centre),
0 = closed. Kinematics (link offsets, axes, joint limits) are the ViperX 300 s's.
"""

from __future__ import annotations

import numpy as np

from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.workspace import ARMS, GRIPPER_OPENING

ARM_JOINTS = ("waist", "shoulder", "elbow", "forearm_roll", "wrist_angle", "wrist_rotate")

BASE_YAW = np.pi / 2  # rad: both arms face +y, away from the robot side of the table

# rad: the rest pose both arms start from and return to (gripper high, outside the work area)
HOME = np.array([0.0, -0.96, 1.16, 0.0, -0.3, 0.0])

JOINT_LOW = np.array([-3.14158, -1.85005, -1.76278, -3.14158, -1.8675, -3.14158])
JOINT_HIGH = np.array([3.14158, 1.25664, 1.6057, 3.14158, 2.23402, 3.14158])

FINGER_TRAVEL = GRIPPER_OPENING / 2  # m: each finger's stroke
TCP_OFFSET = 0.13  # m: grasp centre (between the finger pads) along the gripper axis
# m: finger box in the gripper frame (x along the gripper, y the closing axis): its tip
# workspace.FINGERTIP_DEPTH beyond the grasp centre
FINGER = {"x": round(TCP_OFFSET + workspace.FINGERTIP_DEPTH - workspace.FINGER_LENGTH / 2, 9),
          "hx": workspace.FINGER_LENGTH / 2, "hy": workspace.FINGER_THICKNESS / 2,
          "hz": workspace.FINGER_WIDTH / 2}
# m: the palm box in the gripper frame, its underside workspace.PALM_RISE short of the grasp
# centre, 4 cm deep
PALM = {"x": round(TCP_OFFSET - workspace.PALM_RISE - 0.02, 9), "hx": 0.02,
        "hy": workspace.PALM_HALF[0], "hz": workspace.PALM_HALF[1]}

ACTION_LOW = np.concatenate([JOINT_LOW, [0.0], JOINT_LOW, [0.0]])
ACTION_HIGH = np.concatenate([JOINT_HIGH, [1.0], JOINT_HIGH, [1.0]])


def home_state() -> np.ndarray:
    """The 14-D joint target of both arms at rest, grippers open."""
    arm = np.concatenate([HOME, [1.0]])
    return np.concatenate([arm, arm])


def clip_to_limits(actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint targets (14,) or (T, 14) clipped to the joint limits, and which of them (one
    bool per action) had a target past a limit."""
    clipped = np.clip(actions, ACTION_LOW, ACTION_HIGH)
    return clipped, np.any(clipped != actions, axis=-1)


def observed_state(state: np.ndarray) -> np.ndarray:
    """The 14-D state as a policy observes it (env and datasets): within the joint limits,
    float32. Works on one state or a (T, 14) array."""
    return np.clip(state, ACTION_LOW, ACTION_HIGH).astype(np.float32)


JOINT_NAMES = tuple(f"{arm}_{name}" for arm in ARMS
                    for name in [f"joint_{i}" for i in range(len(ARM_JOINTS))] + ["gripper"])

"""Inverse kinematics: damped least squares on mj_jacSite, for a top-down gripper pose.

A target is the grasp centre's position and the gripper's rotation; `top_down(yaw)` is the
grasping rotation: pointing straight down, fingers closing along world x at yaw 0.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from robofollow.sim import robot

DAMPING = 0.03  # damped least squares lambda (m, rad)
MAX_ITERATIONS = 60
POSITION_TOLERANCE = 5e-4  # m
ANGLE_TOLERANCE = 5e-3  # rad
MAX_JOINT_STEP = 0.25  # rad: largest update of one iteration
# rad: IK keeps the forearm roll near zero (elbow up, wrist below it); the joint itself allows more
IK_LOW = np.maximum(robot.JOINT_LOW, [-np.inf, -np.inf, -np.inf, -1.2, -np.inf, -np.inf])
IK_HIGH = np.minimum(robot.JOINT_HIGH, [np.inf, np.inf, np.inf, 1.2, np.inf, np.inf])


def top_down(yaw: float) -> np.ndarray:
    """Rotation matrix (columns: gripper axes in the world) of a downward grasp at `yaw`."""
    approach = np.array([0.0, 0.0, -1.0])
    closing = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    return np.column_stack([approach, closing, np.cross(approach, closing)])


class ArmIK:
    """IK for one arm on a private MjData (the simulation's state is never touched)."""

    def __init__(self, model: mujoco.MjModel, qpos_index, dof_index, site: int):
        self.model, self.data = model, mujoco.MjData(model)
        self.qpos_index, self.dof_index, self.site = qpos_index, dof_index, site
        self.jacp, self.jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))

    def forward(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Grasp-centre position and rotation for joint angles q."""
        self.data.qpos[self.qpos_index] = q
        mujoco.mj_kinematics(self.model, self.data)
        return (self.data.site_xpos[self.site].copy(),
                self.data.site_xmat[self.site].reshape(3, 3).copy())

    def solve(self, position, rotation: np.ndarray, seed: np.ndarray) -> tuple[np.ndarray, float]:
        """Joint angles reaching the pose from `seed`, and the remaining position error (m)."""
        target = np.asarray(position, dtype=float)
        q = np.array(seed, dtype=float)
        model, data = self.model, self.data
        for _ in range(MAX_ITERATIONS):
            position, current = self.forward(q)
            error_p = target - position
            error_r = 0.5 * sum(np.cross(current[:, i], rotation[:, i]) for i in range(3))
            if np.linalg.norm(error_p) < POSITION_TOLERANCE and np.linalg.norm(error_r) < ANGLE_TOLERANCE:
                break
            mujoco.mj_comPos(model, data)
            mujoco.mj_jacSite(model, data, self.jacp, self.jacr, self.site)
            jacobian = np.vstack([self.jacp[:, self.dof_index], self.jacr[:, self.dof_index]])
            error = np.concatenate([error_p, error_r])
            step = jacobian.T @ np.linalg.solve(jacobian @ jacobian.T + DAMPING ** 2 * np.eye(6), error)
            scale = np.max(np.abs(step)) / MAX_JOINT_STEP
            q = np.clip(q + (step / scale if scale > 1 else step), IK_LOW, IK_HIGH)
        position, _ = self.forward(q)
        return q, float(np.linalg.norm(target - position))

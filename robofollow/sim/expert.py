"""The scripted expert: a compiled plan -> a smooth, limit-respecting 14-D joint trajectory.

Plan points are executed in order, one arm moving at a time. Between two points the grasp
centre moves on a straight line and its rotation turns by slerp, both with a smoothstep time
profile at most LINEAR_SPEED (or the point's own speed) / TURN_SPEED, with IK solved at every control step from the
previous solution. Moves from and to `home` go in joint space (leaving home, to the IK
solution of the first point, solved from a seed that faces the target). Gripper changes
happen in place over GRIPPER_STEPS. The trajectory is open loop: it depends only on the plan
and the model.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from robofollow.compiler.planning.plans import Plan
from robofollow.compiler.scene import workspace
from robofollow.sim import robot
from robofollow.sim.ik import ArmIK, top_down
from robofollow.sim.simulation import CONTROL_HZ, Simulation

LINEAR_SPEED = 0.30  # m/s: peak grasp-centre speed is 1.5x this (smoothstep)
TURN_SPEED = 1.5  # rad/s: average gripper rotation speed
JOINT_SPEED = 1.0  # rad/s: average speed of the largest joint on joint-space moves
GRIPPER_STEPS = 10  # control steps to open or close the gripper
DWELL_STEPS = 2  # control steps held at the end of every move
FINAL_STEPS = 20  # control steps held after the last point (the finish stage checks 20)
REACH_SEED = (-0.2, 0.6, 0.0, 1.2, 0.0)  # rad: shoulder .. wrist_rotate, gripper pointing down


def _smoothstep(n: int) -> np.ndarray:
    s = np.arange(1, n + 1) / n
    return s * s * (3 - 2 * s)


def _joint_path(start: np.ndarray, end: np.ndarray) -> list[np.ndarray]:
    steps = max(2, math.ceil(np.max(np.abs(end - start)) / JOINT_SPEED * CONTROL_HZ))
    return [start + s * (end - start) for s in _smoothstep(steps)]


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, rotation.reshape(-1))
    return quat


def _rotation(quat: np.ndarray) -> np.ndarray:
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, quat)
    return matrix.reshape(3, 3)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return 2 * math.acos(min(1.0, abs(float(np.dot(a, b)))))


def _slerp(a: np.ndarray, b: np.ndarray, s: float) -> np.ndarray:
    if np.dot(a, b) < 0:
        b = -b
    angle = math.acos(min(1.0, float(np.dot(a, b))))
    if angle < 1e-6:
        return a
    return (math.sin((1 - s) * angle) * a + math.sin(s * angle) * b) / math.sin(angle)


class Expert:
    """Turns plans into action sequences for one simulation's model."""

    def __init__(self, sim: Simulation):
        self.iks = [ArmIK(sim.model, sim.arm_qpos[a], sim.arm_dof[a], sim.tcp_sites[a])
                    for a in range(2)]

    def actions(self, plan: Plan, start: np.ndarray | None = None,
                hold: int = FINAL_STEPS) -> np.ndarray:
        """The [T, 14] joint targets executing `plan` from the command `start` (default: home,
        grippers open), ending with `hold` steps holding the last target (float32 values)."""
        command = robot.home_state() if start is None else np.array(start, dtype=float)
        at_home = [bool(np.allclose(command[7 * a:7 * a + 6], robot.HOME)) for a in range(2)]
        actions: list[np.ndarray] = []
        for point in plan.points:
            arm = workspace.ARMS.index(point.arm)
            joints = slice(7 * arm, 7 * arm + 6)
            start = command[joints].copy()
            yaw = math.radians(point.yaw_degrees)
            if point.position is None:
                path = _joint_path(start, robot.HOME)
            elif at_home[arm]:
                path = _joint_path(start, self.reach(arm, np.array(point.position), yaw))
            else:
                path = self._cartesian(self.iks[arm], start, np.array(point.position), yaw,
                                       point.speed or LINEAR_SPEED)
            at_home[arm] = point.position is None
            gripper = command[7 * arm + 6]
            ramp = np.linspace(gripper, point.gripper, len(path) + 1)[1:] if path else []
            for q, g in zip(path, ramp, strict=True):
                command[joints], command[7 * arm + 6] = q, g
                actions.append(command.copy())
            if not path and gripper != point.gripper:
                for g in np.linspace(gripper, point.gripper, GRIPPER_STEPS + 1)[1:]:
                    command[7 * arm + 6] = g
                    actions.append(command.copy())
            actions += [command.copy()] * DWELL_STEPS
        actions += [command.copy()] * hold
        # float32 targets, as a policy sends them: a recorded demonstration's (float32)
        # actions replay to exactly the same trajectory
        return np.array(actions, dtype=np.float32).astype(np.float64)

    def reach(self, arm: int, target: np.ndarray, yaw: float) -> np.ndarray:
        """IK for a pose reached from home: seeded facing the target, wrist pointing down."""
        base_x, base_y = workspace.BASE_XY[workspace.ARMS[arm]]
        waist = math.atan2(-(target[0] - base_x), target[1] - base_y)  # the base faces +y
        seed = np.array([waist, *REACH_SEED])
        solutions = [self.iks[arm].solve(target, top_down(y), seed) for y in (yaw, yaw + math.pi)]
        return min(solutions, key=lambda s: s[1] + 0.01 * abs(s[0][5]))[0]

    def _cartesian(self, ik: ArmIK, start: np.ndarray, target: np.ndarray, yaw: float,
                   speed: float) -> list:
        position, rotation = ik.forward(start)
        begin = _quaternion(rotation)
        ends = [_quaternion(top_down(yaw)), _quaternion(top_down(yaw + math.pi))]
        end = min(ends, key=lambda q: _angle(begin, q))  # symmetric fingers: the nearer one
        distance, turn = float(np.linalg.norm(target - position)), _angle(begin, end)
        if distance < 1e-4 and turn < 1e-3:
            return []
        steps = max(2, math.ceil(max(distance / speed, turn / TURN_SPEED) * CONTROL_HZ))
        path, q = [], start
        for s in _smoothstep(steps):
            q, _ = ik.solve(position + s * (target - position), _rotation(_slerp(begin, end, s)), q)
            path.append(q)
        return path

"""One MuJoCo scene layout with the robot: build, reset to an episode start, step, read state.

Control: 14-D absolute joint targets [left 6, left gripper, right 6, right gripper], gripper
normalised (1 open, 0 closed), held for SUBSTEPS physics steps of TIMESTEP each, i.e. a fixed
control rate of CONTROL_HZ. Arm joints are position actuators with gravity compensation.
"""

from __future__ import annotations

import copy
from functools import lru_cache

import mujoco
import numpy as np

from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import World, sample_offsets
from robofollow.errors import RoboFollowError
from robofollow.sim import robot
from robofollow.sim.mjcf import SPAWN_LIFT, TIMESTEP, scene_xml

CONTROL_HZ = 25  # control steps per second
SUBSTEPS = round(1.0 / (CONTROL_HZ * TIMESTEP))  # physics steps per control step
SETTLE_STEPS = 300  # physics steps objects get to come to rest at episode start
STABLE_DRIFT = 0.01  # m: most an object may move while settling
STABLE_TILT_DEG = 5.0  # deg: most an object may rotate while settling


class UnstableLayoutError(RoboFollowError):
    """A layout that does not come to rest: an object slid, fell or toppled while settling."""


@lru_cache(maxsize=32)
def _compiled(xml: str) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_string(xml)


class Simulation:
    """The physics of one layout; `reset` places the bodies for an episode seed."""

    def __init__(self, scene: Scene, layout: str, width: int = 320, height: int = 240):
        self.scene, self.layout = scene, layout
        # a private copy: episodes move fixtures by editing body_pos
        self.model = copy.copy(_compiled(scene_xml(scene, layout, width, height)))
        self.data = mujoco.MjData(self.model)
        model = self.model
        self.bodies = list(scene.layouts[layout].placed)  # every body of the layout, in order
        self.movable = [b for b in self.bodies if not scene.bodies[b].fixture]
        self.body_ids = np.array([model.body(b).id for b in self.bodies])
        self.free_qpos = {b: model.jnt_qposadr[model.joint(b).id] for b in self.movable}
        self.arm_qpos = np.array([[model.jnt_qposadr[model.joint(f"{arm}/{j}").id]
                                   for j in robot.ARM_JOINTS] for arm in workspace.ARMS])
        self.arm_dof = np.array([[model.jnt_dofadr[model.joint(f"{arm}/{j}").id]
                                  for j in robot.ARM_JOINTS] for arm in workspace.ARMS])
        self.finger_qpos = np.array([[model.jnt_qposadr[model.joint(f"{arm}/finger_{s}").id]
                                      for s in "ab"] for arm in workspace.ARMS])
        self.arm_ctrl = np.array([[model.actuator(f"{arm}/{j}").id for j in robot.ARM_JOINTS]
                                  for arm in workspace.ARMS])
        self.finger_ctrl = np.array([[model.actuator(f"{arm}/finger_{s}").id for s in "ab"]
                                     for arm in workspace.ARMS])
        self.tcp_sites = np.array([model.site(f"{arm}/tcp").id for arm in workspace.ARMS])
        self.start_world: World | None = None

    # -- episode start ---------------------------------------------------------------------

    def reset(self, seed: int | None) -> World:
        """Place the layout with the seed's jitter (none for seed None: nominal positions),
        arms at home, and let it settle.

        Returns the world as settled (measured positions). Raises UnstableLayoutError naming
        the object if anything drifts or tilts beyond the named tolerances while settling.
        """
        model, data = self.model, self.data
        offsets = (sample_offsets(self.scene, self.layout, np.random.default_rng(seed))
                   if seed is not None else {})
        world = World(self.scene, self.layout, offsets)
        mujoco.mj_resetData(model, data)
        for body, body_id in zip(self.bodies, self.body_ids, strict=True):
            pose = world.poses[body]
            if body in self.free_qpos:
                adr = self.free_qpos[body]
                data.qpos[adr:adr + 7] = (pose.x, pose.y, pose.z + SPAWN_LIFT, 1, 0, 0, 0)
            else:  # fixtures are static bodies: every reset places each of them
                model.body_pos[body_id] = (pose.x, pose.y, pose.z)
        for index in range(2):
            data.qpos[self.arm_qpos[index]] = robot.HOME
            data.qpos[self.finger_qpos[index]] = robot.FINGER_TRAVEL
        self.apply(robot.home_state())
        mujoco.mj_forward(model, data)
        start = self.positions()
        for _ in range(SETTLE_STEPS):
            mujoco.mj_step(model, data)
        self._check_settled(start)
        data.time = 0.0
        self.start_world = self.world()
        return self.start_world

    def _check_settled(self, start: np.ndarray) -> None:
        end, quats = self.positions(), self.quaternions()
        for i, body in enumerate(self.bodies):
            drift = float(np.linalg.norm(end[i] - start[i]))
            tilt = np.degrees(2 * np.arccos(min(1.0, abs(float(quats[i][0])))))
            if drift > STABLE_DRIFT + SPAWN_LIFT or tilt > STABLE_TILT_DEG:
                raise UnstableLayoutError(
                    f"layout {self.scene.id}/{self.layout} is not stable: {body} moved "
                    f"{drift * 100:.1f} cm and turned {tilt:.1f} deg while settling "
                    f"(limits {STABLE_DRIFT * 100:.1f} cm, {STABLE_TILT_DEG:.0f} deg)")

    # -- control -----------------------------------------------------------------------------

    def apply(self, action: np.ndarray) -> None:
        """Set the 14-D joint target (not stepped)."""
        ctrl = self.data.ctrl
        for index in range(2):
            arm = action[7 * index:7 * index + 7]
            ctrl[self.arm_ctrl[index]] = arm[:6]
            ctrl[self.finger_ctrl[index]] = float(np.clip(arm[6], 0.0, 1.0)) * robot.FINGER_TRAVEL

    def step(self, action: np.ndarray) -> None:
        """One control step: apply the target and run SUBSTEPS physics steps."""
        self.apply(action)
        mujoco.mj_step(self.model, self.data, nstep=SUBSTEPS)

    # -- state -------------------------------------------------------------------------------

    def state(self) -> np.ndarray:
        """The measured 14-D joint state (gripper normalised from the finger opening)."""
        qpos = self.data.qpos
        fingers = np.clip(qpos[self.finger_qpos].mean(axis=1) / robot.FINGER_TRAVEL, 0.0, 1.0)
        return np.concatenate([qpos[self.arm_qpos[0]], fingers[:1],
                               qpos[self.arm_qpos[1]], fingers[1:]])

    def positions(self) -> np.ndarray:
        return self.data.xpos[self.body_ids].copy()

    def quaternions(self) -> np.ndarray:
        return self.data.xquat[self.body_ids].copy()

    def world(self) -> World:
        """The layout's bodies where they are now."""
        positions = {b: tuple(p) for b, p in zip(self.bodies, self.positions(), strict=True)}
        return World(self.scene, self.layout, positions=positions)


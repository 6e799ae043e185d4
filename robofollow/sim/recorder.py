"""Per-control-step recording of a Simulation into a plain numpy Trajectory."""

from __future__ import annotations

import mujoco
import numpy as np

from robofollow.compiler.scene import workspace
from robofollow.sim.simulation import CONTROL_HZ, Simulation
from robofollow.trajectory import CONTACT_EXTRAS, Trajectory


class Recorder:
    """Collects frames: call `frame(action)` after every control step (and once at start)."""

    def __init__(self, sim: Simulation, meta: dict | None = None):
        self.sim, self.meta = sim, dict(meta or {}, control_hz=CONTROL_HZ)
        model = sim.model
        names = list(sim.bodies) + list(CONTACT_EXTRAS)
        group = {model.body(b).id: names.index(b) for b in sim.bodies}
        for arm in workspace.ARMS:
            gripper = names.index(f"{arm}_gripper")
            for part in ("gripper_link", "finger_a", "finger_b"):
                group[model.body(f"{arm}/{part}").id] = gripper
        self.geom_group = np.array([group.get(int(model.geom_bodyid[g]), -1)
                                    for g in range(model.ngeom)])
        self.geom_group[model.geom("table").id] = names.index("table")
        self.fingers = [(model.geom(f"{arm}/finger_a").id, model.geom(f"{arm}/finger_b").id)
                        for arm in workspace.ARMS]
        self.size = len(names)
        self.frames: dict[str, list] = {k: [] for k in (
            "time", "state", "action", "positions", "quaternions", "ee_positions",
            "ee_quaternions", "grasped", "contacts")}

    def frame(self, action: np.ndarray) -> None:
        sim, data, frames = self.sim, self.sim.data, self.frames
        frames["time"].append(data.time)
        frames["state"].append(sim.state())
        frames["action"].append(np.asarray(action, dtype=float).copy())
        frames["positions"].append(sim.positions())
        frames["quaternions"].append(sim.quaternions())
        frames["ee_positions"].append(data.site_xpos[sim.tcp_sites].copy())
        quats = np.zeros((2, 4))
        for arm, site in enumerate(sim.tcp_sites):
            mujoco.mju_mat2Quat(quats[arm], data.site_xmat[site])
        frames["ee_quaternions"].append(quats)
        pairs = data.contact.geom[:data.ncon]  # (contacts, 2) geom ids
        groups = self.geom_group[pairs]
        first, second = groups[:, 0], groups[:, 1]
        between = (first >= 0) & (second >= 0) & (first != second)
        contacts = np.zeros((self.size, self.size), dtype=bool)
        contacts[first[between], second[between]] = True
        contacts[second[between], first[between]] = True
        held = [self._held(pairs, groups, fingers) for fingers in self.fingers]
        frames["grasped"].append(held)
        frames["contacts"].append(contacts)

    def _held(self, pairs: np.ndarray, groups: np.ndarray, fingers: tuple[int, int]) -> int:
        """The body (contact group below len(bodies)) both fingers of a gripper touch, or -1."""
        common = None
        for finger in fingers:
            touched = set(groups[pairs[:, 0] == finger, 1]) | set(groups[pairs[:, 1] == finger, 0])
            common = touched if common is None else common & touched
        bodies = [int(g) for g in common if 0 <= g < len(self.sim.bodies)]
        return min(bodies) if bodies else -1

    def trajectory(self) -> Trajectory:
        frames = {k: np.array(v) for k, v in self.frames.items()}
        frames["grasped"] = frames["grasped"].astype(np.int16)
        movable = np.array([b in self.sim.movable for b in self.sim.bodies])
        return Trajectory(bodies=tuple(self.sim.bodies), movable=movable, meta=self.meta, **frames)

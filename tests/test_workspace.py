"""The arm workspace model (compiler/scene/workspace.py) against the simulated arm's IK: a point the
model calls reachable is reached; one well beyond its reach is not."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robofollow.compiler.scene import workspace
from robofollow.sim.expert import REACH_SEED, Expert
from robofollow.sim.ik import top_down
from robofollow.sim.simulation import Simulation
from tests.sim_helpers import benchmark

SOLVED = 2e-3  # m: IK position error that counts as reached


@pytest.fixture(scope="module")
def expert():
    scene = benchmark().spec.scenes["scene1"]
    return Expert(Simulation(scene, "default")), scene.table_height


def _error(expert, arm: str, point) -> float:
    solver, table = expert
    base_x, base_y = workspace.BASE_XY[arm]
    seed = np.array([math.atan2(-(point[0] - base_x), point[1] - base_y), *REACH_SEED])
    return solver.iks[workspace.ARMS.index(arm)].solve(np.array(point), top_down(0.0), seed)[1]


def _points(table: float):
    """Grasp points fanning out from the left arm's base, at several heights."""
    base_x, base_y = workspace.BASE_XY["left"]
    for rise in (0.01, 0.05, 0.10, 0.20, 0.30):
        for angle in (0, 30, 60, 90, 120):
            for planar in np.arange(0.10, 0.80, 0.02):
                a = math.radians(angle)
                yield (base_x + planar * math.cos(a), base_y + planar * math.sin(a), table + rise)


def test_the_model_is_conservative_and_close_to_the_arm(expert):
    _, table = expert
    inside = beyond = 0
    for point in _points(table):
        problem = workspace.reach_problem("left", point, table)
        if problem is None:
            inside += 1
            assert _error(expert, "left", point) < SOLVED, point
        elif "stretch" in problem and workspace.reach_problem("left", point, table,
                                                              slack=-0.04) is not None:
            beyond += 1  # 4 cm or more beyond the model's reach: the arm cannot get there
            assert _error(expert, "left", point) > SOLVED, point
    assert inside > 80 and beyond > 80


def test_the_gripper_geometry_is_the_simulated_one(expert):
    """The finger and palm sizes the compiler's clearance rule uses are the model's boxes."""
    solver, _ = expert
    model = solver.iks[0].model
    finger = model.geom("left/finger_a")
    palm = model.geom("left/palm")
    tcp = model.site("left/tcp").pos[0]
    assert finger.size[1] * 2 == pytest.approx(workspace.FINGER_THICKNESS)
    assert finger.size[2] * 2 == pytest.approx(workspace.FINGER_WIDTH)
    assert finger.size[0] * 2 == pytest.approx(workspace.FINGER_LENGTH)
    assert finger.pos[0] + finger.size[0] - tcp == pytest.approx(workspace.FINGERTIP_DEPTH)
    assert tuple(palm.size[1:]) == pytest.approx(workspace.PALM_HALF)
    assert tcp - (palm.pos[0] + palm.size[0]) == pytest.approx(workspace.PALM_RISE)

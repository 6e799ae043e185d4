"""Scene building, episode start (jitter, settling, stability) and rendering."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.scene import workspace
from robofollow.errors import SpecErrors
from robofollow.scoring import score_recording
from robofollow.sim import robot
from robofollow.sim.cameras import CAMERA_NAMES, Cameras
from robofollow.sim.mjcf import FLOOR_HEIGHT
from robofollow.sim.simulation import STABLE_DRIFT, Simulation, UnstableLayoutError
from tests.judged import Script
from tests.sim_helpers import benchmark

LAYOUTS = [(s.id, layout) for s in benchmark().spec.scenes.values() for layout in s.layouts]


@pytest.mark.parametrize("scene, layout", LAYOUTS)
def test_every_layout_builds_and_settles(scene, layout):
    spec_scene = benchmark().spec.scenes[scene]
    sim = Simulation(spec_scene, layout)
    model = sim.model
    assert model.nu == 16  # 6 joints + 2 fingers per arm
    assert {model.camera(i).name for i in range(model.ncam)} >= set(CAMERA_NAMES)
    world = sim.reset(7)
    for body, pose in world.poses.items():
        placed = spec_scene.layouts[layout].placed[body]
        jitter = spec_scene.jitter_of(body if placed.support is None else placed.support)
        margin = STABLE_DRIFT + 0.003
        assert jitter.x[0] - margin <= pose.x - placed.x <= jitter.x[1] + margin, body
        assert jitter.y[0] - margin <= pose.y - placed.y <= jitter.y[1] + margin, body
        assert abs(pose.z - placed.z) <= 0.004, body


def test_robot_has_the_viperx_joint_limits():
    sim = Simulation(benchmark().spec.scenes["scene1"], "default")
    for arm in workspace.ARMS:
        for name, low, high in zip(robot.ARM_JOINTS, robot.JOINT_LOW, robot.JOINT_HIGH, strict=True):
            joint = sim.model.joint(f"{arm}/{name}")
            assert tuple(joint.range) == pytest.approx((low, high))
            assert sim.model.jnt_limited[joint.id]


def test_same_seed_same_start_and_other_seed_other_start():
    scene = benchmark().spec.scenes["scene4"]
    a, b = Simulation(scene, "scene4_1"), Simulation(scene, "scene4_1")
    a.reset(11)
    b.reset(11)
    assert np.array_equal(a.data.qpos, b.data.qpos)
    assert np.array_equal(a.model.body_pos, b.model.body_pos)  # the jittered bowl too
    b.reset(12)
    assert not np.allclose(a.positions(), b.positions())


def test_nominal_start_without_seed():
    scene = benchmark().spec.scenes["scene1"]
    world = Simulation(scene, "default").reset(None)
    for body, placed in scene.layouts["default"].placed.items():
        assert world.poses[body].x == pytest.approx(placed.x, abs=2e-3)
        assert world.poses[body].y == pytest.approx(placed.y, abs=2e-3)


UNSTABLE = """\
scene wobbly "A cube beyond the table's edge" {
    object box cube half=0.02 color=blue rgb=(0, 0, 1) mass=0.2 friction=0.5
    layout edge {
        box at (0.0, 0.2)
    }
    task pick_box on edge {
        "Pick up the blue cube with your left arm."
        expect pick left box
    }
}
"""


def test_an_infeasible_layout_fails_naming_the_object(tmp_path):
    """The compiler refuses a body off the table; a layout that slips past it (built here by
    hand) still fails in the simulator, naming the body."""
    (tmp_path / "wobbly.rf").write_text(UNSTABLE.replace("(0.0, 0.2)", "(0.0, 0.31)"))
    with pytest.raises(SpecErrors) as refused:
        load_spec(tmp_path)
    assert "box at (0, 0.31) can leave the table" in refused.value.errors[0].message
    (tmp_path / "wobbly.rf").write_text(UNSTABLE)
    scene = load_spec(tmp_path).scenes["wobbly"]
    layout = scene.layouts["edge"]
    beyond = layout.model_copy(update={"placed": {"box": layout.placed["box"].model_copy(
        update={"y": 0.31})}})  # the table's far edge is at y = 0.30
    scene = scene.model_copy(update={"layouts": {"edge": beyond}})
    with pytest.raises(UnstableLayoutError, match=r"wobbly/edge is not stable: box moved"):
        Simulation(scene, "edge").reset(0)


def test_a_body_knocked_off_the_table_comes_to_rest_on_the_floor_off_the_table():
    """The floor the table stands on catches what falls off: a block dropped just past the
    table's right edge after the task lands there, finite and still; only movable objects
    touch the floor; and the scorer calls the block off the table (the finish is lost, the
    placement asked for stands)."""
    script = Script("scene1/L0/place_yellow_block_1_behind_red_cylinder#r1").perform()
    rollout, sim, body = script.rollout, script.sim, "yellow_block_3"
    rollout.execute(script.actions)
    _, y, z = sim.positions()[sim.bodies.index(body)]
    edge = workspace.TABLE_SIZE[0] / 2
    at = sim.free_qpos[body]
    sim.data.qpos[at:at + 3] = (edge + 0.03, y, z + 0.01)  # just past the edge, still high
    mujoco.mj_forward(sim.model, sim.data)
    rollout.execute([script.command.copy()] * 100)  # 4 s
    trajectory = rollout.recorder.trajectory()
    column = trajectory.bodies.index(body)
    heights = trajectory.positions[:, column, 2]
    half = benchmark().spec.scenes["scene1"].bodies[body].half_extents
    assert np.all(np.isfinite(heights)) and heights.min() > FLOOR_HEIGHT
    assert heights[-1] == pytest.approx(FLOOR_HEIGHT + half[2], abs=0.003)
    dof = sim.model.jnt_dofadr[sim.model.joint(body).id]
    assert np.linalg.norm(sim.data.qvel[dof:dof + 6]) < 0.01  # at rest
    model, floor = sim.model, sim.model.geom("floor").id
    movable = {model.body(b).id for b in sim.movable}
    for geom in range(model.ngeom):  # the robot, the table and the fixtures never touch it
        touches = (model.geom_contype[geom] & model.geom_conaffinity[floor]
                   or model.geom_contype[floor] & model.geom_conaffinity[geom])
        assert bool(touches) == (model.geom_bodyid[geom] in movable), model.geom(geom).name
    result = score_recording(benchmark(), script.record, trajectory)
    assert result.complete and result.intent_score == result.execution_score == 0.8
    finish = result.stages[-1]
    assert finish.name == "finish" and f"{body} fell off the table" in finish.reason, finish
    assert f"{body} fell off the table" in result.executed_behaviour.description


def _dominant(pixel: np.ndarray) -> str:
    r, g, b = (int(v) for v in pixel)
    if r > g + 60 and r > b + 60:
        return "red"
    if g > r + 60 and g > b + 60:
        return "green"
    if b > r + 60 and b > g + 60:
        return "blue"
    if r > b + 60 and g > b + 60:
        return "yellow"
    return "other"


@pytest.mark.parametrize("scene, layout", [("scene1", "default"), ("scene2", "scene2_3"),
                                           ("scene3", "scene3_1"), ("scene4", "scene4_7")])
def test_each_object_shows_its_colour_where_it_projects_in_cam_high(scene, layout):
    spec_scene = benchmark().spec.scenes[scene]
    sim = Simulation(spec_scene, layout)
    world = sim.reset(3)
    with Cameras(sim) as cameras:
        image = cameras.render("cam_high")
        assert image.shape == (240, 320, 3) and image.dtype == np.uint8
        placed = spec_scene.layouts[layout].placed
        covered = {p.support for p in placed.values() if p.support}  # something on or in it
        for body, pose in world.poses.items():
            if body in covered:
                continue
            top = (pose.x, pose.y, world.top(body) - 0.002)
            u, v = cameras.project("cam_high", top)
            patch = image[int(v) - 1:int(v) + 2, int(u) - 1:int(u) + 2].reshape(-1, 3)
            colour = _dominant(np.median(patch, axis=0))
            assert colour == spec_scene.bodies[body].color, (body, u, v, colour)


def test_images_are_identical_for_identical_states_and_sizes_configurable():
    scene = benchmark().spec.scenes["scene2"]
    sim = Simulation(scene, "default", 160, 120)
    sim.reset(5)
    with Cameras(sim, 160, 120) as cameras:
        first = cameras.images()
        sim.reset(5)
        again = cameras.images()
        for name in CAMERA_NAMES:
            assert first[name].shape == (120, 160, 3)
            assert np.array_equal(first[name], again[name])
        assert not np.array_equal(first["cam_high"], first["cam_left_wrist"])
        mujoco.mj_step(sim.model, sim.data)  # stays renderable after stepping
        assert cameras.render("cam_high").std() > 10  # a real picture, not a blank frame

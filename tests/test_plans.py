"""Expert plans: waypoints from geometry for every action kind."""

import math
from pathlib import Path

import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.planning.plans import (
    PLACE_GAP,
    PUSH_FACE,
    PUSH_RUN_UP,
    PUSH_SPEED,
    PUSH_TRAVEL,
    plan,
)
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.training import check_training

SPECS = Path(__file__).resolve().parent.parent / "specs"


@pytest.fixture(scope="module")
def setup():
    spec = load_spec(SPECS)
    return spec, check_training(spec)


def planned(setup, label):
    spec, training = setup
    task = next(t for t in spec.tasks if t.label == label)
    world = World(spec.scenes[task.scene], task.layout)
    return plan(training[label], world), world


def names(points):
    return [p.name for p in points]


def test_every_training_task_has_a_plan_above_the_table(setup):
    spec, training = setup
    for task in spec.tasks:
        world = World(spec.scenes[task.scene], task.layout)
        result = plan(training[task.label], world)
        assert result.points
        for point in result.points:
            assert point.position is None or point.position[2] >= world.table
        arms = {s.arm for s in training[task.label].steps}
        assert {p.arm for p in result.points} == arms
        assert all(any(p.name == "home" for p in result.of(arm)) for arm in arms)


def test_pickup_grasps_the_object_and_holds_it_home(setup):
    result, world = planned(setup, "pickup_yellow_block_1_left")
    assert names(result.points) == ["pre_grasp", "grasp", "close", "lift", "home"]
    pose = world.poses["yellow_block_1"]
    assert result.points[1].position == pytest.approx((pose.x, pose.y, pose.z))
    assert result.points[-1].gripper == 0.0


def test_relative_placement_lands_beside_the_landmark(setup):
    result, world = planned(setup, "place_yellow_block_1_behind_red_cylinder")
    place = next(p for p in result.points if p.name == "place")
    landmark = world.poses["red_cylinder"]
    assert place.position[0] == pytest.approx(landmark.x)
    assert place.position[1] - landmark.y == pytest.approx(0.025 + 0.02 + PLACE_GAP)
    assert names(result.points)[-4:] == ["place", "release", "retreat", "home"]


def test_stack_and_bowl_release_above_the_support(setup):
    stack, world = planned(setup, "stack_left_cube_on_red_cylinder")
    place = next(p for p in stack.points if p.name == "place")
    assert place.position[2] > world.top("large_red_cylinder") + 0.03
    bowl, world = planned(setup, "place_right_cube_in_green_bowl")
    place = next(p for p in bowl.points if p.name == "place")
    assert math.dist(place.position[:2], (0.07, -0.10)) < 1e-9


def test_routes_pass_over_the_right_slab_and_end_at_the_yaw(setup):
    via, _ = planned(setup, "r_pick2_via4_to6_long_front")
    assert [p.position[:2] for p in via.points if p.name == "via"] == [(0.01, -0.17)]
    assert next(p for p in via.points if p.name == "place").yaw_degrees == 90.0
    around, _ = planned(setup, "l_pick5_around2_to1_short_right")
    assert [p.position[:2] for p in around.points if p.name == "via"] == [(-0.09, -0.09)]


def test_push_starts_behind_the_object_and_moves_towards_the_target(setup):
    result, world = planned(setup, "push_left_cube_to_red_cylinder")
    start = next(p for p in result.points if p.name == "push_start").position
    end = next(p for p in result.points if p.name == "push_end").position
    source, target = world.poses["large_blue_cube"], world.poses["large_red_cylinder"]
    assert start[1] < source.y < target.y
    touch = world.bodies["large_blue_cube"].half_extents[1] + PUSH_FACE  # the cube's face
    assert source.y - start[1] == pytest.approx(touch + PUSH_RUN_UP)
    assert end[1] - (source.y - touch) == pytest.approx(PUSH_TRAVEL)  # fingers past touching
    assert next(p for p in result.points if p.name == "push_end").speed == PUSH_SPEED


def test_a_relative_placement_avoids_a_taken_spot(setup):
    """Right of the red cylinder in scene1_1 is where yellow_block_1 stands: the place spot
    moves on, still right of the cylinder, clear of the block."""
    spec, _ = setup
    scene = spec.scenes["scene1"]
    world = World(scene, "scene1_1")
    step = Step(action="place", arm="right", source="yellow_block_3", relation="right_of",
                target="red_cylinder")
    place = next(p for p in plan(Behaviour(steps=(step,)), world).points if p.name == "place")
    block, cylinder = world.poses["yellow_block_1"], world.poses["red_cylinder"]
    assert max(abs(place.position[0] - block.x), abs(place.position[1] - block.y)) >= 0.05
    moved = World(scene, "scene1_1", positions={"yellow_block_3": place.position})
    assert moved.related("yellow_block_3", "right_of", "red_cylinder")
    assert cylinder.x < place.position[0]


def test_sequences_hold_both_objects_until_both_are_up(setup):
    result, _ = planned(setup, "s41_seq_r_green_cylinder_then_l_bowl")
    assert [(p.arm, p.name) for p in result.points][-2:] == [("right", "home"), ("left", "home")]
    assert [p.arm for p in result.points if p.name == "grasp"] == ["right", "left"]


def test_unstacking_grasps_at_the_stacked_height(setup):
    result, world = planned(setup, "s41_r_unstack_green_cylinder_to_slot6")
    grasp = next(p for p in result.points if p.name == "grasp")
    assert grasp.position[2] == pytest.approx(world.poses["green_cylinder"].z)
    place = next(p for p in result.points if p.name == "place")
    assert place.position[0] > world.poses["red_sphere"].x

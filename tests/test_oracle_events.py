"""The physical events the stages are judged on, on hand-made trajectories (no physics):
holds, closes, pushes, rest, surfaces and tilt."""

from __future__ import annotations

import math

import numpy as np
import pytest

from robofollow.compiler.planning.profile import DEFAULT_PROFILE
from robofollow.compiler.scene.world import World
from robofollow.oracle.recording import Recording
from robofollow.trajectory import CONTACT_EXTRAS, Trajectory, tilt
from tests.sim_helpers import benchmark

FRAMES = 60
SCENE = benchmark().spec.scenes["scene2"]  # large_blue_cube: 6 cm; small_red_cube: 4 cm
FAR = np.array([[-0.3, -0.35, 1.0], [0.3, -0.35, 1.0]])  # both grasp centres, away from it all


def made(**change) -> Trajectory:
    """Scene 2's default layout standing still for FRAMES frames, arms far away, fingers open;
    `change` replaces arrays."""
    world = World(SCENE, "default")
    bodies = tuple(world.poses)
    positions = np.array([[world.poses[b].x, world.poses[b].y, world.poses[b].z]
                          for b in bodies])
    size = len(bodies) + len(CONTACT_EXTRAS)
    arrays = dict(
        movable=np.array([not SCENE.bodies[b].fixture for b in bodies]),
        time=np.arange(FRAMES) / 25.0, state=np.ones((FRAMES, 14)), action=np.ones((FRAMES, 14)),
        positions=np.repeat(positions[None], FRAMES, axis=0),
        quaternions=np.tile([1.0, 0.0, 0.0, 0.0], (FRAMES, len(bodies), 1)),
        ee_positions=np.repeat(FAR[None], FRAMES, axis=0),
        ee_quaternions=np.tile([1.0, 0.0, 0.0, 0.0], (FRAMES, 2, 1)),
        grasped=np.full((FRAMES, 2), -1, dtype=np.int16),
        contacts=np.zeros((FRAMES, size, size), dtype=bool))
    arrays.update(change)
    return Trajectory(bodies=bodies, meta={"layout": "default"}, **arrays)


def recording(trajectory: Trajectory) -> Recording:
    return Recording(trajectory, SCENE, DEFAULT_PROFILE)


def with_grasp(body: str, start: int, end: int, opening: float, before: float = 1.0,
               arm: int = 0) -> Trajectory:
    """Both fingers of `arm` on `body` over [start, end), the measured opening `before` until
    then and `opening` after."""
    base = made()
    grasped, state = base.grasped.copy(), base.state.copy()
    grasped[start:end, arm] = base.bodies.index(body)
    state[:, 6 + 7 * arm] = before
    state[start - 5:, 6 + 7 * arm] = np.linspace(before, opening, 6).tolist() + [opening] * (
        FRAMES - start - 1)
    return made(grasped=grasped, state=state)


def test_a_hold_is_a_body_between_fingers_that_closed_onto_it():
    rec = recording(with_grasp("small_red_cube", 20, 40, 0.53))  # 4 cm between 7.5 cm fingers
    [hold] = rec.holds(0)
    assert (hold.body, hold.start, hold.end) == (rec.index("small_red_cube"), 20, 40)
    assert rec.holding(0)[19] == -1 and rec.holding(0)[20] == rec.index("small_red_cube")


def test_shut_fingertips_on_a_body_and_a_body_prising_them_open_are_not_holds():
    assert not recording(with_grasp("large_blue_cube", 20, 40, 0.05)).holds(0)  # 6 cm cube
    pried = with_grasp("large_blue_cube", 20, 40, 0.8, before=0.0)  # opened by the cube
    assert not recording(pried).holds(0)
    assert recording(with_grasp("large_blue_cube", 20, 40, 0.8)).holds(0)  # closed onto it


def test_a_grasp_flickering_off_briefly_is_one_hold_and_fixtures_are_never_held():
    trajectory = with_grasp("small_red_cube", 20, 40, 0.53)
    grasped = trajectory.grasped.copy()
    grasped[30:32, 0] = -1  # two frames without contact
    assert len(recording(made(grasped=grasped, state=trajectory.state)).holds(0)) == 1
    bowl = with_grasp("green_bowl", 20, 40, 0.53)
    assert not recording(bowl).holds(0)


def test_a_close_goes_from_open_to_shut_near_a_body_within_reach():
    cube = made().positions[0, made().bodies.index("small_red_cube")]
    ee, state = made().ee_positions.copy(), made().state.copy()
    ee[:, 0] = cube + [0.0, 0.0, 0.05]  # 5 cm above the cube's centre
    state[30:, 6] = 0.0
    [attempt] = recording(made(ee_positions=ee, state=state)).attempts(0)
    assert (attempt.kind, attempt.frame, attempt.distance) == ("close", 30, pytest.approx(0.05))
    ee[:, 0] = cube + [0.0, 0.0, 0.15]  # 15 cm above: out of reach
    assert not recording(made(ee_positions=ee, state=state)).attempts(0)


def test_fingers_prised_open_for_an_instant_do_not_close_when_they_spring_back():
    state = made().state.copy()
    state[10:, 6] = 0.0  # shut in free air
    state[30:33, 6] = 0.8  # prised open for three frames
    rec = recording(made(state=state))
    assert rec.closes(0).tolist() == [10]
    state[30:40, 6] = 0.8  # open for ten frames: a real open, then a real close
    assert recording(made(state=state)).closes(0).tolist() == [10, 40]


def test_a_push_is_a_body_starting_to_move_with_an_arm_at_it():
    base = made()
    cube = base.index("small_red_cube")
    positions, ee = base.positions.copy(), base.ee_positions.copy()
    ee[20:, 0] = positions[0, cube] - [0.04, 0.0, 0.0]
    for frame in range(25, FRAMES):  # the cube slides 1 mm a frame from frame 25
        positions[frame, cube, 0] += 0.001 * (frame - 24)
        ee[frame, 0, 0] += 0.001 * (frame - 24)
    [push] = recording(made(positions=positions, ee_positions=ee)).pushes()
    assert (push.arm, push.body, push.kind, push.frame) == (0, cube, "push", 29)
    far = recording(made(positions=positions)).pushes()  # moving with no arm near: not a push
    assert far == ()


def test_rest_surface_and_tilt():
    base = made()
    cube, cylinder = base.index("small_red_cube"), base.index("large_red_cylinder")
    positions = base.positions.copy()
    positions[:30, cube, 2] += np.linspace(0.145, 0.0, 30)  # falling 5 mm a frame to frame 29
    rec = recording(made(positions=positions))
    assert rec.settled(cube, 0) == 29  # then still: moving less than 2 mm over 5 frames
    above = rec.heights_above_surface(cube, slice(0, 1))[0]
    assert above == pytest.approx(0.145)
    positions[:, cube, :2] = positions[0, cylinder, :2]  # over the cylinder, on its top
    positions[:, cube, 2] = rec.top(cylinder)[0] + 0.02
    assert recording(made(positions=positions)).heights_above_surface(
        cube, slice(0, 1))[0] == pytest.approx(0.0)
    quaternions = base.quaternions.copy()
    quaternions[-1, cylinder] = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]
    assert recording(made(quaternions=quaternions)).tilt_deg(cylinder) == pytest.approx(90.0)
    yawed = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]  # turned, not tipped
    assert float(tilt(np.array([1.0, 0, 0, 0]), np.array(yawed))) == pytest.approx(0.0)

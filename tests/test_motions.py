"""Motions: what a step does, compared within tolerances, whoever it is done to."""

from __future__ import annotations

from robofollow.compiler.planning.motions import Repertoire, differences, motion
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.world import World
from tests.sim_helpers import benchmark


def _scene1():
    compiled = benchmark()
    scene = compiled.spec.scenes["scene1"]
    return scene, Repertoire(scene, compiled.training)


def _swapped(scene, a: str, b: str) -> World:
    """Scene 1's default layout with bodies a and b trading places."""
    nominal = World(scene, "default")
    poses = {name: (p.x, p.y, p.z) for name, p in nominal.poses.items()}
    poses[a], poses[b] = poses[b], poses[a]
    return World(scene, "default", positions=poses)


def pick(arm: str, body: str) -> Behaviour:
    return Behaviour(steps=(Step(action="pick", arm=arm, source=body),))


def test_a_trained_motion_on_another_identical_block_is_trained():
    scene, repertoire = _scene1()
    world = _swapped(scene, "yellow_block_1", "yellow_block_3")
    # training picks yellow_block_1 with the right arm where yellow_block_3 now stands
    assert repertoire.covers(pick("right", "yellow_block_3"), world, compose=False)
    assert repertoire.missing(pick("right", "yellow_block_3"), World(scene, "default"),
                              compose=False) is None  # trained there too


def test_a_trained_identity_at_an_untrained_place_is_new():
    scene, repertoire = _scene1()
    world = _swapped(scene, "yellow_block_2", "green_sphere")
    # training picks yellow_block_2 with the left arm, but at (-14, -18) cm, not (-2, -18)
    message = repertoire.missing(pick("left", "yellow_block_2"), world, compose=False)
    assert message and "new pick location: from the table at (-2.0, -18.0, 76.0) cm" in message


def test_differences_name_every_part_that_changed():
    scene, _ = _scene1()
    world = World(scene, "default")
    base = motion(Step(action="pick", arm="left", source="yellow_block_1"), world)
    other = motion(Step(action="pick", arm="right", source="red_sphere"), world)
    assert differences(base, base) == []
    assert differences(other, base) == ["arm", "object", "pick location"]


def test_without_training_tasks_nothing_is_in_the_repertoire():
    scene = benchmark().spec.scenes["scene1"]
    assert Repertoire(scene, {}).missing(pick("left", "yellow_block_1"), World(scene, "default"),
                                         compose=True) == \
        "pick left yellow_block_1: the scene has no checked training task"


def test_a_push_at_an_untrained_place_names_where_it_starts_not_a_pick_location():
    scene, repertoire = _scene1()
    push = Behaviour(steps=(Step(action="push", arm="left", source="yellow_block_2",
                                 target="red_cylinder"),))
    message = repertoire.missing(push, _swapped(scene, "yellow_block_2", "green_sphere"),
                                 compose=False)
    assert message and "new push start: from the table at" in message, message
    assert "pick location" not in message

"""Physical sanity at compile time (compiler/planning/feasibility.py): the open fingers clear every
neighbour at the jitter extremes, a bowl takes one object, a stack's top comes to rest. Each
rule on hand-made specs: the problem itself, a training task refused at its line, a listed test
task reported by `robofollow audit --tasks`."""

from __future__ import annotations

import json

import pytest

from robofollow.cli import main
from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.planning.feasibility import (
    FINGER_MARGIN,
    OPEN_FINGER_REACH,
    infeasible,
    stack_friction_bound,
)
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.training import check_training
from robofollow.errors import SpecErrors

SPEC = """\
scene demo "Demo" {
    object red_cube    cube     half=0.02                      color=red    rgb=(1, 0, 0)  mass=0.2 friction=FRICTION
    object blue_cube   cube     half=0.02                      color=blue   rgb=(0, 0, 1)  mass=0.2 friction=FRICTION
    object yellow_pin  cylinder radius=PIN half_height=0.02     color=yellow rgb=(1, 1, 0)  mass=0.2 friction=FRICTION
    fixture bowl       bowl     radius=0.05 half_height=0.02   color=green  rgb=(0, 1, 0)
    jitter * x=[-0.005, 0.005] y=[-0.005, 0.005]
    layout base {
        red_cube   at (-0.12, -0.05)
        blue_cube  at (0.12, -0.05)
        yellow_pin at (0.0, -0.05)
        bowl       at (0.0, -0.20)
    }
    layout close from base { move blue_cube to (-0.06, -0.05) }
    layout full from base { put red_cube in bowl }
    layout swapped from base { swap red_cube blue_cube }
    task pick_red on base {
        "Pick up the red cube with your left arm."
    }
    split L1 layouts=(close, full, swapped) rounds=10 seed=42
}
"""


def spec_text(friction: float = 0.1, pin: float = 0.02) -> str:
    return SPEC.replace("FRICTION", f"{friction:g}").replace("PIN", f"{pin:g}")


def scene(tmp_path, text: str):
    (tmp_path / "demo.rf").write_text(text)
    return load_spec(tmp_path).scenes["demo"]


def problems(tmp_path, layout: str, *steps: Step, **spec) -> list[str]:
    return infeasible(Behaviour(steps=steps), World(scene(tmp_path, spec_text(**spec)), layout))


PICK_RED = Step(action="pick", arm="left", source="red_cube")


def test_the_open_fingers_reach_is_the_simulated_gripper():
    # half the 7.5 cm opening plus a 0.6 cm finger; a 2 cm cube's neighbour along the closing
    # axis is knocked in simulation at 6.1 cm, untouched at 6.5 cm (see feasibility.py)
    assert OPEN_FINGER_REACH == pytest.approx(0.0435)
    assert 0.061 < 0.02 + OPEN_FINGER_REACH + FINGER_MARGIN <= 0.065


def test_fingers_that_would_strike_a_neighbour_are_infeasible(tmp_path):
    assert problems(tmp_path, "base", PICK_RED) == []
    [problem] = problems(tmp_path, "close", PICK_RED)
    assert problem.startswith("step 1 (pick left red_cube): the left arm's open fingers sweep ")
    assert "into blue_cube at jitter extreme " in problem and "(0.1 cm clear needed)" in problem


def test_a_neighbour_clear_only_at_the_nominal_positions_is_caught_at_its_jitter_extreme(
        tmp_path):
    # 6.5 cm apart: 0.15 cm clear at the nominal positions, 6.0 cm with either body alone at
    # its jitter extreme
    text = spec_text().replace("move blue_cube to (-0.06, -0.05)",
                               "move blue_cube to (-0.055, -0.05)")
    world = World(scene(tmp_path, text), "close")
    [problem] = infeasible(Behaviour(steps=(PICK_RED,)), world)
    assert "at jitter extreme" in problem and "alone moved" in problem
    assert "nominal" not in problem


def test_a_pushing_gripper_is_checked_along_its_sweep(tmp_path):
    push = Step(action="push", arm="left", source="red_cube", target="yellow_pin")
    assert problems(tmp_path, "base", push) == []
    text = spec_text().replace("move blue_cube to (-0.06, -0.05)",
                               "move blue_cube to (-0.17, -0.05)")
    [problem] = infeasible(Behaviour(steps=(push,)), World(scene(tmp_path, text), "close"))
    assert "the left arm's closed fingers" in problem and "blue_cube" in problem


def test_a_body_moved_by_an_earlier_step_is_no_longer_in_the_way(tmp_path):
    first = Step(action="pick", arm="right", source="blue_cube")  # held from then on
    found = problems(tmp_path, "close", first, PICK_RED)
    assert found and all(p.startswith("step 1 ") for p in found)
    assert any("into red_cube" in p for p in found)


def test_a_placement_into_an_occupied_bowl_is_infeasible(tmp_path):
    place = Step(action="place", arm="right", source="blue_cube", relation="in", target="bowl")
    assert problems(tmp_path, "base", place) == []
    assert problems(tmp_path, "full", place) == [
        "bowl is already occupied by red_cube; blue_cube has no room in it"]
    first = Step(action="place", arm="left", source="red_cube", relation="in", target="bowl")
    assert problems(tmp_path, "base", first, place) == [
        "bowl is already occupied by red_cube; blue_cube has no room in it"]
    # taken out first: room again
    out = Step(action="place", arm="left", source="red_cube", relation="left_of",
               target="bowl")
    assert not [p for p in problems(tmp_path, "full", out, place) if "occupied" in p]


STACK = Step(action="place", arm="left", source="red_cube", relation="on", target="yellow_pin")


def test_equal_low_friction_stacks_rest(tmp_path):
    # measured: two equal cubes stay stacked down to friction 0.001, the lowest a spec allows
    on_cube = Step(action="place", arm="left", source="red_cube", relation="on",
                   target="blue_cube")
    assert problems(tmp_path, "base", on_cube, friction=0.001) == []
    assert stack_friction_bound(0.02) < 0.001


def test_a_top_on_a_pin_narrower_than_the_placing_error_cannot_rest(tmp_path):
    [problem] = problems(tmp_path, "base", STACK, pin=0.0005)
    assert problem == ("red_cube would not rest on yellow_pin: its top leaves 0.05 cm around "
                       "the centre, within the expert's 0.05 cm placing error")


def test_a_low_friction_top_on_a_narrow_support_slides_off(tmp_path):
    assert problems(tmp_path, "base", STACK, pin=0.003) == []  # friction 0.1
    # measured: a 4 cm cube on a 2 or 4 mm wide pin falls off at friction 0.001
    [problem] = problems(tmp_path, "base", STACK, pin=0.002, friction=0.001)
    assert problem == ("red_cube would slide off yellow_pin: at friction 0.001 it slides 0.5 cm "
                       "after release, and yellow_pin's top leaves 0.2 cm (friction 0.0034 or "
                       "more needed)")


# a training task per rule: (layout edit, instruction, the message's start)
TRAINING = [
    ("close", "Pick up the red cube with your left arm.",
     "the expert cannot do this: step 1 (pick left red_cube): the left arm's open fingers"),
    ("full", "Use your right arm to pick up the blue cube and place it in the green bowl.",
     "the expert cannot do this: bowl is already occupied by red_cube"),
    ("base", "Use your left arm to stack the red cube onto the yellow cylinder.",
     "the expert cannot do this: red_cube would slide off yellow_pin"),
]


@pytest.mark.parametrize("layout, instruction, message", TRAINING,
                         ids=["fingers", "occupied", "stack"])
def test_an_infeasible_training_task_is_a_located_error(tmp_path, layout, instruction, message):
    text = spec_text(friction=0.001, pin=0.003).replace(
        'task pick_red on base {\n        "Pick up the red cube with your left arm."',
        f'task bad on {layout} {{\n        "{instruction}"')
    tested = ", ".join(name for name in ("close", "full", "swapped") if name != layout)
    text = text.replace("layouts=(close, full, swapped)", f"layouts=({tested})")  # (a training
    (tmp_path / "demo.rf").write_text(text)  # layout is no changed layout to test on)
    with pytest.raises(SpecErrors) as caught:
        check_training(load_spec(tmp_path))
    [error] = caught.value.errors
    line = text[:text.index("task bad")].count("\n") + 1
    assert (error.code, error.line, error.column) == ("infeasible", line, 10)
    assert error.message.startswith(message), error.message
    rendered = error.render().splitlines()
    assert rendered[0].startswith(f"{error.file}:{line}:10: error[infeasible]: ")
    assert rendered[-1].strip() == "^^^"


def test_the_task_audit_reports_each_rule(tmp_path, capsys):
    specs = tmp_path / "specs"
    specs.mkdir()
    (specs / "demo.rf").write_text(spec_text(friction=0.001, pin=0.003))
    listed = tmp_path / "tasks.jsonl"
    tasks = [{"id": f"t{i}", "scene": "demo", "level": "L1", "layout": layout,
              "instruction": instruction} for i, (layout, instruction, _) in enumerate(TRAINING)]
    tasks[2]["layout"] = "swapped"  # an L1 task stands on a test layout
    listed.write_text("".join(json.dumps(t) + "\n" for t in tasks))
    assert main(["audit", str(specs), "--tasks", str(listed), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    found = {(f["id"], f["kind"]): f["message"] for f in report["findings"]}
    assert "open fingers" in found[("t0", "infeasible")]
    assert found[("t1", "infeasible")] == ("bowl is already occupied by red_cube; blue_cube has "
                                           "no room in it")
    assert "red_cube would slide off yellow_pin" in found[("t2", "infeasible")]

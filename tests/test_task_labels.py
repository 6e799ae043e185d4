"""The two labels of an L1/L3 test task, judged: `motion` (the expert's motion changed) and
`object_moved` (a handled body stands elsewhere than the training task's did). They answer
different questions; the task files carry both."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from robofollow.benchmark.labels import labels
from robofollow.benchmark.pipeline import compile_specs
from robofollow.compiler.scene.spec import MOTION_LEVELS

SPECS = Path(__file__).resolve().parent.parent / "specs"
COMPILED = compile_specs(SPECS)
TASKS = {task.id: task for task in COMPILED.splits.tasks}


def _labels(task_id: str) -> dict:
    task = TASKS[task_id]
    return labels(COMPILED.spec.scenes[task.scene], task, COMPILED.training)


@pytest.mark.parametrize(("task_id", "motion", "object_moved", "why"), [
    # the rightmost cube stands where it stood in training; the green bowl moved, so the put
    # place, and the motion, changed
    ("scene2/L1/place_right_cube_in_green_bowl@scene2_5", "moved", False, "the bowl moved"),
    # the slab is picked where it lay in training; the slab to avoid moved, so the route did
    ("scene3/L1/l_pick5_around2_to1_short_right@scene3_1", "moved", False, "the route moved"),
    # "the block to the right of the red ball" is another block on the changed layout
    ("scene1/L1/pickup_yellow_block_1_right@scene1_1", "moved", True, "another block"),
    # the reworded pickup of the right cube on scene2_1: the same cube, in the same place
    ("scene2/L3/pickup_right_cube@scene2_1/referents-bfa87e46", "as-trained", False,
     "nothing it handles moved"),
])
def test_judged_labels(task_id, motion, object_moved, why):
    assert _labels(task_id) == {"motion": motion, "object_moved": object_moved}, why


def test_every_task_has_both_labels_where_they_apply_and_a_moved_object_moves_the_motion():
    counts = {"moved": 0, "object stays": 0}
    for task in COMPILED.splits.tasks:
        found = _labels(task.id)
        if task.level not in MOTION_LEVELS:
            assert found == {"motion": None, "object_moved": None}, task.id
            continue
        assert found["motion"] in ("moved", "as-trained"), task.id
        assert isinstance(found["object_moved"], bool), task.id
        if found["object_moved"]:  # the grasp moves with the object
            assert found["motion"] == "moved", task.id
        if task.level == "L1" and found["motion"] == "moved":
            counts["moved"] += 1
            counts["object stays"] += not found["object_moved"]
    assert counts["moved"] > counts["object stays"] > 0


def test_the_task_files_carry_both_labels(tmp_path):
    out = tmp_path / "out"
    subprocess.run(["robofollow", "compile", str(SPECS / "scene2.rf"), "--out", str(out),
                    "--no-verify"], check=True, capture_output=True)
    rows = {row["task"]: row for row in map(json.loads, (out / "tasks" / "scene2_L1.jsonl")
                                               .read_text().splitlines())}
    row = rows["scene2/L1/place_right_cube_in_green_bowl@scene2_5"]
    assert (row["motion"], row["object_moved"]) == ("moved", False)
    first_l0 = json.loads((out / "tasks" / "scene2_L0.jsonl").read_text().splitlines()[0])
    assert (first_l0["motion"], first_l0["object_moved"]) == (None, None)

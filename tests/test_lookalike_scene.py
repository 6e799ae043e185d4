"""A new scene family beside the shipped specs: three identical-looking yellow cubes, two
square labels, layouts that swap or move referents, listed tests and L1-L3 rules with a max. It compiles clean
beside the shipped four scenes, and theirs stay what they are compiled alone; a layout where
only look-alikes trade places is an error where a rule tests on it."""

from __future__ import annotations

import shutil

from robofollow.audit.report import FINDING_KEYS, findings
from robofollow.benchmark.pipeline import compile_specs
from robofollow.cli import main
from robofollow.resources import builtin_specs

SHIPPED = ("scene1", "scene2", "scene3", "scene4")

SCENE5 = """\
# Scene 5: look-alike objects and labels.
# Three identical yellow cubes beside three distinct objects and two square labels: a
# description that fits a yellow cube is ambiguous unless its place picks one out.
scene scene5 "Look-alike objects and labels" {
    object red_cube cube half=0.02 color=red rgb=(1, 0, 0) mass=0.2 friction=0.5
    object blue_cylinder cylinder radius=0.02 half_height=0.025 color=blue rgb=(0.1, 0.1, 1.0)
        mass=0.2 friction=0.5
    object green_cube cube half=0.02 color=green rgb=(0, 0.8, 0) mass=0.2 friction=0.5
    object yellow_cube_1 cube half=0.02 color=yellow rgb=(1.0, 0.85, 0.1) mass=0.2 friction=0.5
    object yellow_cube_2 cube half=0.02 color=yellow rgb=(1.0, 0.85, 0.1) mass=0.2 friction=0.5
    object yellow_cube_3 cube half=0.02 color=yellow rgb=(1.0, 0.85, 0.1) mass=0.2 friction=0.5
    fixture red_label  label half=(0.03, 0.03, 0.001) color=red  rgb=(0.8, 0.0, 0.0)
    fixture blue_label label half=(0.03, 0.03, 0.001) color=blue rgb=(0.1, 0.3, 0.95)

    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]

    layout default {
        red_cube      at (-0.14, -0.05)
        blue_cylinder at (-0.03, -0.05)
        green_cube    at (0.08, -0.05)
        yellow_cube_1 at (-0.14, -0.17)
        yellow_cube_2 at (-0.03, -0.17)
        yellow_cube_3 at (0.08, -0.17)
        red_label     at (0.18, -0.05)
        blue_label    at (0.18, -0.17)
    }
    layout scene5_1 from default { swap red_cube blue_cylinder }
    layout scene5_2 from default { swap red_cube yellow_cube_1 }
    layout scene5_3 from default { swap red_label blue_label }
    layout scene5_4 from default { move green_cube to (-0.25, -0.11) }
    layout scene5_same from default { swap yellow_cube_1 yellow_cube_3 }

    split L0 rounds=2 seed=5
    split L1 layouts=(scene5_1, scene5_2, scene5_3, scene5_4) max=12 rounds=2 seed=5
    split L2 wordings=(referents) max=16 rounds=2 seed=5
    split L3 layouts=(scene5_1, scene5_2, scene5_3, scene5_4)
        wordings=(referents) max=12 rounds=2 seed=5

    task s5_pickup_red_cube on default {
        "Use your left arm to pick up the red cube."
        "Grasp the red cube with your left arm."
        "Use your left arm to pick up the red block."
        expect pick left red_cube
    }
    task s5_pickup_blue_cylinder on default {
        "Use your left arm to pick up the blue cylinder."
        "Grasp the blue cylinder with your left arm."
        expect pick left blue_cylinder
    }
    task s5_pickup_left_yellow_cube on default {
        "Use your left arm to pick up the leftmost yellow cube."
        expect pick left yellow_cube_1
    }
    task s5_red_cube_on_red_label on default {
        "Use your right arm to pick up the red cube and place it on the red label."
        expect place right red_cube on red_label
    }
    task s5_green_cube_on_blue_label on default {
        "Use your right arm to pick up the green cube and place it on the blue label."
        expect place right green_cube on blue_label
    }
    task s5_push_red_cube_to_blue_cylinder on default {
        "Use your left arm to push the red cube towards the blue cylinder."
        expect push left red_cube towards blue_cylinder
    }

    test L1 blue_cylinder_beside_yellow on scene5_2 {
        "Use your left arm to pick up the blue cylinder."
        expect pick left blue_cylinder
    }
    test L2 the_cylinder on default {
        "Use your left arm to pick up the cylinder."
        expect pick left blue_cylinder
    }
    test L3 the_cylinder_labels_swapped on scene5_3 {
        "Use your left arm to pick up the cylinder."
        expect pick left blue_cylinder
    }
}
"""


def _tasks(compiled, scene: str) -> list[dict]:
    return [t.model_dump(mode="json") for t in compiled.splits.tasks if t.scene == scene]


def test_a_look_alike_scene_compiles_clean_beside_the_shipped_specs(tmp_path):
    folder = tmp_path / "specs"
    folder.mkdir()
    for path in sorted(builtin_specs().glob("*.rf")):
        shutil.copy(path, folder / path.name)
    (folder / "scene5.rf").write_text(SCENE5)
    assert main(["compile", str(folder), "--out", str(tmp_path / "out"), "--no-verify"]) == 0
    compiled = compile_specs(folder)  # (the CLI's compile, cached for this folder's state)
    report = compiled.report
    assert findings(report) == 0, {key: report[key] for key in FINDING_KEYS if report[key]}
    assert list(compiled.spec.scenes) == [*SHIPPED, "scene5"]
    counts = report["counts"]["scene5"]
    assert all(counts[level] > 0 for level in ("L0", "L1", "L2", "L3")), counts
    rules = compiled.spec.scenes["scene5"].splits
    assert all(counts[level] <= rules[level].max_tasks for level in ("L1", "L2", "L3"))
    scene5 = [t for t in compiled.splits.tasks if t.scene == "scene5"]
    assert {t.id for t in scene5 if t.wording == "listed"} == {
        "scene5/L1/blue_cylinder_beside_yellow", "scene5/L2/the_cylinder",
        "scene5/L3/the_cylinder_labels_swapped"}
    assert any("yellow" in t.instruction for t in scene5 if t.level == "L2")
    alone = compile_specs(builtin_specs())
    for scene in SHIPPED:
        assert _tasks(compiled, scene) == _tasks(alone, scene), scene
        assert compiled.split_digests[scene] == alone.split_digests[scene]
    (tmp_path / "scene5.rf").write_text(SCENE5)
    by_itself = compile_specs([tmp_path / "scene5.rf"])
    assert _tasks(by_itself, "scene5") == _tasks(compiled, "scene5")
    assert by_itself.split_digests["scene5"] == compiled.split_digests["scene5"]



def test_a_layout_where_only_look_alikes_trade_places_is_an_error(tmp_path, capsys):
    spec = tmp_path / "scene5.rf"
    spec.write_text(SCENE5.replace("scene5_4) max=12", "scene5_4, scene5_same) max=12"))
    assert main(["compile", str(spec), "--out", str(tmp_path / "out"), "--no-verify"]) == 1
    err = capsys.readouterr().err
    assert f"{spec}:31:12: error[looks-like-training]: layout scene5_same looks the same as " \
        "the training layout default" in err
    assert "Traceback" not in err

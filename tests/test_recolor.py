"""`recolor BODY COLOUR rgb=(r, g, b)`: a body's colour in a layout and the layouts derived from
it, read by grounding, the look-alike check, VQA and the simulator; its errors are located."""

from __future__ import annotations

import numpy as np
import pytest

from robofollow import cli
from robofollow.benchmark.pipeline import compile_specs
from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language.parser import parse
from robofollow.compiler.scene.grounding import ground
from robofollow.compiler.scene.observation import look_alike, same_observation
from robofollow.compiler.scene.world import World
from robofollow.sim.objects import FIELDS, observe_objects
from robofollow.sim.simulation import Simulation
from robofollow.vqa.answers import named

# `repainted` gives each cube the other's colour: it looks like `swapped`, not like `default`
SPEC = """\
scene recolour "Two cubes that trade colours" {
    object red_cube cube half=0.02 color=red rgb=(1, 0, 0) mass=0.2 friction=0.1
    object blue_cube cube half=0.02 color=blue rgb=(0, 0, 1) mass=0.2 friction=0.1
    fixture bowl bowl radius=0.05 half_height=0.02 color=green rgb=(0, 1, 0)
    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]
    layout default {
        red_cube at (-0.1, 0.0)
        blue_cube at (0.1, 0.0)
        bowl at (0.0, -0.15)
    }
    layout swapped from default { swap red_cube blue_cube }
    layout repainted from default {
        recolor red_cube blue rgb=(0, 0, 1)
        recolor blue_cube red rgb=(1, 0, 0)
    }
    layout repainted_moved from repainted {
        move bowl to (0.0, -0.2)
        recolor bowl yellow rgb=(1, 0.85, 0.1)
    }
    task pick_red on default {
        "Use your left arm to pick up the red cube."
        expect pick left red_cube
    }
    task pick_blue on default {
        "Use your left arm to pick up the blue cube."
        expect pick left blue_cube
    }
    split L1 layouts=(repainted, repainted_moved) rounds=2
}
"""
RULE = "split L1 layouts=(repainted, repainted_moved)"


def _compile(folder, text=SPEC):
    folder.mkdir()
    (folder / "recolour.rf").write_text(text)
    return compile_specs(folder)


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    return _compile(tmp_path_factory.mktemp("recolor") / "specs")


def test_a_layout_and_those_derived_from_it_show_the_new_colours(compiled):
    scene = compiled.spec.scenes["recolour"]
    assert scene.bodies["red_cube"].color == "red"  # the scene's body is unchanged
    for layout in ("repainted", "repainted_moved"):
        bodies = World(scene, layout).bodies
        assert (bodies["red_cube"].color, bodies["red_cube"].rgb) == ("blue", (0.0, 0.0, 1.0))
        assert (bodies["blue_cube"].color, bodies["blue_cube"].rgb) == ("red", (1.0, 0.0, 0.0))
        assert named(World(scene, layout), "red_cube").text == "blue cube"  # VQA's answer
    assert World(scene, "repainted").bodies["bowl"].color == "green"
    assert World(scene, "repainted_moved").bodies["bowl"].color == "yellow"
    assert World(scene, "default").bodies["red_cube"].color == "red"


def test_grounding_on_a_recoloured_layout_follows_the_new_colour(compiled):
    scene = compiled.spec.scenes["recolour"]
    form = parse("Use your left arm to pick up the red cube.")
    assert ground(form, World(scene, "default")).steps[0].source == "red_cube"
    assert ground(form, World(scene, "repainted")).steps[0].source == "blue_cube"
    tasks = {t.id: t for t in compiled.splits.of("recolour", "L1")}
    assert tasks["recolour/L1/pick_red@repainted"].behaviour.steps[0].source == "blue_cube"
    assert tasks["recolour/L1/pick_blue@repainted_moved"].behaviour.steps[0].source == "red_cube"
    assert {t.motion for t in tasks.values()} == {"moved"}


def test_the_look_alike_check_sees_the_colours(compiled, tmp_path):
    scene = compiled.spec.scenes["recolour"]
    assert not same_observation(scene, "default", "repainted")
    assert look_alike(scene, "repainted", ("default", "swapped")) == "swapped"
    assert not same_observation(scene, "repainted", "repainted_moved")
    # listed after `swapped`, the repainted layout is a duplicate of it
    other = _compile(tmp_path / "specs", SPEC.replace(RULE, "split L1 layouts=(swapped, "
                                                      "repainted)"))
    kept = {t.layout for t in other.splits.of("recolour", "L1")}
    assert kept == {"swapped"}
    assert any(r.layout == "repainted" and r.reason.startswith("duplicate")
               for r in other.splits.rejected)


def test_the_simulator_renders_the_layout_s_colours(compiled):
    scene = compiled.spec.scenes["recolour"]
    default = Simulation(scene, "default").model
    moved = Simulation(scene, "repainted_moved").model
    np.testing.assert_allclose(default.geom("red_cube").rgba, (1, 0, 0, 1))
    np.testing.assert_allclose(moved.geom("red_cube").rgba, (0, 0, 1, 1))
    np.testing.assert_allclose(moved.geom("blue_cube").rgba, (1, 0, 0, 1))
    np.testing.assert_allclose(moved.geom("bowl_floor").rgba, (1, 0.85, 0.1, 1))


def test_the_colours_count_in_the_scene_s_digest(compiled, tmp_path):
    """(A layout that recolours nothing leaves them out: the shipped specs keep their digests,
    test_split_independence.py.)"""
    (tmp_path / "a.rf").write_text(SPEC.replace("red rgb=(1, 0, 0)\n", "red rgb=(0.9, 0, 0)\n"))
    changed = load_spec(tmp_path).scenes["recolour"]
    assert changed.layouts["repainted"].colours["blue_cube"].rgb == (0.9, 0.0, 0.0)
    assert changed.digest != compiled.spec.scenes["recolour"].digest


MARK = "«"
COLOURS = "red, green, blue, yellow, orange, purple, pink, white, black, gray, brown"


@pytest.mark.parametrize("old,new,code,message", [
    ("recolor red_cube blue", f"recolor {MARK}red_cub blue", "unknown-object",
     "no object named red_cub; did you mean 'red_cube'?"),
    ("recolor red_cube blue", f"recolor red_cube {MARK}bleu", "bad-value",
     f"unknown colour bleu; did you mean 'blue'? (colours: {COLOURS})"),
    ("recolor red_cube blue rgb=(0, 0, 1)", f"recolor red_cube {MARK}red rgb=(0.8, 0, 0)",
     "same-colour", "red_cube is already red in this layout"),
    ("move bowl to (0.0, -0.2)", f"recolor red_cube {MARK}blue rgb=(0.1, 0.1, 0.9)",
     "same-colour", "red_cube is already blue in this layout"),  # inherited from repainted
    ("recolor red_cube blue rgb=(0, 0, 1)", f"recolor red_cube {MARK}green rgb=(0, 0, 1)",
     "colour-mismatch", ("red_cube recoloured green looks the same as blue_cube (kind, size, "
                         "rgb), which is called blue")),
    ("recolor red_cube blue rgb=(0, 0, 1)", f"recolor red_cube {MARK}orange rgb=(1, 0.01, 0)",
     "colour-mismatch", ("red_cube recoloured orange looks the same as red_cube did (kind, "
                         "size, rgb), which is called red")),
    ("move bowl to (0.0, -0.2)", f"remove bowl\n        recolor {MARK}bowl blue rgb=(0, 0, 1)",
     "not-in-layout", "bowl is not in this layout"),
    ("recolor red_cube blue rgb=(0, 0, 1)", f"recolor red_cube blue {MARK}rgb=(0, 1)",
     "bad-value", "rgb takes 3 numbers in [0, 1]: (n, n, n)"),
    ("recolor red_cube blue rgb=(0, 0, 1)", f"recolor red_cube blue {MARK}}}", "syntax",
     "unexpected } (expected: 'rgb')"),
])
def test_a_bad_recolor_is_reported_where_it_is_written(tmp_path, capsys, old, new, code,
                                                         message):
    assert old in SPEC
    marked = SPEC.replace(old, new, 1)
    at = marked.index(MARK)
    line, column = marked.count("\n", 0, at) + 1, at - marked.rfind("\n", 0, at)
    folder = tmp_path / "specs"
    folder.mkdir()
    (folder / "bad.rf").write_text(marked.replace(MARK, ""))
    status = cli.main(["compile", str(folder), "--out", str(tmp_path / "out"), "--no-verify"])
    err = capsys.readouterr().err
    assert status == 1 and "Traceback" not in err
    assert err.splitlines()[0] == f"{folder / 'bad.rf'}:{line}:{column}: error[{code}]: {message}"


def test_the_objects_observation_reports_the_layout_s_colours(compiled):
    scene = compiled.spec.scenes["recolour"]
    colours = {}
    for layout in ("default", "swapped", "repainted"):
        sim = Simulation(scene, layout)
        sim.reset(None)
        rows = observe_objects(sim)
        red, blue = FIELDS.index("red"), FIELDS.index("blue")
        colours[layout] = [tuple(row[red:blue + 1]) for row in rows[:3]]  # by x: left first
    assert colours["default"][0] == colours["repainted"][0][::-1] == (1.0, 0.0, 0.0)
    assert colours["repainted"] == colours["swapped"]  # it looks like `swapped` ...
    assert colours["repainted"] != colours["default"]  # ... not like `default`

"""The shortcuts the split generator takes give what the plain computation gives:

- the jitter check asks once for the worlds where no body a form reads has moved, and shares
  what reads no position among a layout's jittered worlds: its verdict (case, error or the
  objects picked instead) is the one of trying every world with fresh grounders;
- one Realizer speaking many forms (its phrases memoised) says what a fresh one says;
- a style is not tried on a conditional one of whose branches it cannot say in training words:
  the splits and rejections are those of trying every style.
"""

from __future__ import annotations

from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.language.realize import STYLES, Realizer, realize
from robofollow.compiler.scene.grounding import (
    Grounder,
    GroundingError,
    first_unstable,
    position_reads,
)
from robofollow.compiler.scene.world import CORNERS, World, jitter_worlds
from tests.sim_helpers import benchmark


def _every_world(form, grounders, expected, first_case):
    """The jitter verdict without shortcuts: every world, each grounder on its own."""
    objects = tuple((s.source, s.target) for s in expected.steps)
    for index, grounder in enumerate(grounders, start=first_case):
        try:
            picked = Grounder(grounder.world).objects(form)
        except GroundingError as error:
            return index, error.code, error.message
        if picked != objects:
            return index, picked
    return None


def _verdict(unstable):
    if unstable is None:
        return None
    if unstable.error is not None:
        return unstable.case, unstable.error.code, unstable.error.message
    return unstable.case, unstable.objects


def test_jitter_verdicts_match_trying_every_world():
    compiled = benchmark()
    grounders: dict[tuple[str, str], list[Grounder]] = {}
    verdicts = {"stable": 0, "unstable": 0}
    for task in compiled.splits.tasks:
        scene = compiled.spec.scenes[task.scene]
        for layout in scene.layouts:  # its own (stable by construction) and the others
            if (task.scene, layout) not in grounders:
                still: dict = {}
                grounders[task.scene, layout] = [Grounder(w, still)
                                                 for w in jitter_worlds(scene, layout)]
            worlds = grounders[task.scene, layout]
            for first in (1, 1 + len(CORNERS)):  # every jittered world; those of one body
                quick = _verdict(first_unstable(task.form, worlds[first:], task.behaviour,
                                                first))
                assert quick == _every_world(task.form, worlds[first:], task.behaviour,
                                             first), (task.id, layout, first)
                verdicts["stable" if quick is None else "unstable"] += 1
    assert verdicts["stable"] > 2_000 and verdicts["unstable"] > 1_000, verdicts


def test_a_world_knows_which_bodies_it_moved():
    compiled = benchmark()
    scene = compiled.spec.scenes["scene4"]
    layout = next(name for name, placed in scene.layouts.items()
                  if any(p.support is not None for p in placed.placed.values()))
    placed = scene.layouts[layout].placed
    carrier, carried = next((p.support, body) for body, p in placed.items()
                            if p.support is not None)
    assert World(scene, layout).shifted == set()
    assert World(scene, layout, {carrier: (0.0, 0.0)}).shifted == set()
    moved = World(scene, layout, {carrier: (0.01, 0.0)}).shifted
    assert {carrier, carried} <= moved
    assert moved <= {carrier} | {b for b, p in placed.items() if p.support is not None}


def test_a_form_reads_the_positions_of_what_its_descriptions_compare():
    compiled = benchmark()
    scene = compiled.spec.scenes["scene2"]
    layout = scene.tasks[0].layout
    grounder = Grounder(World(scene, layout))
    bodies = grounder.world.bodies
    cubes = {b for b in bodies if bodies[b].kind == "cube"}
    red = {b for b in cubes if bodies[b].color == "red"}
    assert len(cubes) > len(red) > 0
    assert position_reads(parse("pick up the red cube"), grounder) == set()
    assert position_reads(parse("pick up the leftmost cube"), grounder) == cubes
    assert position_reads(parse("pick up the leftmost red cube"), grounder) == red
    condition = parse("if the red cube is to the left of the blue cube, pick up the red cube")
    assert isinstance(condition, lf.Conditional)
    assert position_reads(condition, grounder) == set(bodies)


def test_one_realizer_says_what_fresh_ones_say():
    compiled = benchmark()
    forms = [task.form for task in compiled.splits.tasks]
    for name, style in STYLES.items():
        speaker = Realizer(style)
        for form in forms + forms:  # the second pass reads the memo
            assert speaker.instruction(form) == realize(form, name)


def test_skipping_the_styles_a_branch_cannot_say_gives_what_speaking_every_style_gives(
        monkeypatch):
    """The generator does not speak a conditional in a style one of whose branches says a word
    no training instruction uses: Scene 4's splits and rejections are those of speaking every
    style, and the shortcut is taken."""
    from pathlib import Path

    from robofollow.compiler.authoring.spec_loader import load_spec
    from robofollow.compiler.splits import generator
    from robofollow.compiler.splits.training import check_training

    spec = load_spec(Path(__file__).resolve().parent.parent / "specs" / "scene4.rf")
    training = check_training(spec)
    taken = []
    shortcut = generator._Generator.branch_unsaid

    def counted(self, form, style):
        taken.append(shortcut(self, form, style))
        return taken[-1]

    monkeypatch.setattr(generator._Generator, "branch_unsaid", counted)
    short = generator.generate(spec, training)
    monkeypatch.setattr(generator._Generator, "branch_unsaid", lambda self, form, style: False)
    plain = generator.generate(spec, training)
    assert short == plain and sum(taken) > 1000

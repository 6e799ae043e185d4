"""The order the split generator examines reworded candidates in: the wordings take turns,
each wording's choices are ranked by digest, and a candidate is built only when its turn comes
(so a capped level never builds the candidates it could not choose)."""

from __future__ import annotations

from itertools import islice
from pathlib import Path

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language import lf
from robofollow.compiler.splits import generator
from robofollow.compiler.splits.generator import generate
from robofollow.compiler.splits.task_rules import TaskRules
from robofollow.compiler.splits.training import check_training
from robofollow.compiler.splits.wordings import Describer, round_robin

SPECS = Path(__file__).resolve().parent.parent / "specs"


def test_round_robin_takes_turns_until_every_stream_runs_out():
    streams = [iter("abc"), iter(""), iter("12345"), iter("x")]
    assert "".join(round_robin(streams)) == "a1xb2c345"


def _source(scene_id: str, label: str):
    """A training task's form, its scene's describer of its layout, and the scene."""
    spec = load_spec(SPECS / f"{scene_id}.rf")
    scene = spec.scenes[scene_id]
    task = next(t for t in scene.tasks if t.label == label)
    training = check_training(spec)
    rules = TaskRules(scene, training)
    constructs = {c for t in scene.tasks for f in t.forms for c in lf.constructs(f)}
    return task, Describer(rules.grounders(task.layout)[0], constructs)


def test_a_conditional_sources_wordings_take_turns_one_candidate_each():
    """Scene 4's L2 rule rewords referents, conditions and branches: a conditional's
    candidates come one from each in turn (then conditions+branches), until branches, which
    has two, runs out."""
    task, describer = _source("scene4", "s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack")
    rank = generator._rank("scene4/L2/x@scene4_1")
    wordings = ("referents", "conditions", "branches")
    first = [w for w, _ in islice(generator._variants(task.forms[0], describer, wordings, rank),
                                  12)]
    assert first[:8] == ["referents", "conditions", "branches", "conditions+branches"] * 2
    assert first[8:12] == ["referents", "conditions", "conditions+branches", "referents"]


def test_a_wordings_choices_are_ranked_by_the_digest_of_source_and_choice():
    """The conditions of one source come in the order of their digests with the source, and
    another source orders them otherwise."""
    task, describer = _source("scene4", "s41_if_bowl_nonempty_then_l_pick_blue_else_r_stack")
    form = task.forms[0]

    def conditions(source):
        rank = generator._rank(source)
        return [lf.to_json(v.condition) for _, v in
                generator._variants(form, describer, ("conditions",), rank)]

    one, other = conditions("scene4/L2/a@scene4_1"), conditions("scene4/L2/b@scene4_1")
    assert sorted(one) == sorted(other) and one != other
    rank = generator._rank("scene4/L2/a@scene4_1")
    others = [c for c in describer.conditions() if c != form.condition]
    assert one == [lf.to_json(c) for c in sorted(others, key=lambda c: rank(lf.to_json(c)))]


def test_a_capped_level_builds_only_the_candidates_it_examines(monkeypatch):
    """Scene 2's L3 keeps 48 of its sources' rewordings: the walk stops there, and only the
    candidates it examined were built (each is kept or rejected with a reason)."""
    built = []
    variants = generator._variants

    def counted(*args):
        for found in variants(*args):
            built.append(found)
            yield found

    monkeypatch.setattr(generator, "_variants", counted)
    spec = load_spec(SPECS / "scene2.rf")
    splits = generate(spec, check_training(spec), levels=("L0", "L1", "L3"))
    examined = ([t for t in splits.tasks if t.level == "L3"]
                + [r for r in splits.rejected if r.level == "L3"])
    assert len(built) == len(examined) and len(splits.of("scene2", "L3")) == 48
    monkeypatch.setattr(generator, "_variants", variants)
    every = 0
    scene = spec.scenes["scene2"]
    training = check_training(spec)
    rules = TaskRules(scene, training)
    constructs = {c for t in scene.tasks for f in t.forms for c in lf.constructs(f)}
    for task in (t for t in splits.tasks if t.level == "L1"):
        if task.layout in scene.splits["L3"].layouts:
            describer = Describer(rules.grounders(task.layout)[0], constructs)
            every += sum(1 for _ in variants(task.form, describer, scene.splits["L3"].wordings,
                                             generator._rank("x")))
    assert every > 4 * len(built)  # what ordering them all up front built

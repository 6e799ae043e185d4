"""Split generation for L0 and L1: counts, repertoire, reasons, determinism."""

from pathlib import Path

import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.planning.motions import COMPOSING_LEVELS, Repertoire
from robofollow.compiler.planning.routes import passes_over
from robofollow.compiler.scene.world import World
from robofollow.compiler.splits.generator import generate
from robofollow.compiler.splits.tasks import episode_seed
from robofollow.compiler.splits.training import check_training
from robofollow.compiler.splits.wordings import concepts

SPECS = Path(__file__).resolve().parent.parent / "specs"
# the upstream benchmark's tasks per level, but Scene 1's L3: its training instructions say
# neither 'cube', 'object', 'rightmost' nor 'yellow', which the upstream L3 wordings use, and an
# L3 wording may use only its own scene's training words
TARGETS = {"scene1": (16, 8, 16, 17), "scene2": (16, 24, 68, 24), "scene3": (16, 40, 64, 96),
           "scene4": (27, 14, 25, 24)}


@pytest.fixture(scope="module")
def compiled():
    spec = load_spec(SPECS)
    training = check_training(spec)
    return spec, training, generate(spec, training)


def test_counts_reach_the_targets_within_the_caps(compiled):
    spec, _, splits = compiled
    for scene, targets in TARGETS.items():
        assert len(splits.of(scene, "L0")) == targets[0]
        for level, target in zip(("L1", "L2", "L3"), targets[1:], strict=True):
            count = len(splits.of(scene, level))
            assert count >= target
            cap = spec.scenes[scene].splits[level].max_tasks
            assert cap is None or count <= cap


def test_novel_wordings_mean_their_form_and_are_new_to_their_scene(compiled):
    spec, _, splits = compiled
    for task in splits.tasks:
        if task.level in ("L2", "L3"):
            own = spec.scenes[task.scene].tasks
            assert parse(task.instruction) == task.form
            assert lf.to_json(task.form) not in {lf.to_json(f) for t in own for f in t.forms}
            assert concepts(task.instruction) <= {c for t in own for p in t.paraphrases
                                                  for c in concepts(p)}
            layouts = spec.scenes[task.scene].training_layouts if task.level == "L2" else \
                spec.scenes[task.scene].splits["L3"].layouts
            assert task.layout in layouts


def test_kept_tasks_are_inside_the_repertoire_and_unique(compiled):
    spec, training, splits = compiled
    repertoires = {scene.id: Repertoire(scene, training) for scene in spec.scenes.values()}
    for task in splits.tasks:
        world = World(spec.scenes[task.scene], task.layout)
        assert repertoires[task.scene].covers(task.behaviour, world,
                                              compose=task.level in COMPOSING_LEVELS), task.id
    assert len({t.id for t in splits.tasks}) == len(splits.tasks)
    assert len({(t.layout, lf.to_json(t.form)) for t in splits.tasks}) == len(splits.tasks)


def test_l1_uses_training_strings_on_changed_layouts(compiled):
    spec, _, splits = compiled
    strings = {p for t in spec.tasks for p in t.paraphrases}
    for task in splits.tasks:
        if task.level == "L1":
            assert task.instruction in strings
            assert task.layout in spec.scenes[task.scene].splits["L1"].layouts


def test_every_rejection_says_why(compiled):
    _, _, splits = compiled
    reasons = {r.reason.split(":")[0] for r in splits.rejected}
    assert all(r.reason for r in splits.rejected)
    assert {"no-referent", "ambiguous", "repertoire", "leakage", "words", "duplicate",
            "route"} <= reasons
    assert any(r.reason.startswith("over the split's max") for r in splits.rejected)
    off_way = [r for r in splits.rejected if r.reason.startswith("route")]
    assert off_way and all(r.layout == "scene3_3" or r.layout == "scene3_4" for r in off_way)


def test_a_covered_object_is_not_asked_for(compiled):
    """Where a layout stacks a body on a task's object, no test task moves that object."""
    _, _, splits = compiled
    covered = [r for r in splits.rejected
               if r.reason.startswith("infeasible") and "the object to move" in r.reason]
    assert {(r.layout, r.origin) for r in covered} >= {
        ("scene4_6", "s41_l_pick_yellow_cylinder")}
    assert "green_cylinder rests on yellow_cylinder" in covered[0].reason
    for task in splits.tasks:
        if task.layout == "scene4_6":
            assert all(s.source != "yellow_cylinder" for s in task.behaviour.steps), task.id


def test_a_changed_layout_can_change_the_referent(compiled):
    _, _, splits = compiled
    task = next(t for t in splits.tasks
                if t.id == "scene1/L1/pickup_yellow_block_1_right@scene1_1")
    assert task.behaviour.steps[0].source == "yellow_block_3"


def test_generation_is_deterministic(compiled):
    spec, training, splits = compiled
    assert generate(spec, training).model_dump_json() == splits.model_dump_json()


def test_seeds_follow_the_task_id():
    assert episode_seed("scene1/L0/x", 1, 42) == episode_seed("scene1/L0/x", 1, 42)
    assert episode_seed("scene1/L0/x", 2, 42) - episode_seed("scene1/L0/x", 1, 42) == 100
    assert episode_seed("scene1/L0/x", 1, 42) != episode_seed("scene1/L0/y", 1, 42)


def test_routes_compare_by_the_bodies_passed_over(compiled):
    spec, training, _ = compiled
    world = World(spec.scenes["scene3"], "default")
    around_red = training["l_pick5_around2_to1_short_right"].steps[0]
    assert passes_over(around_red, world) == ("green_slab",)
    via_yellow = training["r_pick2_via4_to6_short_front"].steps[0]
    assert passes_over(via_yellow, world) == ("yellow_slab",)


def _scene1_with(tmp_path: Path, old: str, new: str) -> Path:
    """The shipped specs with scene1 edited."""
    tmp_path.mkdir(exist_ok=True)
    for spec in SPECS.glob("*.rf"):
        (tmp_path / spec.name).write_text(spec.read_text())
    text = (SPECS / "scene1.rf").read_text()
    assert old in text
    (tmp_path / "scene1.rf").write_text(text.replace(old, new, 1))
    return tmp_path


L3_RULE = "split L3 layouts=(scene1_1, scene1_2, scene1_3)"


def test_a_rule_layout_that_yields_nothing_is_a_warning_with_the_reason(tmp_path):
    from robofollow.benchmark.pipeline import compile_specs

    folder = _scene1_with(tmp_path, L3_RULE, "layout scene1_4 from default { swap red_sphere "
                          "red_cylinder }\n    " + L3_RULE.replace(")", ", scene1_4)"))
    warnings = compile_specs(folder).report["split_rules"]["warnings"]
    assert warnings == ["scene1 split L3: layout scene1_4 yields no task (L3 rewords the kept L1 "
                        "tasks of its layouts, and the L1 rule does not name it)"]


def test_a_capped_level_gives_a_new_layout_its_share_and_displaces_no_more(tmp_path):
    from robofollow.benchmark.pipeline import compile_specs

    capped = L3_RULE + " wordings=(referents) max=12"
    rule = L3_RULE + " wordings=(referents) max=80"
    before = compile_specs(_scene1_with(tmp_path / "before", rule, capped))
    assert len(before.splits.of("scene1", "L3")) == 12
    l1_rule = "split L1 layouts=(scene1_1, scene1_2, scene1_3)"
    folder = _scene1_with(tmp_path / "after", l1_rule, "layout scene1_4 from default { swap "
                          "red_sphere red_cylinder }\n    " + l1_rule.replace(")", ", scene1_4)"))
    text = (folder / "scene1.rf").read_text().replace(rule, capped.replace(")", ", scene1_4)", 1))
    (folder / "scene1.rf").write_text(text)
    after = compile_specs(folder)
    old = {t.id for t in before.splits.of("scene1", "L3")}
    new = {t.id for t in after.splits.of("scene1", "L3")}
    gained = [t for t in new - old if "@scene1_4/" in t]
    assert gained and len(new - old) == len(gained) and len(old - new) == len(gained)


def test_a_split_asking_for_moved_tasks_keeps_only_moved_l1_and_l3_tasks(tmp_path):
    """`motion=moved` on L1 rejects the as-trained candidates with the reason; L3 rewords only
    the kept L1 tasks, so it has no as-trained task either."""
    from robofollow.benchmark.labels import object_moved
    from robofollow.benchmark.pipeline import compile_specs
    from robofollow.benchmark.summary import summary

    rule = "split L1 layouts=(scene1_1, scene1_2, scene1_3)"
    (tmp_path / "scene1.rf").write_text((SPECS / "scene1.rf").read_text())
    compiled = compile_specs(tmp_path)
    every = compiled.splits
    text = summary(compiled)
    assert "L1 and L3 tasks by motion" in text
    lines = text.splitlines()
    head = next(i for i, line in enumerate(lines) if "L1 as-trained" in line)
    counts = lines[head + 1].split()
    moved_objects = {level: sum(1 for t in every.of("scene1", level) if t.motion == "moved"
                                and object_moved(compiled.spec.scenes["scene1"], t,
                                                 compiled.training))
                     for level in ("L1", "L3")}
    assert counts == ["scene1"] + [str(value) for level in ("L1", "L3") for value in (
        sum(1 for t in every.of("scene1", level) if t.motion == "moved"), moved_objects[level],
        sum(1 for t in every.of("scene1", level) if t.motion == "as-trained"))]
    assert counts[1:4] == ["8", "8", "7"]  # the shipped split: 7 of 15 L1 tasks as trained
    assert {t.motion for t in every.of("scene1", "L1")} == {"moved", "as-trained"}
    text = (SPECS / "scene1.rf").read_text()
    assert rule in text
    (tmp_path / "scene1.rf").write_text(text.replace(rule, rule + " motion=moved", 1))
    compiled = compile_specs(tmp_path)
    moved = compiled.splits
    assert f"{'scene1':<10}{8:>10}{8:>14}{0:>16}" in summary(compiled)  # moved, object, trained
    assert moved.of("scene1", "L1") and moved.of("scene1", "L3")
    assert {t.motion for level in ("L1", "L3") for t in moved.of("scene1", level)} == {"moved"}
    assert ({t.id for t in moved.of("scene1", "L1")}
            == {t.id for t in every.of("scene1", "L1") if t.motion == "moved"})
    as_trained = [r for r in moved.rejected if r.reason.startswith("as-trained:")]
    assert ({(r.layout, r.origin) for r in as_trained}
            == {(t.layout, t.origin) for t in every.of("scene1", "L1")
                if t.motion == "as-trained"})
    assert all(r.level == "L1" and r.reason == f"as-trained: the expert moves as {r.origin} does"
               for r in as_trained)
    assert moved.of("scene1", "L0") == every.of("scene1", "L0")


def test_training_tasks_left_without_a_rewording_are_named_with_the_words_missing(tmp_path):
    """A training task none of whose rewordings is kept (the cap apart) is named in the
    summary with what dropped them: above all words no training sentence of the scene uses
    (15 of 17 of an author's new tasks got no L2 or L3 task, without a word)."""
    from robofollow.benchmark.pipeline import compile_specs
    from robofollow.benchmark.summary import summary

    (tmp_path / "scene4.rf").write_text((SPECS / "scene4.rf").read_text())
    compiled = compile_specs(tmp_path)
    lines = summary(compiled).splitlines()
    head = next(i for i, line in enumerate(lines)
                if line.startswith("training tasks with no L2 or L3 rewording kept"))
    l2 = next(line for line in lines[head + 1:] if line.startswith("  scene4 L2: "))
    kept = {t.origin for t in compiled.splits.of("scene4", "L2")}
    assert "s41_l_pick_ball_not_leftmost" in l2 and "s41_l_pick_ball_not_leftmost" not in kept
    assert "words training never uses: rightmost" in l2
    training = {t.label for t in compiled.spec.tasks}
    capped = {r.origin for r in compiled.splits.rejected
              if r.level == "L2" and r.reason.startswith("over the split's max")}
    assert l2.startswith(f"  scene4 L2: {len(training - kept - capped)} of {len(training)} (")

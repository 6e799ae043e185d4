"""Split validity on generated specs: the compiled splits always pass their own audit and keep
to their levels' max, a scene's tasks and episodes are the same compiled alone or beside
others, trained motions stay in the repertoire, look-alike layouts are never changed layouts,
and degenerate routes are always found."""

import math
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from robofollow.audit.report import FINDING_KEYS, findings
from robofollow.audit.splits import task_findings
from robofollow.benchmark.pipeline import compile_specs
from robofollow.benchmark.rounds import all_episodes
from robofollow.compiler.planning.motions import Repertoire
from robofollow.compiler.planning.routes import ROUTE_BAND, degenerate_routes
from robofollow.compiler.scene.behaviour import Step
from robofollow.compiler.scene.observation import same_observation
from robofollow.compiler.scene.spec import Body, Layout, Placed, Scene
from robofollow.compiler.scene.world import World
from robofollow.errors import SpecErrors
from tests.spec_helpers import VALID
from tests.strategies import rich_specs, route_geometry, several_scenes, small_specs

HEAVY = settings(max_examples=25, deadline=None,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def compile_text(text: str):
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "demo.rf").write_text(text)
        return compile_specs(Path(folder))


@HEAVY
@given(generated=small_specs())
def test_compiled_splits_pass_the_audit(generated):
    text, _ = generated
    compiled = compile_text(text)
    report = compiled.report
    assert findings(report) == 0, {key: report[key] for key in FINDING_KEYS if report[key]}
    ids = [t.id for t in compiled.splits.tasks]
    assert len(ids) == len(set(ids))
    assert len(compiled.splits.of("demo", "L0")) <= len(compiled.spec.tasks)


@HEAVY
@given(generated=small_specs())
def test_entropy_is_the_group_formula(generated):
    text, sizes = generated
    report = compile_text(text).report
    expected = sum(k / sum(sizes) * math.log2(k) for k in sizes)
    assert math.isclose(report["scene_entropy_bits"], expected, abs_tol=1e-6)


@HEAVY
@given(generated=small_specs())
def test_injected_leaks_are_always_caught(generated):
    text, _ = generated
    compiled = compile_text(text)
    spec, splits = compiled.spec, compiled.splits
    training = spec.tasks[0]
    victim = (splits.of("demo", "L1") + splits.of("demo", "L2") + splits.of("demo", "L0"))[0]
    copied = victim.model_copy(update={"id": victim.id + "/copied", "level": "L2",
                                       "form": training.forms[0]})
    named = victim.model_copy(update={"id": victim.id + "/named",
                                      "instruction": f"{victim.instruction} ({training.label})"})
    tampered = splits.model_copy(update={"tasks": splits.tasks + (copied, named)})
    flagged = {f["task"] for f in task_findings(spec, compiled.training, tampered)["leakage"]}
    assert {copied.id, named.id} <= flagged


def compile_or_skip(text: str):
    """The compiled spec; a random task the expert cannot perform (an arm stretched too far, no
    free spot) or whose route is not on the way is a spec error, not a split problem, and the
    example is discarded."""
    try:
        return compile_text(text)
    except SpecErrors as error:
        assume(not all(e.code in ("infeasible", "degenerate-route") for e in error.errors))
        raise


@HEAVY
@given(generated=rich_specs())
def test_rich_specs_compile_to_splits_without_findings(generated):
    compiled = compile_or_skip(generated["text"])
    report = compiled.report
    assert findings(report) == 0, {key: report[key] for key in FINDING_KEYS if report[key]}
    scene = compiled.spec.scenes["demo"]
    repertoire = Repertoire(scene, compiled.training)
    for task in scene.tasks:  # a training motion is always in the repertoire
        assert repertoire.covers(compiled.training[task.label], World(scene, task.layout),
                                 compose=False)


@HEAVY
@given(generated=rich_specs().filter(lambda g: g["twins"] is not None))
def test_a_swap_of_identical_looking_bodies_is_never_a_changed_layout(generated):
    compiled = compile_or_skip(generated["text"])
    scene = compiled.spec.scenes["demo"]
    assert same_observation(scene, "base", "look_alike")
    text = generated["text"]
    tested = (text.replace("    split L1 layouts=(", "    split L1 layouts=(look_alike, ")
              if "    split L1 layouts=(" in text else
              text.replace("    split L2 ", "    split L1 layouts=(look_alike)\n    split L2 "))
    with pytest.raises(SpecErrors) as raised:  # a rule may not test on it
        compile_text(tested)
    assert [(e.code, "layout look_alike looks the same as the training layout base" in e.message)
            for e in raised.value.errors] == [("looks-like-training", True)]
    # the training motions, performed with the twins' names traded, are still trained motions
    repertoire = Repertoire(scene, compiled.training)
    trade = {"o0": "t0", "t0": "o0"}
    for task in scene.tasks:
        behaviour = compiled.training[task.label]
        steps = tuple(s.model_copy(update={"source": trade.get(s.source, s.source),
                                           "target": trade.get(s.target, s.target)})
                      for s in behaviour.steps)
        assert repertoire.covers(behaviour.model_copy(update={"steps": steps}),
                                 World(scene, "look_alike"), compose=False)


def _route_world(source, target, body) -> World:
    """A label at `target`, a slab at `source` and one at `body` (x, y)."""
    slab = {"kind": "slab", "fixture": False, "color": "red", "rgb": (1, 0, 0),
            "half_extents": (0.018, 0.028, 0.013)}
    bodies = {"s": Body(id="s", **slab), "w": Body(id="w", **{**slab, "color": "blue"}),
              "label": Body(id="label", kind="label", fixture=True, color="green",
                            rgb=(0, 1, 0), half_extents=(0.035, 0.035, 0.001))}
    placed = {name: Placed(x=x, y=y, z=0.74 + bodies[name].half_extents[2])
              for name, (x, y) in (("s", source), ("label", target), ("w", body))}
    scene = Scene(id="r", title="r", bodies=bodies, points={}, jitter={},
                  layouts={"l": Layout(name="l", placed=placed)}, tasks=(), splits={})
    return World(scene, "l")


@settings(max_examples=200, deadline=None)
@given(geometry=route_geometry, behind=st.floats(0.0, 0.15), side=st.floats(-0.3, 0.3),
       mode=st.sampled_from(["via", "avoid"]))
def test_a_degenerate_route_is_always_found(geometry, behind, side, mode):
    x, y, length, heading = geometry
    ux, uy = math.cos(heading), math.sin(heading)
    target = (x + length * ux, y + length * uy)
    step = Step(action="place", arm="left", source="s", relation="on", target="label",
                waypoints=((mode, "w"),))
    # behind the source (its footprint reaching back from the source's): never on the way
    back = (x - (0.04 + behind) * ux, y - (0.04 + behind) * uy)
    assert degenerate_routes(step, _route_world((x, y), target, back))
    middle = (x + length / 2 * ux - side * uy, y + length / 2 * uy + side * ux)
    found = degenerate_routes(step, _route_world((x, y), target, middle))
    if mode == "via":  # halfway, within the band: on the way; beyond the band: off it
        assume(abs(abs(side) - ROUTE_BAND) > 1e-9)  # (not at the band's edge: rounding decides)
        assert bool(found) == (abs(side) > ROUTE_BAND), found
        return
    # 'avoid w' is never sound here (w has no column mate to carry over instead); it is off
    # the path where the carried slab's swept footprint and w's do not meet
    reach = 2 * (abs(ux) * 0.028 + abs(uy) * 0.018)
    assert len(found) == 1
    assume(abs(abs(side) - min(reach, ROUTE_BAND)) > 1e-9)
    assert ("off the straight path" in found[0]) == (abs(side) > min(reach, ROUTE_BAND)), found


# training tasks a random spec may get wrong: the expert cannot reach or clear (a spec error,
# not a split problem); any other error of a generated spec is a failure
TRAINING_ERRORS = ("infeasible", "degenerate-route")


def _write(folder: Path, generated: dict) -> list[Path]:
    """The scenes' spec files: one file a scene, or all scenes in one file."""
    scenes = generated["scenes"]
    if generated["one_file"]:
        path = folder / "all.rf"
        path.write_text("\n".join(s["text"] for s in scenes))
        return [path]
    paths = [folder / f"{s['id']}.rf" for s in scenes]
    for path, scene in zip(paths, scenes, strict=True):
        path.write_text(scene["text"])
    return paths


def _of_scene(compiled, scene: str) -> dict:
    """What a scene's splits are: its tasks, its episode records and its split digest."""
    return {"tasks": [t.model_dump(mode="json") for t in compiled.splits.tasks
                      if t.scene == scene],
            "episodes": [e.model_dump(mode="json") for e in all_episodes(compiled)
                         if e.scene == scene],
            "digest": compiled.split_digests[scene]}


def _compile_together(generated: dict, folder: Path):
    try:
        return compile_specs(_write(folder, generated))
    except SpecErrors as error:
        assume(not all(e.code in TRAINING_ERRORS for e in error.errors))
        raise


@settings(max_examples=200, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(generated=several_scenes())
def test_scenes_compiled_together_audit_clean_and_match_each_alone(generated):
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        compiled = _compile_together(generated, folder)
        report = compiled.report
        assert findings(report) == 0, {key: report[key] for key in FINDING_KEYS if report[key]}
        ids = [t.id for t in compiled.splits.tasks]
        assert len(ids) == len(set(ids))
        for scene in generated["scenes"]:
            sid = scene["id"]
            for level, maximum in scene["max"].items():  # listed tests count toward max
                assert len(compiled.splits.of(sid, level)) <= maximum, (sid, level)
            listed = {t.level for t in compiled.splits.tasks
                      if t.scene == sid and t.wording == "listed"}
            assert listed == set(scene["listed"])
            alone = folder / "alone" / sid
            alone.mkdir(parents=True)
            (alone / f"{sid}.rf").write_text(scene["text"])
            by_itself = compile_specs([alone / f"{sid}.rf"])
            assert _of_scene(by_itself, sid) == _of_scene(compiled, sid), sid


def test_an_unreadable_hand_edited_instruction_is_a_finding_not_a_crash():
    """Found by test_injected_leaks_are_always_caught: a task whose words name a spec identifier
    in parentheses made the audit's wording rule raise UnknownWordError on '('."""
    compiled = compile_text(VALID)
    victim = compiled.splits.tasks[0]
    named = victim.model_copy(update={"id": victim.id + "/named",
                                      "instruction": f"{victim.instruction} (red_cube)"})
    tampered = compiled.splits.model_copy(update={"tasks": compiled.splits.tasks + (named,)})
    found = task_findings(compiled.spec, compiled.training, tampered)
    assert {f["task"] for f in found["leakage"]} == {named.id}
    assert [f["task"] for f in found["misleading_wordings"]] == [named.id]
    assert "unreadable: column" in found["misleading_wordings"][0]["finding"]

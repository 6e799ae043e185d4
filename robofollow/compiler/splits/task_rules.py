"""The rules every test task obeys: one check, applied by the split generator to each
candidate before keeping it and by the audit to each compiled or listed task.

A task is examined against its own scene only (its training tasks, layouts and words), so a
scene's splits never depend on the scenes compiled beside it. The findings, by kind:

duplicate     it repeats an earlier task: the same level and meaning on a layout that looks
              the same
leakage       its (layout, form) pair is a training pair; an L2/L3 form is a training form; the
              words name a spec identifier
level         it is not what its level claims (L0 training pairs, L1 training instructions on
              layouts that look new, L2 training layouts, L3 layouts that look new; a layout
              the L1 or L3 rule declares a repeat, `repeats=allowed`, may look like training)
no-referent   a description names nothing on the layout (in either branch of a conditional)
ambiguous     a description fits several bodies, nominally or at a jitter extreme (in either
              branch of a conditional, nominally)
route         a body the route names is not on the way (routes.py)
infeasible    the expert cannot perform it (feasibility.py)
repertoire    training does not perform its motions (motions.py)
wording       a new wording reads otherwise than it is scored (wording_rules.py); training
              instructions are the spec author's words and are not judged here
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field

from robofollow.compiler.language import lf
from robofollow.compiler.language.lexicon import VOCABULARY
from robofollow.compiler.planning.feasibility import infeasible
from robofollow.compiler.planning.motions import COMPOSING_LEVELS, Repertoire
from robofollow.compiler.planning.routes import degenerate_routes
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.grounding import (
    Grounder,
    GroundingError,
    Unstable,
    first_unstable,
)
from robofollow.compiler.scene.observation import look_alike, same_observation
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import EXTREME_AXES, World, jitter_worlds
from robofollow.compiler.splits.wording_rules import wording_problems


def _identifiers(scene: Scene) -> set[str]:
    """Spec names that could leak into an instruction (those that are not plain words)."""
    names = {scene.id} | set(scene.bodies) | set(scene.layouts) | set(scene.points)
    names |= {task.label for task in scene.tasks}
    return {n for n in names if n.lower() not in VOCABULARY}


class TrainingFacts:
    """What a scene's training tasks fix, for the leakage and level rules (`form` is a
    logical form's canonical JSON)."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self._look_alike: dict[str, str | None] = {}
        self.pairs = {(t.layout, lf.to_json(f)) for t in scene.tasks for f in t.forms}
        self.forms = {form for _, form in self.pairs}
        self.instructions = {p for t in scene.tasks for p in t.paraphrases}
        identifiers = sorted(_identifiers(scene), key=len, reverse=True)
        self.pattern = re.compile(r"\b(" + "|".join(map(re.escape, identifiers)) + r")\b",
                                  re.IGNORECASE) if identifiers else None

    def leakage(self, level: str, layout: str, form: str, instruction: str) -> list[str]:
        found = []
        if level != "L0" and (layout, form) in self.pairs:
            found.append("its (layout, form) pair is a training pair")
        if level in COMPOSING_LEVELS and form in self.forms:
            found.append("its form is a training form")
        named = self.pattern.search(instruction) if self.pattern else None
        if named:
            found.append(f"its instruction names the spec identifier {named.group(0)!r}")
        return found

    def training_look_alike(self, layout: str) -> str | None:
        """The training layout that `layout` looks the same as, if any (memoised)."""
        if layout not in self._look_alike:
            self._look_alike[layout] = look_alike(self.scene, layout, self.scene.training_layouts)
        return self._look_alike[layout]

    def _repeat_allowed(self, level: str, layout: str) -> bool:
        """Whether the level's split rule names `layout` as a distractor-free repeat of a
        training layout (`repeats=allowed`)."""
        rule = self.scene.splits.get(level)
        return rule is not None and rule.repeats == "allowed" and layout in rule.layouts

    def level_problems(self, level: str, layout: str, form: str, instruction: str) -> list[str]:
        same = self.training_look_alike(layout)
        found = []
        if level == "L0" and (layout, form) not in self.pairs:
            found.append("an L0 task is a training pair, but no training task asks this on "
                         f"{layout}")
        if level in ("L1", "L3") and same is not None and not self._repeat_allowed(level, layout):
            found.append(f"an {level} task is on a layout that looks different from every "
                         f"training layout, but {layout} looks the same as {same}")
        if level == "L1" and instruction not in self.instructions:
            found.append("an L1 task's instruction is a training instruction, but this one is "
                         "not")
        if level == "L2" and same is None:
            found.append(f"an L2 task is on a training layout, but {layout} looks different "
                         "from every training layout")
        return found


class SeenTasks:
    """Test tasks seen so far, to find one that repeats another: the same level and logical
    form on a layout that looks the same (a task counted twice)."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.seen: dict[tuple[str, str], list[tuple[str, str]]] = {}
        self._same: dict[tuple[str, str], bool] = {}

    def looks_same(self, a: str, b: str) -> bool:
        """Whether two layouts are one or look the same (memoised; the relation is
        symmetric)."""
        key = (a, b) if a <= b else (b, a)
        if key not in self._same:
            self._same[key] = a == b or same_observation(self.scene, a, b)
        return self._same[key]

    def repeat(self, level: str, layout: str, form: str) -> str | None:
        for other_layout, other in self.seen.get((level, form), ()):
            if self.looks_same(layout, other_layout):
                where = ("" if other_layout == layout else
                         f" ({layout} looks the same as {other_layout})")
                return f"it repeats {other}: the same meaning on the same layout{where}"
        return None

    def add(self, task_id: str, level: str, layout: str, form: str) -> None:
        self.seen.setdefault((level, form), []).append((layout, task_id))


@dataclass
class Examination:
    findings: list[tuple[str, str]] = field(default_factory=list)  # (kind, message)
    behaviour: Behaviour | None = None  # grounded on the nominal layout, arms filled


@dataclass(frozen=True)
class _Grounded:
    """A task that grounds on its layout's nominal positions, for the rules after that."""
    level: str
    instruction: str
    form: lf.Instruction
    form_json: str
    nominal: Behaviour  # as the words give it
    behaviour: Behaviour  # arms filled
    grounders: list[Grounder]  # nominal first, then the jitter extremes

    @property
    def world(self) -> World:
        return self.grounders[0].world


Arms = Callable[[Behaviour, World], Behaviour]  # fills the arms the words leave unnamed


def arms_of(reference: Behaviour) -> Arms:
    """Unnamed arms taken from `reference`, step for step (a training task's arms, which its
    paraphrases name, or a compiled task's)."""
    arms = [s.arm for s in reference.steps]

    def fill(behaviour: Behaviour, _world: World) -> Behaviour:
        if len(arms) != len(behaviour.steps):
            return behaviour
        return behaviour.model_copy(update={"steps": tuple(
            s if s.arm else s.model_copy(update={"arm": a})
            for s, a in zip(behaviour.steps, arms, strict=True))})
    return fill


class TaskRules:
    """The rules of one scene's test tasks (see the module docstring)."""

    def __init__(self, scene: Scene, training: dict[str, Behaviour]):
        self.scene = scene
        self.facts = TrainingFacts(scene)
        self.seen = SeenTasks(scene)
        self.repertoire = Repertoire(scene, training)
        self._grounders: dict[str, list[Grounder]] = {}
        self._infeasible: dict[tuple[str, Behaviour], list[str]] = {}
        self._wordings: dict[tuple[str, str, str], list[str]] = {}

    def grounders(self, layout: str) -> list[Grounder]:
        """The layout's grounders: nominal positions first, then the jitter extremes."""
        if layout not in self._grounders:
            still: dict = {}  # what reads no position is the same in every jittered world
            self._grounders[layout] = [Grounder(w, still)
                                       for w in jitter_worlds(self.scene, layout)]
        return self._grounders[layout]

    def examine(self, level: str, layout: str, instruction: str, form: lf.Instruction,
                arms: Arms, every: bool = True, form_json: str | None = None) -> Examination:
        """The rules' findings for one task (every one, or up to the first rule that finds
        something), and its behaviour as far as it grounds; `form_json` is the form's
        canonical JSON where the caller has it. The task is not remembered: `keep` it once it
        is kept. The cheap rules come first, the jitter extremes last."""
        result = Examination()
        found = result.findings
        form_json = form_json or lf.to_json(form)
        found += self.placement(level, layout, instruction, form_json)
        grounders = self.grounders(layout)
        world = grounders[0].world
        if found and not every:
            return result
        try:
            nominal = grounders[0].behaviour(form, every_branch=True)
        except GroundingError as error:
            found.append((grounding_kind(error), grounding_message(error, world)))
            return result
        result.behaviour = arms(nominal, world)
        task = _Grounded(level, instruction, form, form_json, nominal, result.behaviour,
                         grounders)
        for kind, rule in _GROUNDED_RULES:
            if found and not every:
                break
            found += [(kind, problem) for problem in rule(self, task)]
        return result

    def placement(self, level: str, layout: str, instruction: str,
                  form_json: str) -> list[tuple[str, str]]:
        """The findings of the rules that ground nothing (duplicate, leakage, level): where
        the task stands among the training tasks and the tasks kept so far."""
        found = []
        repeat = self.seen.repeat(level, layout, form_json)
        if repeat:
            found.append(("duplicate", repeat))
        found += [("leakage", m) for m in self.facts.leakage(level, layout, form_json,
                                                            instruction)]
        found += [("level", m) for m in self.facts.level_problems(level, layout, form_json,
                                                                 instruction)]
        return found

    def _routes(self, task: _Grounded) -> list[str]:
        return [p for step in task.behaviour.steps for p in degenerate_routes(step, task.world)]

    def _feasibility(self, task: _Grounded) -> list[str]:
        """(memoised per layout: many candidates ask for one behaviour)"""
        key = task.world.layout.name, task.behaviour
        if key not in self._infeasible:
            self._infeasible[key] = infeasible(task.behaviour, task.world)
        return self._infeasible[key]

    def _repertoire(self, task: _Grounded) -> list[str]:
        missing = self.repertoire.missing(task.behaviour, task.world,
                                          compose=task.level in COMPOSING_LEVELS)
        return [missing] if missing else []

    def _wording(self, task: _Grounded) -> list[str]:
        if task.instruction in self.facts.instructions:
            return []  # a training instruction: the spec author's words
        return self.wording(task.world.layout.name, task.instruction, task.form, task.form_json)

    def wording(self, layout: str, instruction: str, form: lf.Instruction,
                form_json: str) -> list[str]:
        """wording_problems on the layout's nominal positions (memoised: the split generator
        asks it of a candidate before examining it)."""
        key = layout, instruction, form_json
        if key not in self._wordings:
            self._wordings[key] = wording_problems(instruction, form, self.grounders(layout)[0])
        return self._wordings[key]

    def _jitter(self, task: _Grounded) -> list[str]:
        unstable = first_unstable(task.form, task.grounders[1:], task.nominal, first_case=1)
        return [] if unstable is None else [jitter_problem(unstable, task.nominal)]

    def keep(self, task_id: str, level: str, layout: str, form: lf.Instruction,
             form_json: str | None = None) -> None:
        self.seen.add(task_id, level, layout, form_json or lf.to_json(form))


def grounding_kind(error: GroundingError) -> str:
    return "ambiguous" if error.code == "ambiguous" else "no-referent"


def grounding_message(error: GroundingError, world: World) -> str:
    """The error, with the candidates' distances, or what the layout holds of the noun."""
    if error.code == "ambiguous" and error.candidates:
        return f"{error.message} ({_distances(error, world)})"
    if error.code == "no-referent" and error.ref is not None:
        kinds = sorted({b for b in world.bodies if world.bodies[b].kind == error.ref.noun})
        there = f"; the layout's {error.ref.noun}s: {', '.join(kinds)}" if kinds else ""
        return error.message + there
    return error.message


def _distances(error: GroundingError, world: World) -> str:
    """How far apart the candidates are, by what decided between them."""
    ref, candidates = error.ref, error.candidates
    extreme = next((c for c in (ref.constraints if ref else ())
                    if isinstance(c, lf.ExtremeIs)), None)
    if extreme is not None:
        axis, _ = EXTREME_AXES[extreme.extreme]
        name = "xy"[axis]
        return ", ".join(f"{b} at {name} = {100 * (world.poses[b].x, world.poses[b].y)[axis]:.1f}"
                         f" cm" for b in candidates)
    related = next((c for c in (ref.constraints if ref else ())
                    if isinstance(c, (lf.NearestIs, lf.Related))), None)
    if related is not None:
        try:
            anchor = world.poses.get(Grounder(world).resolve(related.landmark))  # not the table
        except GroundingError:
            anchor = None
        if anchor is not None:
            return ", ".join(f"{b} {100 * _apart(world, b, anchor):.1f} cm away"
                             for b in candidates)
    return ", ".join(f"{b} at ({100 * world.poses[b].x:.1f}, {100 * world.poses[b].y:.1f}) cm"
                     for b in candidates)


def _apart(world: World, body: str, anchor) -> float:
    pose = world.poses[body]
    return math.hypot(pose.x - anchor.x, pose.y - anchor.y)


def jitter_problem(unstable: Unstable, nominal: Behaviour) -> str:
    where = f"at jitter extreme {unstable.case}"
    error = unstable.error
    if error is not None:
        return (f"{where}: {error.message} ({_distances(error, unstable.world)})"
                if error.candidates else f"{where}: {error.message}")
    objects = [(s.source, s.target) for s in nominal.steps]
    return f"{where} it picks {_objects(unstable.objects)} instead of {_objects(objects)}"


def _objects(pairs) -> str:
    return ", ".join("/".join(b for b in pair if b) for pair in pairs)


# the rules on a grounded task, in order (cheap first): (finding kind, rule)
_GROUNDED_RULES = (("route", TaskRules._routes), ("infeasible", TaskRules._feasibility),
                   ("repertoire", TaskRules._repertoire), ("wording", TaskRules._wording),
                   ("ambiguous", TaskRules._jitter))

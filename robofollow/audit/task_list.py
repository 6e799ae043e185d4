"""Auditing a list of test tasks, ours or another benchmark's, against the scenes and training
tasks of a spec.

Each task (id, scene, level, layout, instruction, optional `expect` in the compiled episodes'
`behaviour` fields) is checked the way the compiler checks its own candidates:

parse         the instruction does not parse (with the column)
no-referent   a description names nothing on the layout (with what is there)
ambiguous     a description fits several bodies, at the nominal positions or at a jitter
              extreme (with the candidates and their distances)
expectation   grounded on the layout, the words select another behaviour than `expect` states
route         a body the route names is not on the way from the source to the destination
infeasible    the expert cannot perform the behaviour (reach, grip, a busy arm, no free spot)
repertoire    training does not perform the behaviour's motions (arm, action, the body's shape
              and size, pick and put locations, route, yaw), naming the parts that are new
duplicate     it repeats an earlier task of the list: the same level and meaning on a layout
              that looks the same
leakage       as in the split audit: training pairs or forms, spec identifiers in the words
level         the task is not what its level claims (L0 training pairs, L1 training
              instructions on new layouts, L2 training layouts, L3 new layouts)
invalid       an unknown scene, layout or level
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pydantic import ValidationError

from robofollow.audit.splits import SeenTasks, TrainingFacts
from robofollow.compiler import lf
from robofollow.compiler.behaviour import Behaviour, describe
from robofollow.compiler.feasibility import infeasible
from robofollow.compiler.grounding import Grounder, GroundingError, Unstable, first_unstable
from robofollow.compiler.model import Model
from robofollow.compiler.motions import COMPOSING_LEVELS, Repertoire
from robofollow.compiler.parser import parse
from robofollow.compiler.routes import degenerate_routes
from robofollow.compiler.spec import LEVELS, Spec
from robofollow.compiler.spec_files import Sources, spec_error
from robofollow.compiler.splits import TestTask
from robofollow.compiler.world import EXTREME_AXES, World, jitter_worlds
from robofollow.errors import InstructionError, RoboFollowError, SpecError
from robofollow.files import json_lines

FINDING_KINDS = ("invalid", "parse", "no-referent", "ambiguous", "expectation", "route",
                 "infeasible", "repertoire", "duplicate", "leakage", "level")
STEP_FIELDS = ("action", "arm", "source", "relation", "target", "waypoints", "yaw_degrees")


class ListedTask(Model):
    """One line of a task list."""
    id: str
    scene: str
    level: str
    layout: str
    instruction: str
    expect: dict | None = None


@dataclass
class Examination:
    findings: list[tuple[str, str]]  # (kind, message)
    form: lf.Instruction | None
    behaviour: Behaviour | None  # grounded on the nominal layout, arms filled


class TaskAuditor:
    def __init__(self, spec: Spec, training: dict[str, Behaviour]):
        self.spec, self.training = spec, training
        self.facts = TrainingFacts(spec)
        self.seen = SeenTasks(spec)
        self.repertoires = {scene.id: Repertoire(scene, training)
                            for scene in spec.scenes.values()}
        self.grounders: dict[tuple[str, str], list[Grounder]] = {}

    def audit(self, task: ListedTask) -> list[dict]:
        return [{"id": task.id, "kind": kind, "message": message}
                for kind, message in self.examine(task).findings]

    def examine(self, task: ListedTask) -> Examination:
        """The findings, and the form and behaviour as far as the task gets."""
        found: list[tuple[str, str]] = []
        form = behaviour = None
        scene = self.spec.scenes.get(task.scene)
        if scene is None:
            found.append(("invalid", f"no scene {task.scene!r} (scenes: "
                                     f"{', '.join(self.spec.scenes)})"))
            return Examination(found, form, behaviour)
        if task.layout not in scene.layouts:
            found.append(("invalid", f"{task.scene} has no layout {task.layout!r} (layouts: "
                                     f"{', '.join(scene.layouts)})"))
            return Examination(found, form, behaviour)
        if task.level not in LEVELS:
            found.append(("invalid", f"no level {task.level!r} (levels: {', '.join(LEVELS)})"))
            return Examination(found, form, behaviour)
        try:
            form = parse(task.instruction)
        except InstructionError as error:
            found.append(("parse", f"column {error.column}: {error.message}"))
            return Examination(found, form, behaviour)
        form_json = lf.to_json(form)
        repeat = self.seen.repeat(task.id, task.scene, task.level, task.layout, form_json)
        if repeat:
            found.append(("duplicate", repeat))
        for message in self.facts.leakage(task.level, task.scene, task.layout, form_json,
                                          task.instruction):
            found.append(("leakage", message))
        for message in self.facts.level_problems(task.level, task.scene, task.layout,
                                                 form_json, task.instruction):
            found.append(("level", message))
        grounders = self._grounders(task.scene, task.layout)
        try:
            behaviour = grounders[0].behaviour(form)
        except GroundingError as error:
            found.append((_grounding_kind(error), _grounding_message(error, grounders[0].world)))
            return Examination(found, form, behaviour)
        unstable = first_unstable(form, grounders[1:], behaviour, first_case=1)
        if unstable is not None:
            found.append(("ambiguous", _jitter_problem(unstable, behaviour)))
        expect = None
        if task.expect is not None:
            try:
                expect = _expectation(task.expect)
            except ValueError as error:
                found.append(("invalid", f"expect: {error}"))
                return Examination(found, form, behaviour)
        behaviour = self._fill_arms(behaviour, expect, scene.id, grounders[0].world)
        if expect is not None:
            mismatch = _mismatch(behaviour, expect)
            if mismatch:
                found.append(("expectation", mismatch))
        world = grounders[0].world
        found += [("route", problem) for step in behaviour.steps
                  for problem in degenerate_routes(step, world)]
        found += [("infeasible", problem) for problem in
                  infeasible(behaviour, grounders[0].world)]
        missing = self.repertoires[scene.id].missing(behaviour, world,
                                                     compose=task.level in COMPOSING_LEVELS)
        if missing:
            found.append(("repertoire", missing))
        return Examination(found, form, behaviour)

    def _grounders(self, scene: str, layout: str) -> list[Grounder]:
        key = (scene, layout)
        if key not in self.grounders:
            self.grounders[key] = [Grounder(w) for w in jitter_worlds(self.spec.scenes[scene],
                                                                       layout)]
        return self.grounders[key]

    def _fill_arms(self, behaviour: Behaviour, expect: dict | None, scene: str,
                   world: World) -> Behaviour:
        """Unnamed arms: the expectation's, else the one arm training uses for those steps."""
        steps = list(behaviour.steps)
        wanted = (expect or {}).get("steps") or []
        for index, step in enumerate(steps):
            if step.arm is not None:
                continue
            arm = wanted[index].get("arm") if index < len(wanted) else None
            if arm is None:
                arm = self.repertoires[scene].arm_for(behaviour, index, world)
            steps[index] = step.model_copy(update={"arm": arm})
        return behaviour.model_copy(update={"steps": tuple(steps)})


def _grounding_kind(error: GroundingError) -> str:
    return "ambiguous" if error.code == "ambiguous" else "no-referent"


def _grounding_message(error: GroundingError, world: World) -> str:
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
            anchor = world.poses[Grounder(world).resolve(related.landmark)]
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


def _jitter_problem(unstable: Unstable, nominal: Behaviour) -> str:
    where = f"at jitter extreme {unstable.case}"
    error = unstable.error
    if error is not None:
        return (f"{where}: {error.message} ({_distances(error, unstable.world)})"
                if error.candidates else f"{where}: {error.message}")
    objects = [(s.source, s.target) for s in nominal.steps]
    return f"{where} it picks {_objects(unstable.objects)} instead of {_objects(objects)}"


def _objects(pairs: list[tuple]) -> str:
    return ", ".join("/".join(b for b in pair if b) for pair in pairs)


def _expectation(expect: dict) -> dict:
    """The expectation, checked: known fields only; waypoints as [mode, body] pairs."""
    unknown = set(expect) - {"steps", "branch", "condition", "other"}
    if unknown:
        raise ValueError(f"unknown fields {', '.join(sorted(unknown))} (known: steps, branch, "
                         "condition, other)")
    steps = expect.get("steps", [])
    if not isinstance(steps, list) or not all(isinstance(s, dict) for s in steps):
        raise ValueError("steps must be a list of objects")
    for step in steps:
        extra = set(step) - set(STEP_FIELDS)
        if extra:
            raise ValueError(f"unknown step fields {', '.join(sorted(extra))} (known: "
                             f"{', '.join(STEP_FIELDS)})")
    return expect


def _mismatch(behaviour: Behaviour, expect: dict) -> str | None:
    """How the grounded behaviour differs from the fields the expectation states."""
    data = behaviour.model_dump(mode="json")
    for key in ("branch", "condition", "other"):
        if key in expect and _normal(expect[key]) != _normal(data[key]):
            return (f"the words select {key} {data[key]!r}; the expectation says "
                    f"{expect[key]!r}")
    wanted = expect.get("steps")
    if wanted is None:
        return None
    if len(wanted) != len(behaviour.steps):
        return (f"the words select {len(behaviour.steps)} step(s) ({describe(behaviour)}); "
                f"the expectation states {len(wanted)}")
    for index, (got, want) in enumerate(zip(data["steps"], wanted, strict=True), start=1):
        for field in STEP_FIELDS:
            if field in want and _normal(want[field]) != _normal(got[field]):
                where = f"step {index}'s " if len(wanted) > 1 else ""
                return (f"the words select {where}{field} {_shown(got[field])}; the "
                        f"expectation says {_shown(want[field])} ({describe(behaviour)})")
    return None


def _normal(value):
    """JSON values compared as data: waypoint pairs as a sorted list, objects by their keys."""
    if isinstance(value, dict):
        return {k: _normal(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        items = [_normal(v) for v in value]
        return sorted(items) if items and all(isinstance(v, list) for v in items) else items
    return value


def _shown(value) -> str:
    if isinstance(value, list):
        return ", ".join(" ".join(map(str, v)) if isinstance(v, list) else str(v)
                         for v in value) or "none"
    return str(value)


def read_task_list(path) -> list[ListedTask]:
    """The tasks of a JSON Lines file; a bad line is an error naming file:line."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise RoboFollowError(f"cannot read {path}: {error.strerror}") from None
    tasks, seen = [], {}
    for line in json_lines(data):
        number = line.number
        if not line.text:
            raise RoboFollowError(f"{path}:{number}:{line.column}: {line.problem}")
        try:
            task = ListedTask.model_validate_json(line.raw)  # (says what is wrong, field by field)
        except ValidationError as error:
            problems = "; ".join(f"{'.'.join(map(str, p['loc'])) or 'line'}: {p['msg']}"
                                 for p in error.errors())
            raise RoboFollowError(f"{path}:{number}: {problems}") from None
        if task.id in seen:
            raise RoboFollowError(f"{path}:{number}: id {task.id!r} is also on line "
                                  f"{seen[task.id]}")
        seen[task.id] = number
        tasks.append(task)
    return tasks


def audit_task_list(spec: Spec, training: dict[str, Behaviour],
                    tasks: list[ListedTask]) -> dict:
    """{"checked": n, "findings": [{id, kind, message}, ...]} in task order."""
    auditor = TaskAuditor(spec, training)
    return {"checked": len(tasks),
            "findings": [finding for task in tasks for finding in auditor.audit(task)]}


def task_list(splits) -> list[dict]:
    """A compiled benchmark's test tasks as a task list (expect = the compiled behaviour)."""
    return [{"id": t.id, "scene": t.scene, "level": t.level, "layout": t.layout,
             "instruction": t.instruction, "expect": t.behaviour.model_dump(mode="json")}
            for t in splits.tasks]


# what stops a listed test
FATAL = ("invalid", "parse", "no-referent", "ambiguous", "expectation", "infeasible")


def listed_tests(spec: Spec, training: dict[str, Behaviour], sources: Sources,
                 skip: dict[str, set[str]] | None = None
                 ) -> tuple[tuple[TestTask, ...], list[SpecError]]:
    """The test tasks spec authors list in their levels, compiled, and a located error
    (showing its line of `sources`) for each that fails (tests on the layouts in `skip` are
    left unchecked). What would stop a
    generated candidate (no single referent, also at the jitter extremes, another behaviour
    than `expect` states, or one the expert cannot perform) is an error at the test; leakage,
    level and repertoire problems are left to the split audit, as for generated tasks."""
    auditor = TaskAuditor(spec, training)
    tasks, errors = [], []
    for scene in spec.scenes.values():
        for test in scene.tests:
            if test.layout in (skip or {}).get(scene.id, ()):
                continue
            expect = (None if test.expect is None else
                      {"branch": test.expect.branch,
                       "steps": [s.model_dump(mode="json") for s in test.expect.steps]})
            examined = auditor.examine(ListedTask(id=test.id, scene=test.scene, level=test.level,
                                                  layout=test.layout,
                                                  instruction=test.instruction, expect=expect))
            fatal = [(kind, message) for kind, message in examined.findings if kind in FATAL]
            if fatal:
                errors += [spec_error(f"test-{kind}", message, test.source, sources,
                                      len(test.name))
                           for kind, message in fatal]
                continue
            tasks.append(TestTask(id=test.id, scene=test.scene, level=test.level,
                                  layout=test.layout, instruction=test.instruction,
                                  form=examined.form, behaviour=examined.behaviour,
                                  origin=test.name, wording="listed"))
    return tuple(tasks), errors

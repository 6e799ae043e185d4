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
wording       a wording that is not a training instruction reads otherwise than it is scored:
              premodifiers out of English order, a comparison among fewer than two bodies, a
              superlative after the noun that the head noun alone would give to another body
leakage       as in the split audit: training pairs or forms, spec identifiers in the words
level         the task is not what its level claims (L0 training pairs, L1 training
              instructions on new layouts, L2 training layouts, L3 new layouts)
invalid       an unknown scene, layout or level
"""

from __future__ import annotations

import json
from dataclasses import dataclass

from pydantic import ValidationError, create_model

from robofollow.compiler.authoring.spec_files import Sources, spec_error
from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.scene.behaviour import Behaviour, Step, describe
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.spec import LEVELS, Spec
from robofollow.compiler.splits.task_rules import TaskRules
from robofollow.compiler.splits.tasks import TestTask
from robofollow.errors import InstructionError, RoboFollowError, SpecError
from robofollow.files import json_lines, read_file_at_most

FINDING_KINDS = ("invalid", "parse", "no-referent", "ambiguous", "expectation", "route",
                 "infeasible", "repertoire", "duplicate", "leakage", "level", "wording")
STEP_FIELDS = ("action", "arm", "source", "relation", "target", "waypoints", "yaw_degrees")
MAX_TASK_LIST_BYTES = 16 * 1024 * 1024  # a task list: the compiled benchmark's 635 test
#   tasks, exported with their behaviours (--export-tasks), take about 300 KB


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
    """Examines listed tasks in order with each scene's test-task rules (task_rules.py), plus
    what only a list has: unknown names, parse errors and `expect` fields."""

    def __init__(self, spec: Spec, training: dict[str, Behaviour]):
        self.spec, self.training = spec, training
        self.rules = {scene.id: TaskRules(scene, training) for scene in spec.scenes.values()}

    def audit(self, task: ListedTask) -> list[dict]:
        return [{"id": task.id, "kind": kind, "message": message}
                for kind, message in self.examine(task).findings]

    def examine(self, task: ListedTask) -> Examination:
        """The findings, and the form and behaviour as far as the task gets."""
        found: list[tuple[str, str]] = []
        scene = self.spec.scenes.get(task.scene)
        if scene is None:
            found.append(("invalid", (f"no scene {task.scene!r} (scenes: "
                                      f"{', '.join(self.spec.scenes)})")))
        elif task.layout not in scene.layouts:
            found.append(("invalid", (f"{task.scene} has no layout {task.layout!r} "
                                      f"(layouts: {', '.join(scene.layouts)})")))
        elif task.level not in LEVELS:
            found.append(("invalid", f"no level {task.level!r} (levels: {', '.join(LEVELS)})"))
        if found:
            return Examination(found, None, None)
        try:
            form = parse(task.instruction)
        except InstructionError as error:
            return Examination([("parse", f"column {error.column}: {error.message}")], None, None)
        try:
            expect = None if task.expect is None else _expectation(task.expect)
        except ValueError as error:
            return Examination([("invalid", f"expect: {error}")], form, None)
        rules = self.rules[scene.id]
        examined = rules.examine(task.level, task.layout, task.instruction, form,
                                 self._arms(expect, rules))
        found = examined.findings
        if expect is not None and examined.behaviour is not None:
            mismatch = _mismatch(examined.behaviour, expect)
            if mismatch:
                found.append(("expectation", mismatch))
        rules.keep(task.id, task.level, task.layout, form)
        return Examination(found, form, examined.behaviour)

    @staticmethod
    def _arms(expect: dict | None, rules: TaskRules):
        """Unnamed arms: the expectation's, else the one arm training uses for those steps."""
        wanted = (expect or {}).get("steps") or []

        def fill(behaviour: Behaviour, world) -> Behaviour:
            steps = list(behaviour.steps)
            for index, step in enumerate(steps):
                if step.arm is not None:
                    continue
                arm = wanted[index].get("arm") if index < len(wanted) else None
                if arm is None:
                    arm = rules.repertoire.arm_for(behaviour, index, world)
                steps[index] = step.model_copy(update={"arm": arm})
            return behaviour.model_copy(update={"steps": tuple(steps)})
        return fill


# An expectation states some of a behaviour's fields: Step's and Behaviour's, each optional
_ExpectedStep = create_model("_ExpectedStep", __base__=Model, **{
    name: (field.annotation | None, None) for name, field in Step.model_fields.items()})
_Expected = create_model("_Expected", __base__=Model, **{
    name: ((tuple[_ExpectedStep, ...] if name in ("steps", "other") else field.annotation)
           | None, None) for name, field in Behaviour.model_fields.items()})


def _expectation(expect: dict) -> dict:
    """The expectation, checked: known fields only, each of its type (as Behaviour and Step
    have them: waypoints as [mode, body] pairs)."""
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
    try:
        _Expected.model_validate_json(json.dumps(expect), strict=True)
    except ValidationError as error:
        first = error.errors()[0]
        raise ValueError(f"{'.'.join(map(str, first['loc']))}: {first['msg']}") from None
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
    """The tasks of a JSON Lines file (up to MAX_TASK_LIST_BYTES); a bad line is an error
    naming file:line and the field."""
    data, problem = read_file_at_most(path, MAX_TASK_LIST_BYTES)
    if problem:
        raise RoboFollowError(f"{path}: {problem}; a task list holds one line per task")
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



def listed_tests(spec: Spec, training: dict[str, Behaviour], sources: Sources,
                 skip: dict[str, set[str]] | None = None
                 ) -> tuple[tuple[TestTask, ...], list[SpecError]]:
    """The test tasks spec authors list in their levels, compiled, and a located error
    (showing its line of `sources`) for each finding of each that fails (tests on the layouts
    in `skip` are left unchecked). A listed test obeys every rule a generated candidate does
    (task_rules.py) and its `expect`: the split generator keeps it as it is, so whatever the
    audit would find in it is an error at the test."""
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
            if examined.findings:
                errors += [spec_error(f"test-{kind}", message, test.source, sources,
                                      len(test.name))
                           for kind, message in examined.findings]
                continue
            tasks.append(TestTask(id=test.id, scene=test.scene, level=test.level,
                                  layout=test.layout, instruction=test.instruction,
                                  form=examined.form, behaviour=examined.behaviour,
                                  origin=test.name, wording="listed"))
    return tuple(tasks), errors

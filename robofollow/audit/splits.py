"""The split audit: do the splits measure what they claim?

- scene entropy H(T|S) over the training groups;
- every compiled test task re-examined by the rules the generator applies to its candidates
  (compiler/splits/task_rules.py: leakage, level, repertoire, route, feasibility, duplicates,
  ambiguity at the nominal positions and the jitter extremes, truthful wording), each scene
  against its own spec, so a fresh build audits clean by construction and a hand-edited or
  foreign one shows what is wrong (a task the generator itself examined and kept is not
  grounded again: see task_findings);
- every training instruction grounds to its behaviour at the jitter extremes too.
"""

from __future__ import annotations

from robofollow.audit.entropy import same_behaviours, scene_groups
from robofollow.audit.report import FINDING_LISTS
from robofollow.compiler.language import lf
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.grounding import Grounder, instability
from robofollow.compiler.scene.spec import LEVELS, Spec
from robofollow.compiler.scene.world import jitter_worlds
from robofollow.compiler.splits.split_report import rule_report
from robofollow.compiler.splits.task_rules import TaskRules, arms_of
from robofollow.compiler.splits.tasks import Splits, TestTask


def task_findings(spec: Spec, training: dict[str, Behaviour], splits: Splits,
                  examined: frozenset[TestTask] = frozenset()) -> dict:
    """{list name: [{task, finding}]}: every compiled task examined in order by its scene's
    rules (FINDING_LISTS). A task in `examined` (the generator's, `generate_examined` of the
    same spec and training) passed the rules that ground it when the generator kept it, and
    they read nothing but the task, its scene and the training behaviours, so only the rules
    that read the other tasks (duplicates) and the training (leakage, level) run again: the
    audit stays complete for tasks edited, added or reordered after generating."""
    rules = {scene: TaskRules(spec.scenes[scene], training) for scene in spec.scenes}
    kinds = {kind: name for name, members in FINDING_LISTS.items() for kind in members}
    found: dict[str, list[dict]] = {name: [] for name in FINDING_LISTS}
    for task in splits.tasks:
        scene_rules = rules[task.scene]
        if task in examined:
            findings, behaviour = scene_rules.placement(
                task.level, task.layout, task.instruction, lf.to_json(task.form)), task.behaviour
        else:
            examination = scene_rules.examine(task.level, task.layout, task.instruction,
                                              task.form, arms_of(task.behaviour))
            findings, behaviour = examination.findings, examination.behaviour
        for kind, message in findings:
            found[kinds[kind]].append({"task": task.id, "finding": message})
        if behaviour is not None and behaviour != task.behaviour:
            found["ambiguities"].append({"task": task.id, "finding": (
                "its words ground to another behaviour than the compiled one")})
        scene_rules.keep(task.id, task.level, task.layout, task.form)
    return found


def training_ambiguities(spec: Spec, training: dict[str, Behaviour]) -> list[dict]:
    """Training instructions that fail to ground, or ground differently, under jitter
    extremes (a task's paraphrases mostly share their form: each form is checked once)."""
    findings = []
    grounders: dict[tuple[str, str], list[Grounder]] = {}
    for task in spec.tasks:
        key = (task.scene, task.layout)
        if key not in grounders:
            grounders[key] = [Grounder(w) for w in jitter_worlds(spec.scenes[task.scene],
                                                                 task.layout)]
        problems: dict[str, str | None] = {}  # form JSON -> its problem
        for index, form in enumerate(task.forms):
            data = lf.to_json(form)
            if data not in problems:
                problems[data] = instability(form, grounders[key], training[task.label])
            problem = problems[data]
            if problem:
                findings.append({"task": f"{task.label}#{index + 1}", "finding": problem})
    return findings


def scene_audit(spec: Spec, training: dict[str, Behaviour], splits: Splits,
                examined: frozenset[TestTask] = frozenset()) -> dict:
    """The audit of the scenes of `spec` as one JSON-ready object, without what `report.combine`
    adds over every scene of a benchmark (`examined`: see task_findings). A scene's part
    depends on its own spec and splits alone."""
    groups = scene_groups(spec)
    for group in groups:
        group["behaviours"] = same_behaviours(spec, training, group["tasks"])
    found = task_findings(spec, training, splits, examined)
    found["ambiguities"] = training_ambiguities(spec, training) + found["ambiguities"]
    return {
        "groups": groups,
        "same_behaviour": [{"layout": g["layout"], "tasks": b} for g in groups
                           for b in g["behaviours"] if len(b) > 1],
        "counts": {scene: {level: len(splits.of(scene, level)) for level in LEVELS}
                   for scene in spec.scenes},
        **found,
        "rejected": len(splits.rejected),
        "split_rules": rule_report(spec, splits),
    }

"""The split audit: do the splits measure what they claim?

- scene entropy H(T|S) over the training groups;
- leakage: no test (layout, form) pair is a training pair, no L2/L3 form is a training form,
  no instruction names a spec identifier;
- level consistency: L0 tasks are training pairs, L1 tasks training instructions on layouts
  that look different from every training layout, L2 tasks on training layouts, L3 tasks on
  layouts that look different (observation.py: by appearance and position, not names);
- repertoire: training performs every test behaviour's motions, as a whole for L0 and L1,
  step by step for L2 and L3 (motions.py; recomputed here, independently of generation);
- routes: every body a route names is on the way from the source to the destination
  (routes.py);
- feasibility: the expert can perform every test behaviour (feasibility.py);
- duplicates: no test task repeats another's meaning on a layout that looks the same;
- ambiguity: every instruction grounds to one and the same behaviour on its layout at the
  nominal positions and with the jitter at its extremes.
"""

from __future__ import annotations

import re

from robofollow.audit.entropy import (
    behaviour_entropy_bits,
    entropy_bits,
    same_behaviours,
    scene_groups,
)
from robofollow.compiler import lf
from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.feasibility import infeasible
from robofollow.compiler.grounding import Grounder, instability
from robofollow.compiler.lexicon import VOCABULARY
from robofollow.compiler.motions import COMPOSING_LEVELS, Repertoire
from robofollow.compiler.observation import look_alike, same_observation
from robofollow.compiler.routes import degenerate_routes
from robofollow.compiler.spec import Spec
from robofollow.compiler.split_report import rule_report
from robofollow.compiler.splits import Splits
from robofollow.compiler.world import World, jitter_worlds


def _identifiers(spec: Spec) -> set[str]:
    """Spec names that could leak into an instruction (those that are not plain words)."""
    names = set(spec.scenes)
    for scene in spec.scenes.values():
        names |= set(scene.bodies) | set(scene.layouts) | set(scene.points)
        names |= {task.label for task in scene.tasks}
    return {n for n in names if n.lower() not in VOCABULARY}


class TrainingFacts:
    """What the training tasks fix, for the leakage and level checks of any test task
    (`form` is a logical form's canonical JSON)."""

    def __init__(self, spec: Spec):
        self.pairs = {(t.scene, t.layout, lf.to_json(f)) for t in spec.tasks for f in t.forms}
        self.forms = {form for _, _, form in self.pairs}
        self.instructions = {p for t in spec.tasks for p in t.paraphrases}
        self.spec = spec
        identifiers = sorted(_identifiers(spec), key=len, reverse=True)
        self.pattern = re.compile(r"\b(" + "|".join(map(re.escape, identifiers)) + r")\b",
                                  re.IGNORECASE) if identifiers else None

    def leakage(self, level: str, scene: str, layout: str, form: str,
                instruction: str) -> list[str]:
        found = []
        if level != "L0" and (scene, layout, form) in self.pairs:
            found.append("its (layout, form) pair is a training pair")
        if level in ("L2", "L3") and form in self.forms:
            found.append("its form is a training form")
        named = self.pattern.search(instruction) if self.pattern else None
        if named:
            found.append(f"its instruction names the spec identifier {named.group(0)!r}")
        return found

    def level_problems(self, level: str, scene: str, layout: str, form: str,
                       instruction: str) -> list[str]:
        scene_spec = self.spec.scenes[scene]
        same = look_alike(scene_spec, layout, scene_spec.training_layouts)
        found = []
        if level == "L0" and (scene, layout, form) not in self.pairs:
            found.append("an L0 task is a training pair, but no training task asks this on "
                         f"{layout}")
        if level in ("L1", "L3") and same is not None:
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
    """Test tasks seen so far, to find one that repeats another: the same scene, level and
    logical form on a layout that looks the same (a task counted twice)."""

    def __init__(self, spec: Spec):
        self.spec = spec
        self.seen: dict[tuple[str, str, str], list[tuple[str, str]]] = {}

    def repeat(self, task_id: str, scene: str, level: str, layout: str, form: str) -> str | None:
        entries = self.seen.setdefault((scene, level, form), [])
        for other_layout, other in entries:
            if other_layout == layout or same_observation(self.spec.scenes[scene], layout,
                                                          other_layout):
                where = ("" if other_layout == layout else
                         f" ({layout} looks the same as {other_layout})")
                return f"it repeats {other}: the same meaning on the same layout{where}"
        entries.append((layout, task_id))
        return None


def duplicates(spec: Spec, splits: Splits) -> list[dict]:
    seen = SeenTasks(spec)
    found = [(task.id, seen.repeat(task.id, task.scene, task.level, task.layout,
                                   lf.to_json(task.form))) for task in splits.tasks]
    return [{"task": task, "finding": finding} for task, finding in found if finding]


def _split_findings(spec: Spec, splits: Splits, check: str) -> list[dict]:
    facts = TrainingFacts(spec)
    return [{"task": task.id, "finding": finding} for task in splits.tasks
            for finding in getattr(facts, check)(task.level, task.scene, task.layout,
                                                 lf.to_json(task.form), task.instruction)]


def leakage(spec: Spec, splits: Splits) -> list[dict]:
    return _split_findings(spec, splits, "leakage")


def level_inconsistencies(spec: Spec, splits: Splits) -> list[dict]:
    return _split_findings(spec, splits, "level_problems")


def repertoire_violations(spec: Spec, training: dict[str, Behaviour],
                          splits: Splits) -> list[dict]:
    findings = []
    for scene in spec.scenes.values():
        performed = Repertoire(scene, training)
        for task in splits.tasks:
            if task.scene == scene.id:
                missing = performed.missing(task.behaviour, World(scene, task.layout),
                                            compose=task.level in COMPOSING_LEVELS)
                if missing:
                    findings.append({"task": task.id, "finding": missing})
    return findings


def infeasible_tasks(spec: Spec, splits: Splits) -> list[dict]:
    return [{"task": task.id, "finding": problem} for task in splits.tasks
            for problem in infeasible(task.behaviour, World(spec.scenes[task.scene], task.layout))]


def degenerate_route_findings(spec: Spec, splits: Splits) -> list[dict]:
    return [{"task": task.id, "finding": problem} for task in splits.tasks
            for step in task.behaviour.steps
            for problem in degenerate_routes(step, World(spec.scenes[task.scene], task.layout))]


def ambiguities(spec: Spec, training: dict[str, Behaviour], splits: Splits) -> list[dict]:
    """Instructions that fail to ground, or ground differently, under jitter extremes."""
    findings = []
    items = [(t.scene, t.layout, f"{t.label}#{i + 1}", form, training[t.label])
             for t in spec.tasks for i, form in enumerate(t.forms)]
    items += [(t.scene, t.layout, t.id, t.form, t.behaviour) for t in splits.tasks]
    grounders: dict[tuple[str, str], list[Grounder]] = {}
    for scene_id, layout, name, form, expected in items:
        key = (scene_id, layout)
        if key not in grounders:
            grounders[key] = [Grounder(w) for w in jitter_worlds(spec.scenes[scene_id], layout)]
        problem = instability(form, grounders[key], expected)
        if problem:
            findings.append({"task": name, "finding": problem})
    return findings


def audit(spec: Spec, training: dict[str, Behaviour], splits: Splits) -> dict:
    """The audit as one JSON-ready object."""
    groups = scene_groups(spec)
    for group in groups:
        group["behaviours"] = same_behaviours(spec, training, group["tasks"])
    counts = {scene: {level: len(splits.of(scene, level)) for level in ("L0", "L1", "L2", "L3")}
              for scene in spec.scenes}
    return {
        "spec_digest": spec.digest,
        "scene_entropy_bits": round(entropy_bits([len(g["tasks"]) for g in groups]), 6),
        "behaviour_entropy_bits": round(behaviour_entropy_bits(
            [[len(b) for b in g["behaviours"]] for g in groups]), 6),
        "groups": groups,
        "same_behaviour": [{"layout": g["layout"], "tasks": b} for g in groups
                           for b in g["behaviours"] if len(b) > 1],
        "counts": counts,
        "leakage": leakage(spec, splits),
        "level_inconsistencies": level_inconsistencies(spec, splits),
        "repertoire_violations": repertoire_violations(spec, training, splits),
        "degenerate_routes": degenerate_route_findings(spec, splits),
        "infeasible": infeasible_tasks(spec, splits),
        "duplicates": duplicates(spec, splits),
        "ambiguities": ambiguities(spec, training, splits),
        "rejected": len(splits.rejected),
        "split_rules": rule_report(spec, splits),
    }


FINDING_KEYS = ("leakage", "level_inconsistencies", "repertoire_violations", "degenerate_routes",
                "infeasible", "duplicates", "ambiguities")


def findings(report: dict) -> int:
    return sum(len(report[k]) for k in FINDING_KEYS)

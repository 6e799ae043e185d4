"""The split audit: do the splits measure what they claim?

- scene entropy H(T|S) over the training groups;
- leakage: no test (layout, form) pair is a training pair, no L2/L3 form is a training form,
  L1 instructions are training instructions, no instruction names a spec identifier;
- repertoire: every test behaviour is performed by some training task (recomputed here,
  independently of generation);
- ambiguity: every instruction grounds to one and the same behaviour on its layout at the
  nominal positions and with the jitter at its extremes.
"""

from __future__ import annotations

import re

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.grounding import Grounder, instability
from robofollow.compiler.lexicon import VOCABULARY
from robofollow.compiler.spec import Spec
from robofollow.compiler.splits import Splits, signature
from robofollow.compiler.world import World, jitter_worlds
from robofollow.oracle.entropy import entropy_bits, scene_groups


def _identifiers(spec: Spec) -> set[str]:
    """Spec names that could leak into an instruction (those that are not plain words)."""
    names = set(spec.scenes)
    for scene in spec.scenes.values():
        names |= set(scene.bodies) | set(scene.layouts) | set(scene.points)
        names |= {task.label for task in scene.tasks}
    return {n for n in names if n.lower() not in VOCABULARY}


def leakage(spec: Spec, splits: Splits) -> list[dict]:
    findings = []
    training_pairs = {(t.scene, t.layout, lf.to_json(f)) for t in spec.tasks for f in t.forms}
    training_forms = {form for _, _, form in training_pairs}
    training_strings = {p for t in spec.tasks for p in t.paraphrases}
    identifiers = sorted(_identifiers(spec), key=len, reverse=True)
    pattern = re.compile(r"\b(" + "|".join(map(re.escape, identifiers)) + r")\b",
                         re.IGNORECASE) if identifiers else None
    for task in splits.tasks:
        form = lf.to_json(task.form)
        if task.level != "L0" and (task.scene, task.layout, form) in training_pairs:
            findings.append({"task": task.id, "finding": "its (layout, form) pair is a "
                                                         "training pair"})
        if task.level in ("L2", "L3") and form in training_forms:
            findings.append({"task": task.id, "finding": "its form is a training form"})
        if task.level == "L1" and task.instruction not in training_strings:
            findings.append({"task": task.id, "finding": "its instruction is not a training "
                                                         "instruction"})
        named = pattern.search(task.instruction) if pattern else None
        if named:
            findings.append({"task": task.id, "finding": f"its instruction names the spec "
                                                         f"identifier {named.group(0)!r}"})
    return findings


def repertoire_violations(spec: Spec, training: dict[str, Behaviour],
                          splits: Splits) -> list[dict]:
    findings = []
    for scene in spec.scenes.values():
        repertoire = {signature(training[t.label], World(scene, t.layout)) for t in scene.tasks}
        for task in splits.of(scene.id, "L0") + splits.of(scene.id, "L1") + splits.of(
                scene.id, "L2") + splits.of(scene.id, "L3"):
            if signature(task.behaviour, World(scene, task.layout)) not in repertoire:
                findings.append({"task": task.id, "finding": "no training task performs "
                                                             "this behaviour"})
    return findings


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
    counts = {scene: {level: len(splits.of(scene, level)) for level in ("L0", "L1", "L2", "L3")}
              for scene in spec.scenes}
    return {
        "spec_digest": spec.digest,
        "scene_entropy_bits": round(entropy_bits([len(g["tasks"]) for g in groups]), 6),
        "groups": groups,
        "counts": counts,
        "leakage": leakage(spec, splits),
        "repertoire_violations": repertoire_violations(spec, training, splits),
        "ambiguities": ambiguities(spec, training, splits),
        "rejected": len(splits.rejected),
    }


def findings(report: dict) -> int:
    return sum(len(report[k]) for k in ("leakage", "repertoire_violations", "ambiguities"))

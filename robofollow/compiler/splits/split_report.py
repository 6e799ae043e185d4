"""What the split rules did: tasks per scene, level and layout, what each cap dropped, and
rules (or layouts named in them) that yield nothing, with the reason."""

from __future__ import annotations

from collections import Counter

from robofollow.compiler.scene.spec import LEVELS, Spec
from robofollow.compiler.splits.tasks import Splits

CAPPED = "over the split's max"


def _reason(text: str) -> str:
    """A rejection reason's kind: the words before its first colon or parenthesis."""
    return text.split(":")[0].split(" (")[0]


def rule_report(spec: Spec, splits: Splits) -> dict:
    """{"layouts": {scene: {level: {layout: n}}}, "capped": [...], "warnings": [...]}."""
    layouts: dict = {}
    for task in splits.tasks:
        per_level = layouts.setdefault(task.scene, {}).setdefault(task.level, {})
        per_level[task.layout] = per_level.get(task.layout, 0) + 1
    capped, warnings = [], []
    for scene in spec.scenes.values():
        l1 = scene.splits.get("L1")
        for level in LEVELS:
            rule = scene.splits.get(level)
            rejected = [r for r in splits.rejected if r.scene == scene.id and r.level == level]
            dropped = Counter(r.layout for r in rejected if r.reason.startswith(CAPPED))
            if dropped:
                kept = len(splits.of(scene.id, level))
                capped.append({"scene": scene.id, "level": level, "max": rule.max_tasks,
                               "kept": kept, "dropped": sum(dropped.values()),
                               "dropped_by_layout": dict(sorted(dropped.items()))})
            if rule is None:
                continue
            counts = layouts.get(scene.id, {}).get(level, {})
            for layout in rule.layouts:
                if counts.get(layout):
                    continue
                if level == "L3" and layout not in (l1.layouts if l1 else ()):
                    why = ("L3 rewords the kept L1 tasks of its layouts, and the L1 rule does "
                           "not name it")
                else:
                    reasons = Counter(_reason(r.reason) for r in rejected if r.layout == layout)
                    why = (f"{sum(reasons.values())} candidates rejected, most often: "
                           f"{reasons.most_common(1)[0][0]}" if reasons else "no candidates")
                warnings.append(f"{scene.id} split {level}: layout {layout} yields no task "
                                f"({why})")
            if not counts and not rule.layouts:
                reasons = Counter(_reason(r.reason) for r in rejected)
                why = (f"{sum(reasons.values())} candidates rejected, most often: "
                       f"{reasons.most_common(1)[0][0]}" if reasons else "no candidates")
                warnings.append(f"{scene.id} split {level} yields no task ({why})")
    return {"layouts": layouts, "capped": capped, "warnings": warnings}

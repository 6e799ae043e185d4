"""The build in words, for people: summary.txt and what changed against a previous build."""

from __future__ import annotations

from collections import Counter

from robofollow.audit.report import FINDING_KEYS
from robofollow.benchmark.compiled import Compiled
from robofollow.benchmark.labels import object_moved
from robofollow.compiler.scene.spec import LEVELS, MOTION_LEVELS
from robofollow.errors import counted, named


def summary(compiled: Compiled, changes: str = "") -> str:
    report, spec = compiled.report, compiled.spec
    lines = [(f"RoboFollow: {counted(len(spec.scenes), 'scene')}, "
             f"{counted(len(spec.tasks), 'training task')}, spec digest {spec.digest[:12]}"),
             (f"scene entropy H(T|S) = {report['scene_entropy_bits']:.3f} bits over "
             f"{counted(len(report['groups']), 'training scene group')} (task labels, as the "
             "paper counts); "
             f"over distinct behaviours H(B|S) = {report['behaviour_entropy_bits']:.3f} bits"),
             "split digests: " + ", ".join(f"{scene} {digest[:12]}"
                                           for scene, digest in compiled.split_digests.items()),
             "", "test tasks per scene and level (each run for the split's rounds):",
             "          " + "".join(f"{level:>6}" for level in LEVELS)]
    for scene, counts in report["counts"].items():
        lines.append(f"{scene:<10}" + "".join(f"{counts[level]:>6}" for level in LEVELS))
    lines += _blind_best_text(report["blind_best"], report["guessable"])
    lines += _motion_text(compiled)
    lines += _rules_text(report["split_rules"])
    lines += _unreworded_text(compiled)
    same = report["same_behaviour"]
    lines += ["", f"training tasks with the same behaviour on one layout: {len(same) or 'none'}"]
    lines += [f"  {item['layout']}: {', '.join(item['tasks'])}" for item in same]
    lines += ["", f"rejected candidates: {report['rejected']} (rejected.jsonl says why)"]
    for key in FINDING_KEYS:
        title = key.replace("_", " ")
        items = report[key]
        lines.append(f"{title}: {len(items) or 'none'}")
        lines += [f"  {item['task']}: {item['finding']}" for item in items[:20]]
    return "\n".join(lines) + "\n" + changes


def _blind_best_text(best: dict, guessable: list[dict]) -> list[str]:
    """Per scene and level, the best language-blind guess against chance, Intent and
    completion; then the cells the guess margin flags."""
    lines = ["", ("the best language-blind guess / chance, IS and CR (on each layout the one "
                  "training behaviour that earns most over the cell's tests / a uniform "
                  "guess among those the layout allows):"),
             "             " + "".join(f"{level:>12}" for level in LEVELS)]
    for scene, levels in best.items():
        for metric in ("IS", "CR"):
            lines.append((f"{scene:<10}{metric:>3}" + "".join(
                f"{levels[level][metric]:>6.1f}/{levels[level][f'chance_{metric}']:<5.1f}"
                if level in levels else f"{'.':>12}" for level in LEVELS)).rstrip())
    lines.append("guessable cells (the best guess more than the scene's guess_margin over "
                 f"chance): {len(guessable) or 'none'}")
    lines += [f"  {cell['scene']} {cell['level']}: {cell['IS']:.1f} against chance "
              f"{cell['chance_IS']:.1f} (margin {cell['margin']:g})" for cell in guessable]
    return lines


def _motion_text(compiled: Compiled) -> list[str]:
    """Per scene, how many L1 and L3 tasks are moved (the expert moves otherwise than in the
    training task) and how many as-trained (it moves as trained), and of the moved ones how
    many also move their object (labels.py: the two labels answer different questions)."""
    lines = ["", ("L1 and L3 tasks by motion (moved: the expert moves otherwise than in the "
                  "training task; of those, object moved: a handled body stands elsewhere):"),
             "          " + "".join(f"{f'{level} moved':>10}{'object moved':>14}"
                                    f"{f'{level} as-trained':>16}" for level in MOTION_LEVELS)]
    for scene_id, scene in compiled.spec.scenes.items():
        row = ""
        for level in MOTION_LEVELS:
            tasks = compiled.splits.of(scene_id, level)
            moved = [t for t in tasks if t.motion == "moved"]
            shifted = sum(bool(object_moved(scene, t, compiled.training)) for t in moved)
            trained = sum(1 for t in tasks if t.motion == "as-trained")
            row += f"{len(moved):>10}{shifted:>14}{trained:>16}"
        lines.append(f"{scene_id:<10}{row}")
    listed = sum(1 for t in compiled.splits.tasks if t.level in MOTION_LEVELS and t.motion is None)
    if listed:
        lines.append(f"  (and {listed} listed L1/L3 tests, whose motion is not classified)")
    return lines


def _rules_text(rules: dict) -> list[str]:
    """Tasks per layout, what each cap dropped and the rules' warnings, for people."""
    lines = ["", "test tasks per layout:"]
    for scene, levels in rules["layouts"].items():
        lines.append(f"  {scene:<12}" + "".join(f"{level:>6}" for level in LEVELS))
        for layout in dict.fromkeys(name for level in LEVELS for name in levels.get(level, {})):
            lines.append(f"    {layout:<10}" + "".join(
                f"{levels.get(level, {}).get(layout, '.'):>6}" for level in LEVELS))
    lines.append(f"caps: {'none applied' if not rules['capped'] else ''}".rstrip())
    lines += [f"  {c['scene']} {c['level']}: {c['kept']} kept (max {c['max']}), {c['dropped']} "
              "dropped ("
              + ", ".join(f"{layout} {n}" for layout, n in c["dropped_by_layout"].items()) + ")"
              for c in rules["capped"]]
    lines.append(f"split rule warnings: {len(rules['warnings']) or 'none'}")
    lines += [f"  {warning}" for warning in rules["warnings"]]
    return lines


CAPPED = "over the split's max"  # a rejection that a kept candidate would have replaced
WORDS = "words: no training instruction of "  # a rewording with words training never uses


def _unreworded_text(compiled: Compiled) -> list[str]:
    """Per scene and reworded level (a rule with `wordings`), the training tasks no
    rewording of which was kept, the cap apart, and what dropped their candidates: above all
    the words a generator used that no training instruction of the scene does."""
    lines = []
    for scene_id, scene in compiled.spec.scenes.items():
        training = [task.label for task in compiled.spec.tasks if task.scene == scene_id]
        for level in ("L2", "L3"):
            rule = scene.splits.get(level)
            if rule is None or not rule.wordings:
                continue
            kept = {task.origin for task in compiled.splits.of(scene_id, level)}
            reasons: dict[str, list[str]] = {label: [] for label in training}
            for rejection in compiled.splits.rejected:
                if rejection.scene == scene_id and rejection.level == level:
                    reasons.setdefault(rejection.origin, []).append(rejection.reason)
            missing = [label for label in training if label not in kept
                       and not any(reason.startswith(CAPPED) for reason in reasons[label])]
            if missing:
                why = _why_dropped([r for label in missing for r in reasons[label]])
                lines.append(f"  {scene_id} {level}: {len(missing)} of {len(training)} "
                             f"({named(missing)}): {why}")
    if not lines:
        return []
    return ["", (f"training tasks with no L2 or L3 rewording kept: {len(lines)} "
                 "scene x level (rejected.jsonl says why, candidate by candidate; a "
                 "rewording keeps to the words of the scene's training instructions, "
                 "docs/spec-language.md#wording-generators):"), *lines]


def _why_dropped(reasons: list[str]) -> str:
    """What dropped the candidates, most often first; for `words`, the words most missing."""
    if not reasons:
        return "no candidate rewording"
    kinds = Counter(reason.split(":")[0] for reason in reasons)
    words = Counter(word for reason in reasons if reason.startswith(WORDS)
                    for word in reason.partition(" uses ")[2].split(", "))
    text = ", ".join(f"{kind} {count}" for kind, count in kinds.most_common())
    if words:
        text += " (words training never uses: " + ", ".join(
            f"{word} {count}" for word, count in words.most_common(6)) + ")"
    return text


def changes(before: set[str], compiled: Compiled, shown: int = 20) -> str:
    """Which test tasks a build adds and removes against the ids of a previous one."""
    if not before:
        return ""
    after = {t.id for t in compiled.splits.tasks}
    added, removed = sorted(after - before), sorted(before - after)
    if not added and not removed:
        return "\nagainst the previous build: the same test tasks\n"
    lines = ["", (f"against the previous build: {counted(len(added), 'test task')} added, "
                 f"{len(removed)} removed")]
    lines += [f"  + {task}" for task in added[:shown]]
    lines += [f"  - {task}" for task in removed[:shown]]
    if max(len(added), len(removed)) > shown:
        lines.append(f"  (the first {shown} of each)")
    return "\n".join(lines) + "\n"

"""What a run's report shows, computed once from its records (full or compact): Table 1 with
chance and the below-chance flag, the findings that open the page, per-layout (L1, L3) and
per-training-task (L2, L3) summaries, what the policy did, where it failed first, a sample of
failure videos per cell, and the per-task tables and instructed x executed matrices.

Tasks are named by their level and full instruction ("L2 · Use your left arm to pick up the
cube that is …"), with the layout where one instruction is given on several ("… @scene2_3")
and a number where even that coincides; the task id is kept beside it."""

from __future__ import annotations

import re
from collections import Counter, defaultdict

import numpy as np

from robofollow.compiler.scene.spec import LEVELS, MOTION_LEVELS
from robofollow.eval.reports.pages import shade
from robofollow.eval.reports.tables import ground_truth
from robofollow.eval.running.outcomes import (
    DID,
    UNRECOGNISED,
    closest,
    first_failure,
    kind,
    kinds,
)
from robofollow.eval.running.run_benchmark import described as benchmark_described
from robofollow.eval.running.runner import EvalOptions, summary
from robofollow.eval.statistics.drops import level_drops, origin
from robofollow.eval.statistics.metrics import (
    METRICS,
    MOTIONS,
    references,
    scores,
    shown_interval,
)
from robofollow.provenance import described

VIDEO_LINK = re.compile(r"videos/[A-Za-z0-9_.#@-]+\.mp4")  # what the runner writes
TOP = 15  # confusions and failure reasons listed
VIDEOS_PER_CELL = 2  # failure videos shown beside each cell
LAYOUT_LEVELS = ("L1", "L3")  # levels whose tasks move to other layouts
DERIVED_LEVELS = ("L2", "L3")  # levels whose tasks derive from a training task
GAP = 20.0  # points: layouts split into two groups this far apart are named in the findings
SHADES = (0, 5, 10, 20, 30, 50, 75, 100)  # the legend's Intent values


def below_chance(cell: dict) -> bool:
    """Whether a cell's Intent lies under chance: the upper end of its interval over tasks
    (the Wilson interval over episodes for a one-task cell) is below the chance Intent."""
    if "chance_IS" not in cell:
        return False
    return shown_interval(cell, "IS")[1] < cell["chance_IS"]


def level_averages(cells: dict, levels: list[str]) -> dict:
    """Per level: each metric (and chance) averaged over the scenes that have it, each scene
    counting equally, as Table 1's average does."""
    found = {}
    for level in levels:
        present = [row[level] for row in cells.values() if level in row]
        keys = [*METRICS, *(["chance_IS"] if all("chance_IS" in c for c in present) else [])]
        found[level] = {key: float(np.mean([c[key] for c in present])) for key in keys}
        found[level]["scenes"] = len(present)
    return found


def task_names(results: list[dict], instructions: dict[str, str]) -> dict[str, str]:
    """Each task's name: its level and instruction (else its id), with its layout where one
    name is given to tasks on several layouts, else numbered."""
    tasks = {r["task"]: r for r in results}
    names = {task: f"{r['level']} · " + instructions.get(task, task.split("/", 2)[-1])
             for task, r in tasks.items()}
    groups: dict[str, list[str]] = defaultdict(list)
    for task in sorted(names):
        groups[names[task]].append(task)
    for group in (g for g in groups.values() if len(g) > 1):
        layouts = [tasks[task].get("layout") for task in group]
        by_layout = len(set(layouts)) == len(group)
        for number, (task, layout) in enumerate(zip(group, layouts, strict=True), 1):
            names[task] += f" @{layout}" if by_layout else f" ({number})"
    return names


def _group(results: list[dict], *keys) -> dict:
    """Records grouped by one key, or by a tuple of keys (a key may be a function)."""
    def value(record, key):
        return key(record) if callable(key) else record[key]
    grouped: dict = defaultdict(list)
    for record in results:
        grouped[value(record, keys[0]) if len(keys) == 1
                else tuple(value(record, k) for k in keys)].append(record)
    return grouped


def breakdown(results: list[dict], levels: tuple[str, ...], key) -> list[dict]:
    """Per scene, level (of `levels`) and key value (a layout, a training task): the scores,
    with the cell's chance Intent where the records carry it."""
    rows = []
    for (scene, level, value), records in sorted(
            _group([r for r in results if r["level"] in levels], "scene", "level", key).items()):
        rows.append({"scene": scene, "level": level, "key": value, **scores(records),
                     "chance_IS": references(records).get("chance_IS")})
    return rows


def concentration(rows: list[dict]) -> list[str]:
    """Findings on cells whose Intent sits on some of their layouts only: the layouts sorted by
    Intent split at their widest gap, where it is at least GAP points."""
    lines = []
    for (scene, level), group in sorted(_group(rows, "scene", "level").items()):
        ranked = sorted(group, key=lambda r: (-r["IS"], r["key"]))
        if len(ranked) < 3:
            continue
        gaps = [ranked[i]["IS"] - ranked[i + 1]["IS"] for i in range(len(ranked) - 1)]
        cut = int(np.argmax(gaps))
        if gaps[cut] < GAP:
            continue
        top, rest = ranked[:cut + 1], ranked[cut + 1:]
        names = ", ".join(r["key"] for r in top)
        low, high = min(r["IS"] for r in top), max(r["IS"] for r in top)
        span = f"{high:.1f}" if low == high else f"{low:.1f}–{high:.1f}"
        lines.append(f"{scene} {level}: Intent {span} on {len(top)} of {len(ranked)} layouts "
                     f"({names}), at most {rest[0]['IS']:.1f} on the other {len(rest)}.")
    return lines


def findings(data: dict) -> list[str]:
    """The sentences that open the report."""
    avg, references = data["summary"]["avg"], data["summary"].get("references", {})
    chance = (f" (chance {references['chance_IS']:.1f})" if "chance_IS" in references else "")
    lines = [(f"Average over the {len(data['table'])} scene × level cells: IS {avg['IS']:.1f}"
              f"{chance}, ES {avg['ES']:.1f}, CR {avg['CR']:.1f}; "
              f"{data['summary']['episodes']} episodes.")]
    by_level = data["level_averages"]
    if len(by_level) > 1:
        lines.append("Intent by level, averaged over scenes: " + ", ".join(
            f"{level} {values['IS']:.1f}" for level, values in by_level.items()) + ".")
    below = [c for c in data["table"] if c["below_chance"]]
    if below:
        lines.append("Intent below chance (its interval over tasks under the chance Intent): "
                     + "; ".join(f"{c['scene']} {c['level']} {c['IS']:.1f} "
                                 f"[{c['interval'][0]:.1f}–{c['interval'][1]:.1f}] against "
                                 f"{c['chance_IS']:.1f}" for c in below) + ".")
    lines += concentration(data["layouts"])
    for control in data["controls"]:
        lines += [f"Language effect (instructed − {control['mode']}): {line}"
                  for line in control["verdicts"]]
    return lines


def _table(cells: dict, levels: list[str]) -> list[dict]:
    """Table 1's cells in order, each with its interval over tasks and its below-chance flag."""
    return [{"scene": scene, "level": level, **row[level],
             "interval": shown_interval(row[level], "IS"),
             "below_chance": below_chance(row[level]), "shade": shade(row[level]["IS"])}
            for scene, row in cells.items() for level in levels if level in row]


def _grid(table: list[dict]) -> dict:
    """Table 1's cells by scene and level."""
    grid: dict = defaultdict(dict)
    for cell in table:
        grid[cell["scene"]][cell["level"]] = cell
    return dict(grid)


def clipping(results: list[dict]) -> str | None:
    """A sentence on the actions whose joint targets lay past a limit, if any did."""
    actions = sum(r.get("clipped") or 0 for r in results)
    if not actions:
        return None
    steps = sum(r.get("steps") or 0 for r in results)
    episodes = sum(1 for r in results if r.get("clipped"))
    share = f" ({100 * actions / steps:.1f}% of the {steps} actions executed)" if steps else ""
    return (f"{actions} actions{share} in {episodes} of {len(results)} episodes "
            f"({100 * episodes / len(results):.0f}%) asked for a joint past its limit; each "
            "was clipped to the limit and executed. A large share means the policy's targets "
            "often lie outside the robot's joint range: its action scale or normalisation may "
            "not be the robot's, or it drives the arms against their stops.")


def _did(results: list[dict], shown: tuple[str, ...]) -> dict:
    """Per scene and level: % completed and % of each kind of what the policy did."""
    did: dict = {}
    for (scene, level), records in sorted(_group(results, "scene", "level").items()):
        counts = Counter(kind(r) for r in records)
        did.setdefault(scene, {})[level] = {
            "completed": 100 * sum(r["complete"] for r in records) / len(records),
            **{k: 100 * counts[k] / len(records) for k in shown}}
    return did


def _matrix(records: list[dict]) -> dict:
    """Instructed task x closest behaviour, in episodes (as instructed first, the kinds of
    unrecognised last), with each count's shade (its share of the row)."""
    counts: dict[str, Counter] = defaultdict(Counter)
    for record in records:
        counts[record["task"]][closest(record)] += 1
    order = {DID[0]: 0, DID[2]: 1, **{k: 3 + i for i, k in enumerate(UNRECOGNISED)}}
    columns = sorted({c for row in counts.values() for c in row},
                     key=lambda c: (order.get(c, 2), c))
    return {"rows": sorted(counts), "columns": columns, "counts": dict(counts),
            "totals": {task: sum(row.values()) for task, row in counts.items()}}


def _failures(results: list[dict]) -> list[dict]:
    failures: Counter = Counter()
    reasons: dict[str, Counter] = defaultdict(Counter)
    for record in results:
        failed = first_failure(record)
        if failed is not None:
            failures[failed[0]] += 1
            reasons[failed[0]][failed[1]] += 1
    return [{"stage": stage, "episodes": count, "reasons": reasons[stage].most_common(3)}
            for stage, count in failures.most_common()]


def _videos(results: list[dict], names: dict[str, str]) -> dict:
    """Per (scene, level): up to VIDEOS_PER_CELL failure videos, the first in episode order,
    each with its caption's parts."""
    found: dict = defaultdict(list)
    for record in sorted(results, key=lambda r: r["episode"]):
        video = record.get("video")
        cell = found[record["scene"], record["level"]]
        if (isinstance(video, str) and VIDEO_LINK.fullmatch(video) and not record["complete"]
                and len(cell) < VIDEOS_PER_CELL):
            failed = first_failure(record)
            cell.append({"episode": record["episode"], "path": video,
                         "task": names[record["task"]], "did": closest(record),
                         "failed": f"{failed[0]}: {failed[1]}" if failed else "none"})
    return {key: value for key, value in found.items() if value}


def _instructions(results: list[dict], options: EvalOptions) -> dict[str, str]:
    """Each task's own instruction: recorded as task_instruction, or as the instruction
    given where that is the task's own (runs before task_instruction was recorded, given
    other instructions, have none: their tasks are named by id)."""
    return {r["task"]: text for r in results
            if (text := r.get("task_instruction") or (
                r.get("instruction") if options.instruction_mode == "normal" else None))}


def report_data(name: str, options: EvalOptions, results: list[dict],
                controls: list[dict] | None = None, provenance: list[dict] | None = None
                ) -> dict:
    """Everything the templates show, computed once (`controls`: the run against its
    control arms, compare.control_comparisons; `provenance`: the environments that ran it).
    The same in any record order."""
    results = sorted(results, key=lambda r: r["episode"])
    totals = summary(results, options)
    cells = totals["cells"]
    levels = [level for level in LEVELS if any(level in row for row in cells.values())]
    instructions = _instructions(results, options)
    names = task_names(results, instructions)
    by_motion = [{"scene": scene, "level": level, "all": row[level], **row[level]["by_motion"]}
                 for scene, row in cells.items() for level in levels
                 if level in MOTION_LEVELS and "by_motion" in row.get(level, {})]
    table = _table(cells, levels)
    shown = kinds(results)
    data = {
        "name": name, "options": options, "summary": totals, "levels": levels,
        "ground_truth": ground_truth(totals),
        "table": table, "grid": _grid(table),
        "with_chance": all("chance_IS" in cell for cell in table),
        "level_averages": level_averages(cells, levels),
        "shades": [(value, shade(value)) for value in SHADES],
        "drops": level_drops(results), "controls": controls or [],
        "metrics": METRICS, "cells": cells, "by_motion": by_motion, "motions": MOTIONS,
        "motion_unknown": sum(row["unknown"] for row in by_motion),
        "layouts": breakdown(results, LAYOUT_LEVELS, "layout"),
        "training": breakdown(results, DERIVED_LEVELS, lambda r: origin(r["task"])),
        "tasks": [{"task": task, **scores(records)}
                  for task, records in sorted(_group(results, "task").items())],
        "names": names, "instructions": instructions,
        "did": _did(results, shown), "did_kinds": shown,
        "unrecognised": [k for k in UNRECOGNISED if k in shown],
        "confusions": Counter((r["task"], closest(r)) for r in results
                              if kind(r) == DID[1]).most_common(TOP),
        "matrices": {scene: _matrix(records)
                     for scene, records in sorted(_group(results, "scene").items())},
        "first_failures": _failures(results),
        "errors": Counter(r["error"].split(": ", 1)[-1] for r in results if r.get("error")
                          ).most_common(TOP),
        "clipping": clipping(results),
        "videos": _videos(results, names),
        "benchmark": benchmark_described(options),
        "made_with": [described(entry) for entry in provenance or ()]}
    data["findings"] = findings(data)
    return data

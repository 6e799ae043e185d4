"""Reports of an evaluation run (`RUN/report.md`, `RUN/report.html`) and comparisons of two:
the paper's Table 1 (with an Intent heatmap in HTML), its L1 and L3 cells for the moved and
the as-trained tasks beside the whole, Intent minus Execution per cell, a
per-task table, completion beside what the policy did (per cell, the most frequent confusions
and the instructed x executed matrix per scene), the stages that failed first with their most
common reasons, and links to failure videos.

Tasks are named by their level and instruction, shortened ("L2 · Use your left arm to pick up
the cube that…"); the full instruction and the task id are in the markdown's task table and in
the HTML's tooltips. The instructed x executed matrices are in the HTML only (their behaviour
headers turned upright, in a scrolling box), where a task's row fits on a screen."""

from __future__ import annotations

import json
import re
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from robofollow.compiler.spec import LEVELS, MOTION_LEVELS
from robofollow.errors import RoboFollowError
from robofollow.eval.compare import CompareError, compare_runs, control_comparisons, markdown
from robofollow.eval.drops import level_drops
from robofollow.eval.pages import PAGES
from robofollow.eval.run_folder import RESULTS, RUN_FILE, read_results
from robofollow.eval.runner import EvalOptions, summary, with_motion
from robofollow.oracle.metrics import METRICS, MOTIONS, table

VIDEO_LINK = re.compile(r"videos/[A-Za-z0-9_.#-]+\.mp4")  # what the runner writes
DID = ("as instructed", "another training task", "other branch", "unrecognised")
TOP = 15  # confusions and failure reasons listed
NAME_CHARS = 50  # a task's instruction is shortened to its first words within this many


class ReportError(RoboFollowError):
    """A folder that holds no evaluation run."""


def load_run(run: Path) -> tuple[EvalOptions, list[dict]]:
    if not (run / RUN_FILE).is_file():
        raise ReportError(f"{run} holds no evaluation run (no {RUN_FILE})")
    data = json.loads((run / RUN_FILE).read_text(encoding="utf-8"))
    options = EvalOptions(**dict(data, scenes=tuple(data["scenes"]),
                                 levels=tuple(data["levels"]), tasks=tuple(data["tasks"])))
    return options, read_results(run / RESULTS)


def _clip(text: str, limit: int = NAME_CHARS) -> str:
    """The text's first words within `limit` characters, with an ellipsis where it was cut."""
    if len(text) <= limit:
        return text
    cut = text[:limit + 1]
    return (cut.rsplit(" ", 1)[0] if " " in cut else cut[:limit]) + "…"


def task_names(results: list[dict], instructions: dict[str, str]) -> dict[str, str]:
    """Each task's name in the tables: its level and its instruction (`instructions`, by task),
    shortened ("L2 · Use your left arm to pick up the cube that…"), else its id. Where shortened
    instructions coincide, each goes on to the first word that tells it apart ("L0 · Use your
    right arm to pick up the smaller blue … the green…"); the names that still coincide are
    told apart by their layout where those differ ("… @scene2_3"), else numbered ("… (2)")."""
    tasks = {r["task"]: r for r in results}
    names = {task: f"{r['level']} · " + (_clip(instructions[task]) if task in instructions
                                          else task.split("/", 2)[-1])
             for task, r in tasks.items()}
    for group in _clashes(names):
        words = {task: instructions[task].split() for task in group if task in instructions}
        for task, own in words.items():
            others = [other for other in words.values() if other != own]
            if others:
                names[task] = _told_apart(names[task], own, others)
    for group in _clashes(names):
        layouts = [tasks[task].get("layout") for task in group]
        by_layout = len(set(layouts)) == len(group)
        for number, (task, layout) in enumerate(zip(group, layouts, strict=True), 1):
            names[task] += f" @{layout}" if by_layout else f" ({number})"
    return names


def _clashes(names: dict[str, str]) -> list[list[str]]:
    """The groups of keys (in order) that share a name."""
    groups: dict[str, list[str]] = defaultdict(list)
    for key in sorted(names):
        groups[names[key]].append(key)
    return [group for group in groups.values() if len(group) > 1]


def _told_apart(name: str, words: list[str], others: list[list[str]]) -> str:
    """A shortened name (ending "…") followed by its text's words up to the first that none of
    the `others` (texts with the same name) has at its place: that word and the one before,
    the words shown first and those between elided."""
    end = min(len(words), 1 + max(_shared(words, other) for other in others))
    shown = len(name.split()) - 2  # the level and the dot are two words
    start = max(shown, end - 2)
    return (name.removesuffix("…") + (" … " if start > shown else " ")
            + " ".join(words[start:end]) + ("…" if end < len(words) else ""))


def _shared(words: list[str], other: list[str]) -> int:
    """How many leading words two texts share."""
    return next((i for i, (a, b) in enumerate(zip(words, other, strict=False)) if a != b),
                min(len(words), len(other)))


def _outcome(record: dict) -> str:
    """The behaviour closest to what the arms did: as instructed, the other branch, a
    training task's label, or unrecognised."""
    match = (record["executed_behaviour"] or {}).get("match") or None
    return {"instructed": DID[0], "other branch": DID[2], None: DID[3]}.get(match, match)


def _did(record: dict) -> str:
    outcome = _outcome(record)
    return outcome if outcome in DID else DID[1]


def _matrix(records: list[dict]) -> dict:
    """Instructed task x closest behaviour, in episodes (as instructed first, unrecognised
    last)."""
    counts: dict[str, Counter] = defaultdict(Counter)
    for record in records:
        counts[record["task"]][_outcome(record)] += 1
    special = {DID[0]: 0, DID[2]: 1, DID[3]: 3}
    columns = sorted({c for row in counts.values() for c in row},
                     key=lambda c: (special.get(c, 2), c))
    return {"rows": sorted(counts), "columns": columns, "counts": dict(counts)}


def report_data(name: str, options: EvalOptions, results: list[dict],
                controls: list[dict] | None = None) -> dict:
    """Everything the templates show, computed once (`controls`: the run against its
    control arms, compare.control_comparisons)."""
    totals = summary(results, options)
    cells = totals["cells"]
    levels = [level for level in LEVELS if any(level in row for row in cells.values())]
    # the records hold the instruction given and, where it is not the task's own, that one
    # (runs before task_instruction was recorded: their tasks are named by id)
    instructions = {r["task"]: text for r in results
                    if (text := r.get("task_instruction") or (
                        r.get("instruction") if options.instruction_mode == "normal" else None))}
    by_motion = [{"scene": scene, "level": level, "all": row[level], **row[level]["by_motion"]}
                 for scene, row in cells.items() for level in levels
                 if level in MOTION_LEVELS and "by_motion" in row.get(level, {})]
    names = task_names(results, instructions)
    full = {task: f"{instructions[task]} ({task})" if task in instructions else task
            for task in names}
    tasks = []
    for task, records in sorted(_group(results, "task").items()):
        done = [r["complete"] for r in records]
        tasks.append({"task": task, "episodes": len(records),
                      "IS": 100 * np.mean([r["intent_score"] for r in records]),
                      "ES": 100 * np.mean([r["execution_score"] for r in records]),
                      "CR": 100 * np.mean(done)})
    did = {}
    for (scene, level), records in sorted(_group(results, "scene", "level").items()):
        counts = Counter(_did(r) for r in records)
        did.setdefault(scene, {})[level] = {
            "completed": 100 * sum(r["complete"] for r in records) / len(records),
            **{k: 100 * counts[k] / len(records) for k in DID}}
    confusions = Counter((r["task"], _outcome(r)) for r in results if _did(r) == DID[1])
    matrices = {scene: _matrix(records)
                for scene, records in sorted(_group(results, "scene").items())}
    failures = Counter()
    reasons: dict[str, Counter] = defaultdict(Counter)
    for record in results:
        failed = next((s for s in record["stages"] if s["intent"] < s["weight"]
                       or s["execution"] < s["weight"]), None)
        if failed is not None:
            failures[failed["stage"]] += 1
            reasons[failed["stage"]][failed["reason"]] += 1
    return {
        "name": name, "options": options, "summary": totals, "levels": levels,
        "drops": level_drops(results), "controls": controls or [],
        "metrics": METRICS, "cells": cells, "by_motion": by_motion, "motions": MOTIONS,
        "motion_unknown": sum(row["unknown"] for row in by_motion), "tasks": tasks, "names": names, "full": full,
        "instructions": instructions, "did": did, "did_kinds": DID,
        "confusions": confusions.most_common(TOP), "matrices": matrices,
        "first_failures": [{"stage": stage, "episodes": count,
                            "reasons": reasons[stage].most_common(3)}
                           for stage, count in failures.most_common()],
        "errors": Counter(r["error"].split(": ", 1)[-1] for r in results if r["error"]
                          ).most_common(TOP),
        "clipped": {"actions": sum(r.get("clipped", 0) for r in results),
                    "episodes": sum(1 for r in results if r.get("clipped"))},
        "videos": [(r["episode"], r["video"]) for r in results
                   if isinstance(r.get("video"), str) and VIDEO_LINK.fullmatch(r["video"])][:50]}


def _group(results: list[dict], *keys: str) -> dict:
    grouped: dict = defaultdict(list)
    for record in results:
        grouped[record[keys[0]] if len(keys) == 1 else tuple(record[k] for k in keys)].append(
            record)
    return grouped


def write_report(run: Path, motions: dict[str, str | None] | None = None,
                 controls: list[dict] | None = None) -> tuple[Path, Path]:
    """(Re)build RUN/report.md and RUN/report.html from the run's results; `motions` (the
    compiled episodes' motion, by episode id) fills in the records written before they carried
    it (else their motion is unknown: "-"); `controls`: the run against its control arms
    where the caller has them (else compared here)."""
    options, results = load_run(run)
    data = report_data(run.name, options, with_motion(results, motions or {}),
                       control_comparisons(run) if controls is None else controls)
    paths = run / "report.md", run / "report.html"
    for path in paths:
        template = PAGES.get_template(f"report{path.suffix}.j2")
        path.write_text(template.render(**data), encoding="utf-8")
    return paths


def comparison(runs: list[Path], motions: list[dict[str, str | None]] | None = None) -> str:
    """Markdown: the runs' Table 1 cells side by side, with B - A differences; under each L1
    and L3 cell, its moved and its as-trained tasks (`motions`, per run, fills in the records
    written before they carried their task's motion); then the paired differences B - A with
    their intervals over tasks and p-values (compare.py), where the runs share episodes."""
    loaded = [load_run(run) for run in runs]
    motions = motions or [{} for _ in runs]
    tables = [table(with_motion(results, found))
              for (_, results), found in zip(loaded, motions, strict=True)]
    template = PAGES.get_template("compare.md.j2")
    side_by_side = template.render(runs=[run.name for run in runs],
                                   options=[o for o, _ in loaded], tables=tables,
                                   metrics=METRICS, levels=LEVELS, motions=MOTIONS)
    try:
        paired = markdown(compare_runs(runs[1], runs[0]))  # B - A, as the Δ columns
    except CompareError as error:
        return side_by_side + f"\nPaired differences: not available ({error}).\n"
    body = paired.split("\n", 1)[1].replace("\n## ", "\n### ")
    return side_by_side + "\n## Paired differences (B − A, intervals over tasks)\n" + body

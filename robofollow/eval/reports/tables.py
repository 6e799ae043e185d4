"""The paper's Table 1 as text, within 80 columns: IS / ES / CR per scene and level, and the
average. Under each scene, L1 and L3 again for the tasks whose expert motion moved from the
training task's and for those where it moves as trained ("-" where the records do not say),
with their episode counts. A cell of fewer than FEW episodes is marked: read it with its
interval over tasks, in the report."""

from __future__ import annotations

import textwrap

from robofollow.compiler.scene.spec import LEVELS, MOTION_LEVELS
from robofollow.eval.statistics.metrics import METRICS, MOTIONS

WIDTH, LABEL = 18, 8  # a level's column, the scenes' labels (a motion row's label runs on
#                       into the blank L0 column)
FEW = 20  # episodes: a cell with fewer is marked
MARK = "*"


def _cell(cell: dict | None) -> str:
    if cell is None:
        return "-"
    few = MARK if cell["episodes"] < FEW else " "
    return " ".join(_number(cell[m]) for m in METRICS) + few  # WIDTH, starting with a space


def _number(value: float) -> str:
    """A score in 5 characters, the first a space: 100 is written without its decimal."""
    return f"{value:5.1f}" if value < 99.95 else "  100"


def _wrapped(label: str, text: str) -> list[str]:
    return textwrap.wrap(text, 80, initial_indent=f"{label:<10}", subsequent_indent=" " * 10)


def table_text(summary: dict) -> str:
    cells = summary["cells"]
    levels = [level for level in LEVELS if any(level in c for c in cells.values())]
    head = f"{'':{LABEL}}" + "".join(f"{level:^{WIDTH}}" for level in levels)
    sub = f"{'':{LABEL}}" + "".join(f"{' '.join(f'{m:>5}' for m in METRICS):^{WIDTH}}"
                                    for _ in levels)
    lines = [head, sub]
    for scene, row in cells.items():
        lines.append(f"{scene:<{LABEL}}" + "".join(f"{_cell(row.get(level)):^{WIDTH}}"
                                                   for level in levels))
        lines += _motion_rows(row, levels)
    avg = summary["avg"]
    lines.append(f"{'Avg':<10}" + "  ".join(f"{m} {avg[m]:.1f}" for m in METRICS)
                 + f"   ({summary['episodes']} episodes)")
    references = summary.get("references", {})
    if "chance_IS" in references:
        lines += _wrapped("Chance", f"IS {references['chance_IS']:.1f}  CR "
                          f"{references['chance_CR']:.1f}   (a language-blind guess among the "
                          "training behaviours each layout allows)")
    if "followed_IS" in references and references["followed_IS"] < 100:
        lines += _wrapped("Followed", f"IS {references['followed_IS']:.1f}   (perfectly "
                          "following the instructions given)")
    seen = ground_truth(summary)
    if seen:
        lines += _wrapped("Objects", GROUND_TRUTH[seen])
    if any(c["episodes"] < FEW for row in cells.values() for c in row.values()):
        lines += _wrapped(MARK, f"fewer than {FEW} episodes: read the cell with its 95% "
                          "interval over tasks, in the report")
    return "\n".join(line.rstrip() for line in lines)


GROUND_TRUTH = {  # the table's line for each answer of ground_truth
    "removed": "perception removed: the policy read the objects observation (ground truth), "
               "not camera images",
    "added": "ground truth added: the policy read the objects observation (ground truth) "
             "beside camera images"}


def ground_truth(summary: dict) -> str | None:
    """Whether the run's policy read the objects observation: instead of camera images
    ("removed": perception removed), beside them ("added"), or not at all (None)."""
    observed = summary.get("observed", ())
    if "objects" not in observed:
        return None
    return "added" if "images" in observed else "removed"


def _motion_rows(row: dict, levels: list[str]) -> list[str]:
    """A scene's L1 and L3 cells again for its moved and its as-trained tasks (blank under the
    other levels), then their episode counts."""
    shown = [level for level in levels if level in MOTION_LEVELS and level in row]
    if not shown:
        return []
    lines = []
    for kind in MOTIONS:
        values = []
        for level in levels:
            split = row[level].get("by_motion", {}) if level in shown else None
            values.append("" if level not in shown else _cell(split.get(kind) if split else None))
        line = f"{'':{LABEL}}" + "".join(f"{v:^{WIDTH}}" for v in values)
        label = f"  {kind} "
        lines.append(label + line[len(label):] if not line[:len(label)].strip()
                     else f"  {kind}:" + line[LABEL:])  # (no blank L0 column to run into)
    counts = {level: [(row[level].get("by_motion", {}).get(kind) or {}).get("episodes", 0)
                      for kind in MOTIONS] for level in shown}
    unknown = {level: row[level].get("by_motion", {}).get("unknown", row[level]["episodes"])
               for level in shown}
    said = f"episodes ({', '.join(MOTIONS)}): " + "; ".join(
        f"{level} {', '.join(map(str, found))}" for level, found in counts.items())
    if any(unknown.values()):
        said += "; motion unknown: " + ", ".join(f"{level} {count}" for level, count in
                                                unknown.items()) + (
            " (records written before they carried it, or listed tests)")
    return lines + textwrap.wrap(said, 80, initial_indent="  ", subsequent_indent="    ")

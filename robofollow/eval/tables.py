"""The paper's Table 1 as text: IS / ES / CR per scene and level, and the average. Under each
scene, L1 and L3 again for the tasks whose expert motion moved from the training task's and
for those where it moves as trained ("-" where the records do not say), with their episode
counts."""

from __future__ import annotations

from robofollow.compiler.spec import LEVELS, MOTION_LEVELS
from robofollow.oracle.metrics import METRICS, MOTIONS

WIDTH, LABEL = 20, 12  # a level's column, the scenes' (and their motion rows') labels


def table_text(summary: dict) -> str:
    cells = summary["cells"]
    levels = [level for level in LEVELS if any(level in c for c in cells.values())]
    width = WIDTH
    head = f"{'':{LABEL}}" + "".join(f"{level:^{width}}" for level in levels)
    sub = f"{'':{LABEL}}" + "".join(f"{'  '.join(f'{m:>5}' for m in METRICS):^{width}}"
                               for _ in levels)
    lines = [head, sub]
    for scene, row in cells.items():
        values = []
        for level in levels:
            cell = row.get(level)
            values.append("  ".join(f"{cell[m]:5.1f}" for m in METRICS) if cell else "-")
        lines.append(f"{scene:<{LABEL}}" + "".join(f"{v:^{width}}" for v in values))
        lines += _motion_rows(row, levels)
    avg = summary["avg"]
    lines.append(f"{'Avg':<10}" + "  ".join(f"{m} {avg[m]:.1f}" for m in METRICS)
                 + f"   ({summary['episodes']} episodes)")
    references = summary.get("references", {})
    if "chance_IS" in references:
        lines.append(f"{'Chance':<10}IS {references['chance_IS']:.1f}  CR "
                     f"{references['chance_CR']:.1f}   (a language-blind guess among the "
                     "training behaviours each layout allows)")
    if "followed_IS" in references and references["followed_IS"] < 100:
        lines.append(f"{'Followed':<10}IS {references['followed_IS']:.1f}   (perfectly following "
                     "the instructions given)")
    return "\n".join(lines)


def _motion_rows(row: dict, levels: list[str]) -> list[str]:
    """A scene's L1 and L3 cells again for its moved and its as-trained tasks (blank under the
    other levels), each row ending with its episode counts."""
    shown = [level for level in levels if level in MOTION_LEVELS and level in row]
    if not shown:
        return []
    lines = []
    for kind in MOTIONS:
        values, counts = [], []
        for level in levels:
            split = row[level].get("by_motion", {}) if level in shown else None
            cell = split.get(kind) if split else None
            values.append("" if level not in shown else "-" if cell is None else
                          "  ".join(f"{cell[m]:5.1f}" for m in METRICS))
            if level in shown:
                counts.append(f"{level} {cell['episodes'] if cell else 0}")
        lines.append(f"  {kind:<{LABEL - 2}}" + "".join(f"{v:^{WIDTH}}" for v in values)
                     + f"  ({', '.join(counts)} episodes)")
    unknown = {level: row[level].get("by_motion", {}).get("unknown", row[level]["episodes"])
               for level in shown}
    if any(unknown.values()):
        listed = ", ".join(f"{level} {count}" for level, count in unknown.items())
        lines.append(f"{'':<{LABEL}}motion unknown: {listed} episodes (records written "
                     "before they carried it, or listed tests)")
    return lines

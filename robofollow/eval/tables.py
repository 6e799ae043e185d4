"""The paper's Table 1 as text: IS / ES / CR per scene and level, and the average."""

from __future__ import annotations

from robofollow.compiler.spec import LEVELS
from robofollow.oracle.metrics import METRICS


def table_text(summary: dict) -> str:
    cells = summary["cells"]
    levels = [level for level in LEVELS if any(level in c for c in cells.values())]
    width = 20
    head = f"{'':10}" + "".join(f"{level:^{width}}" for level in levels)
    sub = f"{'':10}" + "".join(f"{'  '.join(f'{m:>5}' for m in METRICS):^{width}}"
                               for _ in levels)
    lines = [head, sub]
    for scene, row in cells.items():
        values = []
        for level in levels:
            cell = row.get(level)
            values.append("  ".join(f"{cell[m]:5.1f}" for m in METRICS) if cell else "-")
        lines.append(f"{scene:<10}" + "".join(f"{v:^{width}}" for v in values))
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

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
    return "\n".join(lines)

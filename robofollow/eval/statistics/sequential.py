"""`eval --until-separated RUN_B`: add rounds one at a time and stop once the run is told
apart from RUN_B on the same episodes (docs/statistics.md).

The test is declared before the run: the paired difference in average Intent (the `avg` row
of `compare`; the one cell where the run has one), its sign-flip p-value over tasks, looked
at after each round. With at most K = --rounds looks, a look separates the runs when p <
alpha / K (Bonferroni over the looks): whatever the looks' dependence, the chance of ever
separating two policies that do not differ is at most alpha. The price is power: a fixed
design of K rounds tests at alpha itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

ALPHA = 0.05
SEQUENTIAL = "sequential.json"  # RUN/sequential.json: how a sequential run stopped


@dataclass(frozen=True)
class Look:
    round: int
    difference: float  # average Intent, run - other, points
    p: float
    threshold: float  # alpha / looks

    @property
    def separated(self) -> bool:
        return self.p < self.threshold


def look(rows: list[dict], round_index: int, looks: int, alpha: float = ALPHA) -> Look:
    """The declared test after a round, from the rows of the comparison of the run's episodes
    so far with the other run's (paired.paired_rows)."""
    row = next((r for r in rows if r["level"] == "avg"), rows[-1])
    return Look(round_index, row["IS"]["difference"], row["IS"]["p"], alpha / looks)


def record(look_taken: Look, other: Path, looks: int, alpha: float = ALPHA) -> dict:
    """What RUN/sequential.json says of the run."""
    return {"against": str(other), "test": "average Intent, paired sign-flip over tasks",
            "alpha": alpha, "looks": looks, "threshold": look_taken.threshold,
            "stopped_after_round": look_taken.round, "separated": look_taken.separated,
            "difference": look_taken.difference, "p": look_taken.p}

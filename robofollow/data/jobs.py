"""What a demonstration dataset holds: one job per (training task, episode index), its seeds
and its instruction(s), all fixed by the specs and the generation options."""

from __future__ import annotations

import difflib
import hashlib
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from robofollow.errors import RoboFollowError

if TYPE_CHECKING:  # the CLI reads this module's constants without loading the compiler
    from robofollow.benchmark.episode import Benchmark, EpisodeSetup
    from robofollow.compiler.scene.behaviour import Behaviour

# Demonstration seeds live far above the test episodes' seeds (split seed bases are small and
# rounds few), so no training demonstration shares a jittered start with a test episode.
DEMO_SEED_BASE = 1_000_000
MAX_ATTEMPTS = 10  # seeds tried per episode before the run stops with an error
DEMO_INSTRUCTIONS = ("sample", "all")  # one sampled paraphrase per demonstration, or all
FORMATS = ("lerobot-v2.1", "lerobot-v3.0", "hdf5")


class UnknownTaskError(RoboFollowError):
    """A --tasks entry that is not a training task label."""


@dataclass(frozen=True)
class DemoJob:
    label: str
    scene: str
    layout: str
    index: int  # episode index within the task, 0-based
    behaviour: Behaviour  # the task's behaviour
    instructions: tuple[str, ...]  # one dataset episode per instruction, in this order

    @property
    def key(self) -> str:
        """Stable name of the job's unit of work on disk."""
        return f"{self.label}/{self.index:04d}"

    def seed(self, attempt: int) -> int:
        return demo_seed(self.index, attempt)

    def episode(self, attempt: int) -> EpisodeSetup:
        """What the expert runner takes for one attempt."""
        from robofollow.benchmark.episode import EpisodeSetup

        return EpisodeSetup(id=f"{self.label}#demo{self.index}", scene=self.scene,
                            layout=self.layout, seed=self.seed(attempt), behaviour=self.behaviour)


def demo_seed(index: int, attempt: int) -> int:
    """The jitter seed of a demonstration attempt: fixed by episode index and attempt."""
    return DEMO_SEED_BASE + index * MAX_ATTEMPTS + attempt


def sampled_paraphrase(label: str, index: int, paraphrases: tuple[str, ...]) -> str:
    """One paraphrase per episode, drawn with a seed fixed by the task label and index."""
    entropy = int(hashlib.sha256(f"{label}#{index}".encode()).hexdigest()[:16], 16)
    return paraphrases[int(np.random.default_rng(entropy).integers(len(paraphrases)))]


def select_tasks(compiled: Benchmark, names: list[str] | None) -> list[str]:
    """Training task labels, in spec order; `names` keeps only those (labels or scene ids)."""
    labels = [task.label for task in compiled.spec.tasks]
    if not names:
        return labels
    wanted = set()
    for name in names:
        if name in compiled.spec.scenes:
            wanted |= {t.label for t in compiled.spec.tasks if t.scene == name}
        elif name in labels:
            wanted.add(name)
        else:
            close = difflib.get_close_matches(name, labels + list(compiled.spec.scenes), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise UnknownTaskError(f"--tasks: {name!r} is neither a training task label nor a "
                                   f"scene{hint}")
    return [label for label in labels if label in wanted]


def demo_jobs(compiled: Benchmark, per_task: int, labels: list[str],
              instructions: str = "sample") -> list[DemoJob]:
    """Every job, task by task in spec order, episode index ascending."""
    if instructions not in DEMO_INSTRUCTIONS:
        raise ValueError(f"instructions must be one of {DEMO_INSTRUCTIONS}, got {instructions!r}")
    tasks = {task.label: task for task in compiled.spec.tasks}
    jobs = []
    for label in labels:
        task = tasks[label]
        behaviour = compiled.candidates(task.scene)[label]
        for index in range(per_task):
            chosen = (task.paraphrases if instructions == "all"
                      else (sampled_paraphrase(label, index, task.paraphrases),))
            jobs.append(DemoJob(label, task.scene, task.layout, index, behaviour, chosen))
    return jobs

"""The options of a training run, with their defaults and ranges (apart from train.py, which
loads JAX and the video decoder, so that the command line's help quotes the defaults)."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from robofollow.errors import RoboFollowError
from robofollow.sim import CHUNK

# what the network reads: camera images, or the objects observation (perception removed); and
# of the instruction its words, its logical form (tokens.py) or nothing
KINDS = ("text", "blind", "form", "objects-text", "objects-form")
OBJECTS_PREFIX = "objects-"  # a kind that reads the objects observation, then its language


def reads_objects(kind: str) -> bool:
    """Whether a kind reads the objects observation instead of camera images."""
    return kind.startswith(OBJECTS_PREFIX)


class TrainingError(RoboFollowError):
    """Training cannot start or go on."""


@dataclass(frozen=True)
class TrainOptions:
    dataset: str
    kind: str = "text"
    steps: int = 10000
    batch: int = 64
    learning_rate: float = 1e-3
    seed: int = 0
    cameras: tuple[str, ...] = ("cam_high",)
    factor: int = 4  # 320 x 240 frames become 80 x 60
    shift: int = 4  # pixels of random-shift augmentation
    chunk: int = CHUNK  # actions predicted per query (what the harness runs of each)
    execute: int = 25
    val_fraction: float = 0.05
    checkpoint_every: int = 1000
    episodes_per_task: int | None = None  # the first N demonstrations of each task
    variants_per_task: int | None = None  # only the first N instruction wordings of each task

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def image_cameras(self) -> tuple[str, ...]:
        """The cameras the network reads: none for the objects kinds."""
        return () if reads_objects(self.kind) else self.cameras

    def check(self) -> None:
        """TrainingError naming the first option out of its range."""
        problems = [(self.kind in KINDS, f"--policy {self.kind!r}: expected one of "
                                         f"{', '.join(KINDS)}"),
                    (self.learning_rate > 0, "--learning-rate must be positive"),
                    (0 <= self.val_fraction <= 0.5, "--val-fraction must be within 0..0.5"),
                    (self.shift >= 0, "--shift must be 0 or more pixels"),
                    (self.execute <= self.chunk, f"--execute {self.execute} is more than the "
                                                 f"{self.chunk} actions of a chunk"),
                    (len(self.cameras) > 0, "--cameras names no camera")]
        for ok, message in problems:
            if not ok:
                raise TrainingError(message)

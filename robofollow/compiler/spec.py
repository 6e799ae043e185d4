"""The benchmark as data: scene families, layouts, training tasks and split rules.

Built by spec_loader.py from the .rf files in specs/; frozen and validated. Positions are in
the world frame (metres): +x to the robot's right, +y away from the robot, +z up.
"""

from __future__ import annotations

from typing import Literal

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Step
from robofollow.compiler.model import Model

BodyKind = Literal["cube", "slab", "cylinder", "sphere", "label", "bowl"]
Level = Literal["L0", "L1", "L2", "L3"]
LEVELS: tuple[Level, ...] = ("L0", "L1", "L2", "L3")


class Source(Model):
    """Where something is written: file, 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"


class Body(Model):
    """An object (movable) or a fixture (static: labels, bowls)."""

    id: str
    kind: BodyKind
    fixture: bool
    color: lf.Color
    rgb: tuple[float, float, float]
    half_extents: tuple[float, float, float]  # x, y, z; a sphere (r, r, r), a cylinder (r, r, h/2)
    mass: float | None = None
    friction: float | None = None

    @property
    def volume(self) -> float:
        """What 'larger' and 'smaller' compare (m^3)."""
        x, y, z = self.half_extents
        if self.kind == "sphere":
            return 4.0 / 3.0 * 3.141592653589793 * x ** 3
        if self.kind in ("cylinder", "bowl"):
            return 3.141592653589793 * x * x * 2 * z
        return 8 * x * y * z


class Jitter(Model):
    """Uniform offsets (m) added to a body's nominal x and y at episode start."""

    x: tuple[float, float] = (0.0, 0.0)
    y: tuple[float, float] = (0.0, 0.0)


class Placed(Model):
    """Where a body is in a layout: its nominal centre, and what it rests on or in."""

    x: float
    y: float
    z: float
    support: str | None = None
    relation: Literal["table", "on", "in"] = "table"


class Layout(Model):
    name: str
    base: str | None = None
    placed: dict[str, Placed]


class Expected(Model):
    """A behaviour as a task author writes it after `expect`."""

    branch: Literal["then", "otherwise"] | None = None
    steps: tuple[Step, ...]


class Task(Model):
    label: str
    scene: str
    layout: str
    paraphrases: tuple[str, ...]
    forms: tuple[lf.Instruction, ...]  # the parsed paraphrases, in order
    expect: Expected | None = None
    source: Source
    paraphrase_sources: tuple[Source, ...]


class ListedTest(Model):
    """A test task its author lists in a level: `test L2 name on layout { "..." expect ... }`."""

    name: str
    scene: str
    level: Level
    layout: str
    instruction: str
    expect: Expected | None = None
    source: Source

    @property
    def id(self) -> str:
        return f"{self.scene}/{self.level}/{self.name}"


class SplitRule(Model):
    level: Level
    layouts: tuple[str, ...] = ()
    wordings: tuple[str, ...] = ()
    max_tasks: int | None = None
    rounds: int = 10
    seed: int = 42


class Scene(Model):
    id: str
    title: str
    bodies: dict[str, Body]
    points: dict[str, tuple[float, float]]
    jitter: dict[str, Jitter]  # by body id; "*" is the default
    layouts: dict[str, Layout]
    tasks: tuple[Task, ...]
    splits: dict[str, SplitRule]
    tests: tuple[ListedTest, ...] = ()
    table_height: float = 0.74

    def jitter_of(self, body: str) -> Jitter:
        return self.jitter.get(body) or self.jitter.get("*") or Jitter()

    @property
    def training_layouts(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(task.layout for task in self.tasks))


class Spec(Model):
    scenes: dict[str, Scene]
    digest: str  # sha256 over the source files, in order

    @property
    def tasks(self) -> tuple[Task, ...]:
        return tuple(task for scene in self.scenes.values() for task in scene.tasks)

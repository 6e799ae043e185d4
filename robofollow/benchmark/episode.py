"""What an episode is: a compiled test task's round, fully determined by its world (the
layout's bodies, where they stand, their jitter), instruction, behaviour and seed, with a hash
over that. `EpisodeSetup` is the part a simulation and the scorer read (where the episode
starts and what it asks); an `Episode` is a compiled test episode, as the build writes it to
`episodes/*.jsonl`; a `Benchmark` is what running and scoring one read of the benchmark it
belongs to. This module stays light: an env
reads episodes without loading the compiler's passes."""

from __future__ import annotations

from typing import Literal, Protocol

from pydantic import ConfigDict, Field

from robofollow.compiler.language import lf
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.model import Model
from robofollow.compiler.scene.spec import Level, Spec


class EpisodeSetup(Model):
    """Where an episode starts and what it asks for: its id, the scene's layout, the jitter
    seed and the grounded behaviour."""

    model_config = ConfigDict(validate_by_name=True, validate_by_alias=True,
                              serialize_by_alias=True)

    id: str = Field(alias="episode")  # `<scene>/<level>/<task>#r<round>` for a test episode
    scene: str
    layout: str
    seed: int
    behaviour: Behaviour

    def meta(self) -> dict:
        """What a recording of it carries: the id, the scene, the layout and the seed."""
        return {"episode": self.id, "scene": self.scene, "layout": self.layout,
                "seed": self.seed}


class Episode(EpisodeSetup):
    """A compiled test episode: its task, level and round, the instruction a policy is given
    and its logical form, whether an L1/L3 task's motion moved from the trained one, a hash
    over what decides it (benchmark.episode_hash; what pairs two runs' episodes; release v1's
    records carry an earlier hash over their whole scene), and its scene's split digest (16
    hex digits; which version of the split it belongs to)."""

    task: str
    level: Level
    instruction: str
    lf: lf.Instruction
    round: int
    motion: Literal["moved", "as-trained"] | None = None
    hash: str
    split: str


class Benchmark(Protocol):
    """What running and scoring an episode read of a compiled benchmark: a
    `compiled.Compiled`, or the `compiled_cache.Episodes` read from the cache."""

    @property
    def spec(self) -> Spec: ...

    def candidates(self, scene: str) -> dict[str, Behaviour]:
        """The scene's training behaviours by label ('did instead' candidates)."""

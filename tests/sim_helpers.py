"""Shared set-up for the simulation tests: the compiled built-in benchmark, once per session."""

from __future__ import annotations

from functools import lru_cache

from robofollow.build import Compiled, all_episodes, compile_specs
from robofollow.resources import builtin_specs


@lru_cache(maxsize=1)
def benchmark() -> Compiled:
    return compile_specs(builtin_specs())


@lru_cache(maxsize=1)
def _episodes() -> dict[str, dict]:
    return {e["episode"]: e for e in all_episodes(benchmark())}


def episode(episode_id: str) -> dict:
    return _episodes()[episode_id]

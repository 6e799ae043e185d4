"""Shared set-up for the simulation tests: the compiled built-in benchmark, once per session."""

from __future__ import annotations

import socket
import subprocess
import sys
from contextlib import contextmanager
from functools import lru_cache

from robofollow import compiled_cache
from robofollow.benchmark.episode import Episode
from robofollow.benchmark.pipeline import Compiled, compile_specs
from robofollow.benchmark.rounds import all_episodes
from robofollow.resources import builtin_specs


@lru_cache(maxsize=1)
def benchmark() -> Compiled:
    return compile_specs(builtin_specs())


@lru_cache(maxsize=1)
def cached_benchmark() -> compiled_cache.Episodes:
    """The built-in benchmark as the cache holds it (what `eval` reads)."""
    return compiled_cache.of(benchmark())


@lru_cache(maxsize=1)
def _episodes() -> dict[str, Episode]:
    return {e.id: e for e in all_episodes(benchmark())}


def episode(episode_id: str) -> Episode:
    return _episodes()[episode_id]


@contextmanager
def serve_process(*options: str):
    """`robofollow serve --policy noop` on a free loopback port, with `options` added; yields
    (process, port), its stdout a text pipe; terminated on leaving."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    process = subprocess.Popen(
        [sys.executable, "-m", "robofollow.cli", "serve", "--policy", "noop", "--port",
         str(port), "--specs", str(builtin_specs()), *options],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        yield process, port
    finally:
        process.terminate()
        process.wait(10)

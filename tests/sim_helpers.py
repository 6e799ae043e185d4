"""Shared set-up for the simulation tests: the working compile of the built-in specs (what the
generator's tests read), and the release the shipped results and the judged catalogue's
episodes were made on (what tests of recorded episodes read), each once per session."""

from __future__ import annotations

import socket
import subprocess
import sys
from contextlib import contextmanager
from functools import lru_cache

from robofollow import compiled_cache, release
from robofollow.benchmark.compiled import Compiled
from robofollow.benchmark.episode import Episode
from robofollow.benchmark.pipeline import compile_specs
from robofollow.resources import builtin_specs


@lru_cache(maxsize=1)
def benchmark() -> Compiled:
    return compile_specs(builtin_specs())


@lru_cache(maxsize=1)
def cached_benchmark() -> compiled_cache.Episodes:
    """The built-in benchmark as the cache holds it (what `eval` reads)."""
    return compiled_cache.of(benchmark())


SHIPPED_RELEASE = "v1"  # the shipped results' and the judged catalogue's release


def shipped() -> compiled_cache.Episodes:
    """The release the shipped results and the judged catalogue's episodes were made on."""
    return release.load(SHIPPED_RELEASE)


def episode(episode_id: str) -> Episode:
    """A recorded episode by id, from the release it was recorded on."""
    return shipped().record(episode_id)


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

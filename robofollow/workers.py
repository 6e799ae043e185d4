"""Running items through a worker object (one per process: it keeps its simulation and
renderer), in this process or in a pool of spawned processes.

A worker is made by `make()` (picklable, e.g. a functools.partial of a class), called as
`worker(item)` and closed with `worker.close()`. Pool workers ignore Ctrl-C: the parent gets
it, and leaving the pool stops them.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections.abc import Callable, Iterator

_WORKER: dict = {}


def _start(make: Callable) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _WORKER["worker"] = make()


def _call(item):
    return _WORKER["worker"](item)


def results(make: Callable, items: list, workers: int) -> Iterator:
    """Each item's result, in the order they finish."""
    if workers <= 1 or len(items) <= 1:
        worker = make()
        try:
            for item in items:
                yield worker(item)
        finally:
            worker.close()
        return
    with multiprocessing.get_context("spawn").Pool(workers, _start, (make,)) as pool:
        yield from pool.imap_unordered(_call, items, chunksize=1)

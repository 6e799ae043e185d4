"""Running items through a worker object (one per process: it keeps its simulation and
renderer), in this process, in a pool of spawned processes, or in Ray actors.

A worker is made by `make()` (picklable, e.g. a functools.partial of a class), called as
`worker(item)` and closed with `worker.close()`. Pool workers ignore Ctrl-C: the parent gets
it, and leaving the pool stops them. With Ray, the actors run on the cluster `ray.init()`
finds (RAY_ADDRESS) or on a local one; leaving kills them.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator

from robofollow.errors import RoboFollowError

EXECUTORS = ("process", "ray")
_WORKER: dict = {}


def _start(make: Callable) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _WORKER["worker"] = make()


def _call(item):
    return _WORKER["worker"](item)


def results(make: Callable, items: list, workers: int, executor: str = "process") -> Iterator:
    """Each item's result, in the order they finish."""
    if executor == "ray":
        yield from _ray_results(make, items, workers)
        return
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


class _Actor:
    """A worker inside a Ray actor."""

    def __init__(self, make: Callable):
        self.worker = make()

    def run(self, item):
        return self.worker(item)


def _ray_results(make: Callable, items: list, workers: int) -> Iterator:
    try:
        import ray
    except ImportError:
        raise RoboFollowError("--executor ray needs Ray: pip install 'robofollow[ray]'") from None
    started = not ray.is_initialized()
    if started:
        # a local cluster's workers would run at Ray's default niceness 15: here they are the work
        os.environ.setdefault("RAY_worker_niceness", "0")
        ray.init(include_dashboard=False, log_to_driver=False, configure_logging=False)
    actor = ray.remote(num_cpus=1)(_Actor)
    actors = [actor.remote(make) for _ in range(max(1, min(workers, len(items))))]
    queue, pending = iter(items), {}

    def submit(worker) -> None:
        item = next(queue, None)
        if item is not None:
            pending[worker.run.remote(item)] = worker

    try:
        for worker in actors:
            submit(worker)
        while pending:
            [done], _ = ray.wait(list(pending), num_returns=1)
            worker = pending.pop(done)
            submit(worker)
            yield ray.get(done)
    finally:
        for worker in actors:
            ray.kill(worker)
        if started:
            ray.shutdown()

"""Running items through a worker object (one per process: it keeps its simulation and
renderer), in this process, in supervised worker processes, or in Ray actors.

A worker is made by `make()` (picklable, e.g. a functools.partial of a class), called as
`worker(item)` and closed with `worker.close()`.

Worker processes are supervised: each has its own pipe and runs one item at a time, so a
process that dies or exits (os._exit, a signal, SystemExit escaping the worker) is seen at
once and is charged to the item it was running. `lost(item, what)` then gives that item's
result (`what` says how the process ended, e.g. "exited with status 1") and a fresh process
replaces it; without `lost` the run stops with WorkerLost. Every first process must start
(`make()` succeed) before any item is given out; one that cannot start stops the run with
WorkerStartError, once. An exception raised by `worker(item)` stops the run and is raised
here. Worker processes ignore Ctrl-C: the parent gets it, and leaving stops them. With Ray,
the actors run on the cluster `ray.init()` finds (RAY_ADDRESS) or on a local one, a lost actor
is charged to its item the same way, and leaving kills them.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import traceback
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from multiprocessing.connection import wait

from robofollow.errors import RoboFollowError, error_text

EXECUTORS = ("process", "ray")
Lost = Callable[[object, str], object]  # (item, how its process ended) -> the item's result


class WorkerStartError(RoboFollowError):
    """A worker could not be made. `reported`: the message is the worker's own RoboFollowError
    (it already says what is wrong); otherwise it says how the process or `make()` failed."""

    def __init__(self, message: str, reported: bool = False):
        super().__init__(message)
        self.reported = reported

    def __reduce__(self):
        return type(self), (str(self), self.reported)


class WorkerLost(RoboFollowError):
    """A worker process died while running an item, and no `lost` handler was given."""


def results(make: Callable, items: list, workers: int, executor: str = "process",
            lost: Lost | None = None, isolate: bool = False) -> Iterator:
    """Each item's result, in the order they finish. One worker (and not `isolate`) runs in
    this process; otherwise `workers` supervised processes (or Ray actors) run the items."""
    if executor == "ray":
        yield from _ray_results(make, items, workers, lost)
        return
    if not isolate and (workers <= 1 or len(items) <= 1):
        worker = make()
        try:
            for item in items:
                yield worker(item)
        finally:
            worker.close()
        return
    if items:
        yield from _supervised(make, items, max(1, min(workers, len(items))), lost)


# -- supervised worker processes --------------------------------------------------------------

_STOP = None  # sent to a worker process: close and leave


def _serve(make: Callable, conn) -> None:
    """A worker process: make the worker, then run the items the pipe brings, one at a time."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        worker = make()
    except BaseException as error:  # noqa: B036 (reported to the parent, which stops the run)
        reported = isinstance(error, RoboFollowError)
        conn.send(("failed", (error.render() if reported else error_text(error), reported)))
        return
    conn.send(("ready", os.getpid()))
    try:
        while True:
            try:
                item = conn.recv()
            except (EOFError, OSError):  # the parent is gone
                return
            if item is _STOP:
                return
            try:
                result = worker(item)
            except Exception as error:  # a fault of the worker itself: the parent raises it
                conn.send(("raised", _portable(error)))
                return
            except BaseException as error:  # noqa: B036 (SystemExit & co. end this process)
                conn.send(("exited", f"raised {error!r}"))
                return
            conn.send(("done", result))
    finally:
        worker.close()


class _RemoteTraceback(Exception):
    def __str__(self) -> str:
        return self.args[0]


def _portable(error: Exception) -> tuple:
    """An exception and its traceback, in a form the parent can unpickle."""
    import pickle

    text = "".join(traceback.format_exception(error))
    try:
        pickle.loads(pickle.dumps(error))
    except Exception:
        error = RuntimeError(error_text(error))
    return error, text


def _ended(exitcode: int | None) -> str:
    """How a process ended, as words."""
    if exitcode is None:
        return "stopped answering"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"was killed by {name}"
    return f"exited with status {exitcode}"


@dataclass
class _Slot:
    process: multiprocessing.process.BaseProcess
    conn: object
    ready: bool = False
    item: object = None
    busy: bool = False


def _supervised(make: Callable, items: list, count: int, lost: Lost | None) -> Iterator:
    context = multiprocessing.get_context("spawn")
    queue = deque(items)
    slots: list[_Slot] = []

    def start() -> None:
        ours, theirs = context.Pipe()
        process = context.Process(target=_serve, args=(make, theirs), daemon=True,
                                  name="robofollow-worker")
        process.start()
        theirs.close()
        slots.append(_Slot(process, ours))

    def gone(slot: _Slot, what: str | None = None) -> str:
        """Remove a slot whose process ended; how it ended."""
        slot.process.join(5)
        if slot.process.is_alive():  # it closed its pipe but goes on: not ours any more
            slot.process.kill()
            slot.process.join(5)
        slots.remove(slot)
        slot.conn.close()
        return what or _ended(slot.process.exitcode)

    finished = False
    try:
        for _ in range(count):
            start()
        starting = True  # no item is given out before every first worker is ready
        while queue or any(s.busy for s in slots):
            if not starting:
                for slot in slots:
                    if slot.ready and not slot.busy and queue:
                        slot.item, slot.busy = queue.popleft(), True
                        try:
                            slot.conn.send(slot.item)
                        except OSError:  # it just died: seen below, and charged the item
                            pass
            if not slots:  # every process ended and no item is left running: start one
                start()
                continue
            ready = wait([s.conn for s in slots] + [s.process.sentinel for s in slots])
            for slot in [s for s in slots if s.conn in ready or s.process.sentinel in ready]:
                message = None
                try:
                    if slot.conn.poll():
                        message = slot.conn.recv()
                except (EOFError, OSError):
                    pass
                if message is None and slot.process.is_alive() and slot.conn not in ready:
                    continue  # (only the sentinel woke us, and it is alive: nothing yet)
                kind, value = message if message is not None else ("ended", None)
                if kind == "ready":
                    slot.ready = True
                    starting = starting and not all(s.ready for s in slots)
                elif kind == "done":
                    slot.item, slot.busy = None, False
                    yield value
                elif kind == "failed":
                    message_text, reported = value
                    raise WorkerStartError(message_text if reported else
                                           f"a worker could not start: {message_text}",
                                           reported)
                elif kind == "raised":
                    error, text = value
                    raise error from _RemoteTraceback(f"\n\"\"\"\n{text}\"\"\"")
                else:  # "exited" (SystemExit & co.) or the process ended
                    what = gone(slot, value)
                    if not slot.ready:
                        raise WorkerStartError(f"a worker process {what} while starting")
                    if slot.busy:
                        if lost is None:
                            raise WorkerLost(f"a worker process {what} while working on "
                                             f"{slot.item!r}")
                        result = lost(slot.item, what)
                        if queue:
                            start()
                        yield result
                    elif queue:
                        start()
        finished = True
    finally:
        for slot in slots:
            try:
                if finished:
                    slot.conn.send(_STOP)
            except OSError:
                pass
        for slot in slots:
            if finished:
                slot.process.join(10)
            if slot.process.is_alive():
                slot.process.terminate()
                slot.process.join(2)
            if slot.process.is_alive():
                slot.process.kill()
                slot.process.join(2)
            slot.conn.close()


# -- Ray actors -------------------------------------------------------------------------------

class _Actor:
    """A worker inside a Ray actor."""

    def __init__(self, make: Callable):
        self.worker, self.problem = None, None
        try:
            self.worker = make()
        except Exception as error:  # said by ready(), once, rather than at every call
            reported = isinstance(error, RoboFollowError)
            self.problem = (error.render() if reported else error_text(error), reported)

    def ready(self):
        return self.problem

    def run(self, item):
        return self.worker(item)


def _ray_results(make: Callable, items: list, workers: int, lost: Lost | None) -> Iterator:
    try:
        import ray
        from ray.exceptions import RayActorError
    except ImportError:
        raise RoboFollowError("--executor ray needs Ray: pip install 'robofollow[ray]'") from None
    started = not ray.is_initialized()
    if started:
        # a local cluster's workers would run at Ray's default niceness 15: here they are the work
        os.environ.setdefault("RAY_worker_niceness", "0")
        ray.init(include_dashboard=False, log_to_driver=False, configure_logging=False)
    actor = ray.remote(num_cpus=1)(_Actor)
    actors: list = []
    queue, pending = iter(items), {}

    def new_actors(number: int) -> list:
        made = [actor.remote(make) for _ in range(number)]
        actors.extend(made)
        for problem in ray.get([a.ready.remote() for a in made]):
            if problem is not None:
                text, reported = problem
                raise WorkerStartError(text if reported else
                                       f"a worker could not start: {text}", reported)
        return made

    def submit(worker) -> None:
        item = next(queue, None)
        if item is not None:
            pending[worker.run.remote(item)] = worker, item

    try:
        try:
            for worker in new_actors(max(1, min(workers, len(items)))) if items else []:
                submit(worker)
        except RayActorError:
            raise WorkerStartError("a Ray actor died while starting") from None
        while pending:
            [done], _ = ray.wait(list(pending), num_returns=1)
            worker, item = pending.pop(done)
            try:
                result = ray.get(done)
            except RayActorError:
                if lost is None:
                    raise WorkerLost(f"a Ray actor died while working on {item!r}") from None
                result = lost(item, "died (its Ray actor was lost)")
                ray.kill(worker)
                actors.remove(worker)
                worker = new_actors(1)[0]
            submit(worker)
            yield result
    finally:
        for worker in actors:
            ray.kill(worker)
        if started:
            ray.shutdown()

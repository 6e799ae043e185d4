"""A time limit on an in-process policy call (servers have their own, with retries).

The limit is a SIGALRM timer, so it interrupts the policy's Python code in the main thread of
the process that evaluates (where pool workers and Ray actors run episodes); a call blocked
inside a C extension is interrupted when it returns to Python.

`robofollow eval` gives in-process policies DEFAULT_POLICY_TIMEOUT unless told otherwise (as
servers have their own default of 60 s): a policy that stops answering costs its episode,
recorded as a policy failure, not the run."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from robofollow.errors import RoboFollowError

DEFAULT_POLICY_TIMEOUT = 60.0  # seconds per reset() or act() call of an in-process policy


class PolicyTimeout(RoboFollowError):
    """A policy call ran past its time limit."""


def check_deadline(seconds: float | None) -> None:
    """Raise (before any policy call) if a time limit cannot be kept here."""
    if seconds is not None and threading.current_thread() is not threading.main_thread():
        raise RoboFollowError("a policy time limit needs the episode on the main thread")


@contextmanager
def deadline(seconds: float | None) -> Iterator[None]:
    """Raise PolicyTimeout in the block once `seconds` have passed (None: no limit)."""
    if seconds is None:
        yield
        return
    check_deadline(seconds)

    def expire(signum, frame):
        raise PolicyTimeout(f"the policy did not answer within {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)

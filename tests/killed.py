"""A RoboFollow command killed at its Nth write into a folder, for the kill tests.

`killed(folder, n, argv)` runs `robofollow ARGV` in a forked copy of the test process and ends
it at once (os._exit, as SIGKILL would: no cleanup, no flush) at the Nth write under the
folder: just before a file is moved into place (os.replace, os.rename), or at a write to a
file opened there (os.write), which writes half its bytes first: a line cut short.
`writes(folder, argv)` runs the command to the end here and lists those writes."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from robofollow.cli import main

KILLED = 137  # the exit status a shell gives a process SIGKILL ended


def _under(folder: str, path) -> str | None:
    """The path, relative to the folder, when it is under it (a descriptor: its file's)."""
    try:
        target = os.path.realpath(f"/proc/self/fd/{path}" if isinstance(path, int) else path)
    except OSError:
        return None
    return os.path.relpath(target, folder) if target.startswith(folder + os.sep) else None


@contextmanager
def _counted(folder: Path, kill_at: int) -> Iterator[list[str]]:
    """The write calls wrapped for the block: each write under the folder is listed, and the
    `kill_at`th (from 1) ends the process."""
    root, seen = os.path.realpath(folder), []
    replace, rename, write = os.replace, os.rename, os.write

    def counted(kind: str, where: str | None) -> bool:
        if where is not None:
            seen.append(f"{kind} {where}")
        return where is not None and len(seen) == kill_at

    def killing_replace(source, target, *args, **kwargs):
        if counted("replace", _under(root, target)):
            os._exit(KILLED)
        return replace(source, target, *args, **kwargs)

    def killing_rename(source, target, *args, **kwargs):
        if counted("rename", _under(root, target)):
            os._exit(KILLED)
        return rename(source, target, *args, **kwargs)

    def killing_write(fd, data):
        if counted("write", _under(root, fd)):
            write(fd, bytes(data)[:len(data) // 2])
            os._exit(KILLED)
        return write(fd, data)

    os.replace, os.rename, os.write = killing_replace, killing_rename, killing_write
    try:
        yield seen
    finally:
        os.replace, os.rename, os.write = replace, rename, write


def writes(folder: Path, argv: list[str]) -> list[str]:
    """The writes the command makes under the folder, run to the end (it must succeed)."""
    with _counted(folder, 0) as seen:
        assert main(argv) == 0, argv
    return list(seen)


def killed(folder: Path, kill_at: int, argv: list[str]) -> int:
    """The exit status of the command killed at its `kill_at`th write under the folder (the
    command's own status where it makes fewer)."""
    pid = os.fork()
    if pid == 0:  # (the copy: it never returns into the tests)
        status = 1
        try:
            with _counted(folder, kill_at):
                status = main(argv)
        finally:
            os._exit(status)
    return os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1])

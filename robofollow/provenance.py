"""What made a result: RoboFollow's version and commit, Python, the libraries whose arithmetic
decides a trajectory bit for bit (NumPy, MuJoCo, JAX where a baseline ran) and the CPU.

A run records it in RUN/run.json ("provenance": one entry per environment that ran part of
it, normally one); reports show it, and `compare`, `merge` and `reproduce` name the fields in
which two results' environments differ (trajectory hashes are comparable only where they do
not)."""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from functools import cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

FIELDS = ("robofollow", "commit", "python", "numpy", "mujoco", "jax", "cpu", "platform")
NOTE = "note"  # an entry added after its run (never by one): how its values were found
# the fields on which a trajectory's bits depend (the rest say which code and machine)
ARITHMETIC = ("python", "numpy", "mujoco", "jax", "cpu", "platform")


def _installed(package: str) -> str | None:
    try:
        return version(package)
    except PackageNotFoundError:
        return None


def _commit() -> str | None:
    """The checkout's commit (with "+changes" when it has uncommitted ones), or None when the
    package is not in a git checkout."""
    root = Path(__file__).resolve().parents[1]
    if not (root / ".git").exists():
        return None
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=10, check=False)
        changes = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                  "--untracked-files=no"], capture_output=True, text=True,
                                 timeout=10, check=False,
                                 env={**os.environ, "GIT_OPTIONAL_LOCKS": "0"})  # (read only:
        # a status that refreshes the index takes .git/index.lock, left behind if it is killed)
    except (OSError, subprocess.SubprocessError):
        return None
    if head.returncode != 0:
        return None
    return head.stdout.strip() + ("+changes" if changes.stdout.strip() else "")


def _cpu() -> str:
    """The CPU model as the system names it (Linux: /proc/cpuinfo), else the machine type."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines():
            key, _, value = line.partition(":")
            if key.strip() in ("model name", "Model", "Hardware") and value.strip():
                return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


@cache
def environment(with_jax: bool = False) -> dict[str, str | None]:
    """This process's provenance entry; `with_jax`: a baseline runs, so JAX's version counts
    (None where JAX is not installed)."""
    return {"robofollow": _installed("robofollow"), "commit": _commit(),
            "python": platform.python_version(),
            "numpy": _installed("numpy"), "mujoco": _installed("mujoco"),
            "jax": _installed("jax") if with_jax else None, "cpu": _cpu(),
            "platform": f"{sys.platform}-{platform.machine()}"}


def differences(a: dict, b: dict, fields: tuple[str, ...] = FIELDS) -> list[str]:
    """'numpy 2.4.6 / 2.3.0' for each field in which two entries differ."""
    return [f"{field} {a.get(field) or '-'} / {b.get(field) or '-'}" for field in fields
            if a.get(field) != b.get(field)]


def described(entry: dict) -> str:
    """An entry in words: 'RoboFollow 0.1.0 (commit 7d77f1a1516a), Python 3.11.7, NumPy 2.4.6,
    MuJoCo 4.0.0; Intel(R) Xeon(R) Processor, linux-x86_64'."""
    commit = entry.get("commit")
    code = f"RoboFollow {entry.get('robofollow') or '?'}" + (
        f" (commit {commit[:12]}{'+changes' if commit.endswith('+changes') else ''})"
        if commit else "")
    libraries = [f"{name} {entry[field]}" for field, name in
                 (("python", "Python"), ("numpy", "NumPy"), ("mujoco", "MuJoCo"), ("jax", "JAX"))
                 if entry.get(field)]
    machine = ", ".join(entry[field] for field in ("cpu", "platform") if entry.get(field))
    note = f" ({entry[NOTE]})" if entry.get(NOTE) else ""
    return ", ".join([code, *libraries]) + (f"; {machine}" if machine else "") + note

"""lark parsers whose LALR tables are kept in the cache folder (resources.cache_root), since
building them takes most of a second per process and reading them back a hundredth of that.

A tables file is named by what it is built from (the grammar, lark's and Python's versions)
and written by lark itself (its `cache=` option, whose check covers the file's name, so the
file is never renamed); an exclusive lock on a file beside it keeps another process from
reading it half-written. lark builds the tables again when a file does not match. With caching
off (ROBOFOLLOW_NO_CACHE), a cache folder that cannot be written or no file locks, the tables
are built every time.
"""

from __future__ import annotations

import hashlib
import sys

import lark
from lark import Lark

from robofollow.resources import cache_root

try:
    import fcntl
except ImportError:  # (no file locks on this platform: no cached tables)
    fcntl = None


def cached_lark(name: str, grammar: str, **options) -> Lark:
    """`Lark(grammar, parser="lalr", **options)`, its tables read from the cache folder when
    they are there (`name` tells the files apart)."""
    options["parser"] = "lalr"
    root = cache_root()
    if root is None or fcntl is None:
        return Lark(grammar, **options)
    built_from = f"{grammar}\0{lark.__version__}\0{sys.version}"
    path = root / "parser" / f"{name}-{hashlib.sha256(built_from.encode()).hexdigest()}"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path.with_name(f"{path.name}.lock"), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            return Lark(grammar, cache=str(path), **options)
    except OSError:  # not writable: build them every time
        return Lark(grammar, **options)

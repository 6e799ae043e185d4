"""lark parsers whose LALR tables are kept in the cache folder (resources.cache_root), since
building them takes most of a second per process and reading them back a tenth of that.

A tables file is named by what it is built from (the grammar, lark's and Python's versions);
lark checks its hash when it reads it and builds the tables again when it does not match. A
new file is written under a temporary name and renamed into place, so readers never see half
of one. With caching off (ROBOFOLLOW_NO_CACHE) or a cache folder that cannot be written, the
tables are built every time.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import sys

import lark
from lark import Lark

from robofollow.resources import cache_root


def cached_lark(name: str, grammar: str, **options) -> Lark:
    """`Lark(grammar, parser="lalr", **options)`, its tables read from the cache folder when
    they are there (`name` tells the files apart)."""
    options["parser"] = "lalr"
    root = cache_root()
    if root is None:
        return Lark(grammar, **options)
    built_from = f"{grammar}\0{lark.__version__}\0{sys.version}"
    path = root / "parser" / f"{name}-{hashlib.sha256(built_from.encode()).hexdigest()}"
    if path.is_file():
        return Lark(grammar, cache=str(path), **options)
    partial = path.with_name(f".{path.name}.{os.getpid()}-{secrets.token_hex(4)}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError:  # not writable: build them every time
        return Lark(grammar, **options)
    parser = Lark(grammar, cache=str(partial), **options)
    try:
        os.replace(partial, path)
    except OSError:
        partial.unlink(missing_ok=True)
    return parser

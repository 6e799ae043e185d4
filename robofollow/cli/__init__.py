"""`robofollow` command line: thin wrappers around library functions, one module per command
or family of commands, each with its arguments (`add_<command>`) beside its handler
(`cmd_<command>`)."""

from __future__ import annotations

import argparse
import atexit
import gc
import os
import sys

from robofollow.cli.compile import add_audit, add_compile
from robofollow.cli.data import add_dataset, add_generate
from robofollow.cli.eval import add_compare, add_eval, add_merge, add_report
from robofollow.cli.layouts import add_propose_layouts
from robofollow.cli.parse import add_parse
from robofollow.cli.release import add_release
from robofollow.cli.reproduce import add_reproduce
from robofollow.cli.serve import add_serve
from robofollow.cli.sim import add_expert, add_render, add_score
from robofollow.cli.train import add_train
from robofollow.cli.vqa import add_vqa
from robofollow.errors import RoboFollowError, UsageError


class _Parser(argparse.ArgumentParser):
    """argparse's parser, whose errors are one line (exit status 2) pointing to --help."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


class _Version(argparse.Action):
    """--version, read from the installed package's metadata only when asked for."""

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import version

        parser.exit(message=f"robofollow {version('robofollow')}\n")


def parser() -> argparse.ArgumentParser:
    """The `robofollow` parser: every command, in the order its help lists them."""
    parser = _Parser(
        prog="robofollow",
        description="RoboFollow: measure whether robot policies really follow language "
                    "instructions.")
    parser.add_argument("--version", action=_Version, nargs=0,
                        help="show the program's version number and exit")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for add in (add_parse, add_compile, add_audit, add_propose_layouts, add_score, add_expert,
                add_render, add_eval, add_report, add_compare, add_merge, add_reproduce,
                add_release, add_serve, add_generate, add_vqa, add_train, add_dataset):
        add(commands)
    return parser


# The collector's first generation is examined after this many new objects (CPython: 700). A
# compile makes some millions of small, mostly acyclic ones, and each collection also walks the
# older generations often; at this threshold it costs 13% less (bench/compile_bench.py).
YOUNG_OBJECTS = 50_000


def main(argv: list[str] | None = None) -> int:
    gc.set_threshold(YOUNG_OBJECTS, 20, 20)
    args = parser().parse_args(argv)
    try:
        _check_text(args)
        return args.handler(args)
    except RoboFollowError as error:
        text = error.render()
        if type(error).render is RoboFollowError.render:  # a plain message: say what it is
            text = f"error: {text}"
        print(text, file=sys.stderr)
        return 2 if isinstance(error, UsageError) else 1
    except BrokenPipeError:  # output piped into e.g. `head`, which stopped reading
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115  (no flush error at exit)
        return 1


def run() -> None:
    """The `robofollow` command: `main`, then the exit handlers and a flush of the standard
    streams, and the process ends without freeing its objects one by one (after a compile,
    some millions: that took 0.5 s of CPU, bench/compile_bench.py)."""
    status = main()
    atexit._run_exitfuncs()  # (what interpreter exit runs first: pools, temporary folders)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except OSError:  # (output piped into a reader that stopped reading)
        status = status or 1
    os._exit(status)


def _check_text(args) -> None:
    """UsageError, before anything runs, for an argument that is not UTF-8 text (a folder
    name with a byte such as 0xff, which Python hands on as a lone surrogate): runs record
    and their pages show the names they are given, as UTF-8."""
    for name, value in vars(args).items():
        for text in value if isinstance(value, list | tuple) else [value]:
            if isinstance(text, str) and not text.isascii():
                try:
                    text.encode("utf-8")
                except UnicodeEncodeError as error:
                    raise UsageError(f"{_as_given(text)} (the {name} argument) is not UTF-8 "
                                     f"text ({_what(text[error.start])}); RoboFollow records "
                                     "and shows the names it is given as UTF-8: rename it"
                                     ) from None


def _as_given(text: str) -> str:
    """Text holding lone surrogates, shown with the bytes they stand for (\\xff)."""
    try:
        raw = text.encode("utf-8", "surrogateescape")
    except UnicodeEncodeError:  # (a surrogate no byte stands for: main() given it)
        raw = text.encode("utf-8", "backslashreplace")
    return raw.decode("utf-8", "backslashreplace")


def _what(surrogate: str) -> str:
    code = ord(surrogate)
    return f"byte 0x{code - 0xDC00:02x}" if 0xDC80 <= code <= 0xDCFF else f"U+{code:04X}"

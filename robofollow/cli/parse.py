"""`robofollow parse`: instructions to logical forms and back to English."""

from __future__ import annotations

import argparse
import io
import sys

from robofollow.compiler.language import lf
from robofollow.compiler.language.notation import notation
from robofollow.compiler.language.realize import STYLES, realize
from robofollow.errors import InstructionError
from robofollow.files import json_line

_PARSE_EXAMPLES = """\
examples:
  robofollow parse "Use your left arm to pick up the block to the right of the red ball."
  robofollow parse --json "Push the leftmost cube towards the larger red object."
  robofollow parse --style trailing "If the bowl is empty, pick up the red sphere."
  printf 'Pick up the red cube.\\nPick up the cube.\\n' | robofollow parse -

With '-', each line of standard input is one instruction and each output line is one JSON
object: {"text": ..., "lf": {...}} or {"text": ..., "error": {"type", "column", "message"}}.
The exit status is 1 when any instruction fails to parse.
"""


def add_parse(commands) -> None:
    p = commands.add_parser(
        "parse", help="parse instructions into canonical logical forms",
        description="Parse an instruction into its canonical logical form and say it back in "
                    "English.", epilog=_PARSE_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("text", metavar="TEXT", help="the instruction, or '-' to read one per line "
                                                "from standard input (JSON lines out)")
    p.add_argument("--json", action="store_true", help="print the logical form as JSON")
    p.add_argument("--style", choices=sorted(STYLES), default="plain",
                   help="paraphrase style of the English line (default: plain)")
    p.set_defaults(handler=cmd_parse)


def _parse_one(text: str, args) -> int:
    from robofollow.compiler.language.parser import (
        parse,  # (lark: only for this command)
    )

    try:
        instruction = parse(text)
    except InstructionError as error:
        print(error.render(), file=sys.stderr)
        return 1
    if args.json:
        print(lf.to_json(instruction, indent=2))
    else:
        print(f"lf       {notation(instruction)}")
        print(f"english  {realize(instruction, args.style)}")
    return 0


def _parse_stream(stream, out) -> int:
    """One output record per input line, blank lines included (an 'empty' error)."""
    from robofollow.compiler.language.parser import parse

    status = 0
    for line in stream:
        text = line.removesuffix("\n").removesuffix("\r")
        try:
            record = {"text": text, "lf": parse(text).model_dump(mode="json")}
        except InstructionError as error:
            record, status = {"text": text, "error": error.to_dict()}, 1
        out.write(json_line(record))
        out.flush()
    return status


def _stdin_lines():
    """Standard input as text split at '\\n' only (a stray '\\r' stays in its line); bytes
    that are not UTF-8 become U+FFFD (an unknown word)."""
    if hasattr(sys.stdin, "buffer"):
        return io.TextIOWrapper(sys.stdin.buffer, encoding="utf-8", errors="replace",
                                newline="\n")
    return sys.stdin


def cmd_parse(args) -> int:
    if args.text == "-":
        return _parse_stream(_stdin_lines(), sys.stdout)
    return _parse_one(args.text, args)

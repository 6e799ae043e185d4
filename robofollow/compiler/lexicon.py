"""The instruction vocabulary and the tokenizer that feeds the LALR parser.

Every known word maps to one grammar terminal and a canonical value: synonyms share both
("ball" and "sphere" -> NOUN "sphere"), so canonicalisation of words happens here, once.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from functools import cache

from lark import Token

from robofollow.errors import UnknownWordError

# terminal -> {word: canonical value}; a terminal listed with a tuple maps every word to itself.
_CLASSES: dict[str, dict[str, str] | tuple[str, ...]] = {
    "NOUN": {
        "object": "object", "item": "object", "thing": "object",
        "block": "block", "cube": "cube", "cylinder": "cylinder",
        "sphere": "sphere", "ball": "sphere", "slab": "slab", "bar": "slab",
        "bowl": "bowl", "table": "table",
    },
    "NOUNS": {
        "objects": "object", "items": "object", "things": "object",
        "blocks": "block", "cubes": "cube", "cylinders": "cylinder",
        "spheres": "sphere", "balls": "sphere", "slabs": "slab", "bars": "slab",
        "bowls": "bowl", "labels": "label",
    },
    "LABEL": {"label": "label"},
    "SQUARE": ("square",),
    "ONE": ("one",),
    "COLOR": {
        "red": "red", "green": "green", "blue": "blue", "yellow": "yellow", "orange": "orange",
        "purple": "purple", "pink": "pink", "white": "white", "black": "black",
        "gray": "gray", "grey": "gray", "brown": "brown",
    },
    "SIZE": {
        "larger": "larger", "bigger": "larger", "largest": "larger", "biggest": "larger",
        "large": "larger", "big": "larger",
        "smaller": "smaller", "smallest": "smaller", "small": "smaller", "little": "smaller",
    },
    "EXTREME": {
        "leftmost": "leftmost", "rightmost": "rightmost",
        "frontmost": "frontmost", "backmost": "backmost", "rearmost": "backmost",
    },
    "LEFT": ("left",),
    "RIGHT": ("right",),
    "FRONT": {"front": "front", "forward": "front", "forwards": "front"},
    "BACK": {"back": "back", "backward": "back", "backwards": "back", "rear": "back"},
    "TOP": ("top",),
    "POSITION": {"position": "position", "spot": "position"},
    "DIRECTION": ("direction",),
    "THE": ("the",),
    "A": {"a": "a", "an": "a"},
    "THAT": ("that",),
    "WHICH": ("which",),
    "NO": ("no",),
    "IT": ("it",),
    "ITS": ("its",),
    "YOUR": ("your",),
    "IS": {"is": "is", "are": "is"},
    "NOT": ("not",),
    "NON": ("non",),
    "EMPTY": ("empty",),
    "THERE": ("there",),
    "HAS": ("has",),
    "CONTAINS": ("contains",),
    "DOES": ("does",),
    "HAVE": ("have",),
    "CONTAIN": ("contain",),
    "ON": ("on",),
    "IN": ("in",),
    "INTO": ("into",),
    "ONTO": ("onto",),
    "INSIDE": ("inside",),
    "TO": ("to",),
    "AT": ("at",),
    "BEHIND": ("behind",),
    "BESIDE": ("beside",),
    "NEXT": ("next",),
    "TOUCHING": ("touching",),
    "FROM": ("from",),
    "OFF": ("off",),
    "OUT": ("out",),
    "OF": ("of",),
    "OVER": {"over": "over", "above": "over"},
    "VIA": ("via",),
    "AROUND": ("around",),
    "TOWARDS": {"towards": "towards", "toward": "towards"},
    "PICK": ("pick",),
    "GRASP": {"grasp": "grasp", "grab": "grasp", "lift": "grasp"},
    "TAKE": ("take",),
    "REMOVE": ("remove",),
    "PLACE": {"place": "place", "put": "place", "set": "place"},
    "MOVE": ("move",),
    "STACK": ("stack",),
    "PUSH": {"push": "push", "slide": "push", "shove": "push"},
    "UP": ("up",),
    "PICKING": {"picking": "pick"},
    "GRASPING": {"grasping": "grasp", "grabbing": "grasp", "lifting": "grasp"},
    "TAKING": {"taking": "take"},
    "REMOVING": {"removing": "remove"},
    "PLACING": {"placing": "place", "putting": "place", "setting": "place"},
    "MOVING": {"moving": "move"},
    "STACKING": {"stacking": "stack"},
    "PUSHING": {"pushing": "push", "sliding": "push", "shoving": "push"},
    "PASS": ("pass",),
    "PASSING": ("passing",),
    "GO": ("go",),
    "AVOID": ("avoid",),
    "AVOIDING": ("avoiding",),
    "DETOUR": ("detour",),
    "DO": ("do",),
    "INSTEAD": ("instead",),
    "WHILE": ("while",),
    "WITHOUT": ("without",),
    "USE": ("use",),
    "USING": ("using",),
    "WITH": ("with",),
    "ARM": {"arm": "arm", "hand": "arm", "gripper": "arm"},
    "LENGTH": ("short", "long"),
    "SIDE": {"side": "side", "face": "side", "edge": "side"},
    "FACING": {"facing": "facing", "pointing": "facing"},
    "IF": ("if",),
    "WHEN": ("when",),
    "UNLESS": ("unless",),
    "OTHERWISE": {"otherwise": "otherwise", "else": "otherwise"},
    "CHECK": ("check",),
    "WHETHER": ("whether",),
    "YES": {"yes": "yes", "so": "yes"},
    "AND": ("and",),
    "THEN": ("then",),
    "FIRST": ("first",),
    "START": {"start": "start", "begin": "start"},
    "BY": ("by",),
    "BEFORE": ("before",),
    "AFTER": ("after",),
    "AMONG": {"among": "among", "amongst": "among"},
}

# Words that stand for several tokens.
_EXPANSIONS: dict[str, tuple[str, ...]] = {
    "isn't": ("is", "not"),
    "aren't": ("is", "not"),
    "don't": ("do", "not"),
    "doesn't": ("does", "not"),
    "nonempty": ("non", "empty"),
}

_PUNCTUATION = {",": "COMMA", ";": "SEMICOLON", ".": "PERIOD"}
_FINAL_PUNCTUATION = frozenset(".!")

# "and" starts a further modifier (AND_MOD), not a further clause, before these terminals.
_MODIFIER_STARTS = frozenset({
    "NOT", "NON", "COLOR", "SIZE", "EXTREME", "LEFT", "RIGHT", "ON", "IN", "INTO", "ONTO",
    "INSIDE", "TO", "AT", "BEHIND", "BESIDE", "NEXT", "TOUCHING", "FROM", "OFF", "OUT", "OVER",
    "VIA", "AROUND", "TOWARDS", "THAT", "WHICH",
})
# A separator right before these is implied by them ("A; otherwise B", "A, if not, B").
_ABSORBING = frozenset({"OTHERWISE", "IF"})

_WORD_OR_MARK = re.compile(r"[A-Za-z]+(?:['’][A-Za-z]+)?(?:-[A-Za-z]+)*|[,;.!]|\S")


@dataclass(frozen=True, slots=True)
class Word:
    terminal: str
    value: str


def _build_vocabulary() -> dict[str, Word]:
    vocabulary: dict[str, Word] = {}
    for terminal, words in _CLASSES.items():
        pairs = words.items() if isinstance(words, dict) else ((w, w) for w in words)
        for word, value in pairs:
            if word in vocabulary:
                raise ValueError(f"word {word!r} is listed twice in the lexicon")
            vocabulary[word] = Word(terminal, value)
    return vocabulary


VOCABULARY: dict[str, Word] = _build_vocabulary()
TERMINALS: frozenset[str] = frozenset(_CLASSES) | {"AND_MOD", *_PUNCTUATION.values()}


@cache
def words_of(terminal: str) -> tuple[str, ...]:
    """The words that make a terminal, for error messages ("expected: 'up', a colour, ...")."""
    if terminal == "AND_MOD":
        return ("and",)
    for mark, name in _PUNCTUATION.items():
        if name == terminal:
            return (mark,)
    return tuple(w for w, entry in VOCABULARY.items() if entry.terminal == terminal)


def suggestions(word: str) -> list[str]:
    """Known words close to an unknown one."""
    return difflib.get_close_matches(word, [*VOCABULARY, *_EXPANSIONS], n=3, cutoff=0.75)


def _lower(word: str) -> str:
    lowered = word.lower().replace("’", "'")
    return lowered if len(lowered) == len(word) else word


def _split_word(word: str, column: int) -> list[tuple[str, int]]:
    """Hyphenated words: 'left-most' -> 'leftmost'; 'non-leftmost' -> 'non', 'leftmost'."""
    if "-" not in word:
        return [(word, column)]
    joined = word.replace("-", "")
    if joined in VOCABULARY or joined in _EXPANSIONS:
        return [(joined, column)]
    parts, offset = [], 0
    for part in word.split("-"):
        parts.append((part, column + offset))
        offset += len(part) + 1
    return parts


def tokenize(text: str) -> list[Token]:
    """Split an instruction into terminal tokens, each with its 1-based column in `text`."""
    raw: list[tuple[str, str, int, int]] = []  # terminal, value, column, length
    for match in _WORD_OR_MARK.finditer(text):
        piece, column = match.group(), match.start() + 1
        if piece in _PUNCTUATION or piece == "!":
            raw.append((_PUNCTUATION.get(piece, "PERIOD"), piece, column, 1))
            continue
        for word, word_column in _split_word(_lower(piece), column):
            for expanded in _EXPANSIONS.get(word, (word,)):
                entry = VOCABULARY.get(expanded)
                if entry is None:
                    raise UnknownWordError(
                        f"unknown word {piece[word_column - column:][:len(word)]!r}",
                        text=text, column=word_column, length=max(len(word), 1),
                        suggestions=tuple(suggestions(word)),
                    )
                raw.append((entry.terminal, entry.value, word_column, len(word)))
    while raw and raw[-1][0] == "PERIOD" and text[raw[-1][2] - 1] in _FINAL_PUNCTUATION:
        raw.pop()
    tokens: list[Token] = []
    for index, (terminal, value, column, length) in enumerate(raw):
        following = raw[index + 1][0] if index + 1 < len(raw) else None
        if terminal in _PUNCTUATION.values() and following in _ABSORBING and tokens:
            continue
        if terminal == "AND" and following in _MODIFIER_STARTS:
            terminal = "AND_MOD"
        tokens.append(Token(terminal, value, start_pos=column - 1, line=1, column=column,
                            end_column=column + length))
    return tokens

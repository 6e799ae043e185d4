"""The instruction vocabulary and the tokenizer that feeds the LALR parser.

Every known word maps to one grammar terminal and a canonical value: synonyms share both
("ball" and "sphere" -> NOUN "sphere"), so canonicalisation of words happens here, once.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache, lru_cache

from robofollow.compiler.language.coverage import near_misses, unsupported
from robofollow.errors import UnknownWordError, UnsupportedConstructError

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
        "bowls": "bowl", "labels": "label", "tables": "table",
    },
    "LABEL": {"label": "label"},
    "SQUARE": ("square",),
    "ONE": ("one",),
    "COLOR": {
        "red": "red", "green": "green", "blue": "blue", "yellow": "yellow", "orange": "orange",
        "purple": "purple", "pink": "pink", "white": "white", "black": "black",
        "gray": "gray", "grey": "gray", "brown": "brown",
    },
    "ORDINAL": {"second": "2", "third": "3", "fourth": "4", "fifth": "5"},
    "MIDDLE": {"middle": "middle", "center": "middle", "centre": "middle", "central": "middle"},
    "NEAREST": {"nearest": "nearest", "closest": "nearest"},
    "FARTHEST": {"farthest": "farthest", "furthest": "farthest"},
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
    "BESIDE": {"beside": "beside", "near": "beside"},
    "NEXT": ("next",),
    "TOUCHING": ("touching",),
    "FROM": ("from",),
    "OFF": ("off",),
    "OUT": ("out",),
    "OF": ("of",),
    "OVER": {"over": "over", "above": "over"},
    "BELOW": {"below": "below", "under": "below", "beneath": "below", "underneath": "below"},
    "BETWEEN": ("between",),
    "WAY": ("way",),
    "ALONG": ("along",),
    "VIA": ("via",),
    "AROUND": ("around",),
    "TOWARDS": {"towards": "towards", "toward": "towards"},
    "PICK": ("pick",),
    "GRASP": {"grasp": "grasp", "grab": "grasp", "lift": "grasp"},
    "TAKE": ("take",),
    "REMOVE": ("remove",),
    "PLACE": {"place": "place", "put": "place", "set": "place", "lay": "place",
              "deposit": "place"},
    "MOVE": ("move",),
    "STACK": ("stack",),
    "PUSH": {"push": "push", "slide": "push", "shove": "push"},
    "UP": ("up",),
    "DOWN": ("down",),
    "PICKING": {"picking": "pick"},
    "GRASPING": {"grasping": "grasp", "grabbing": "grasp", "lifting": "grasp"},
    "TAKING": {"taking": "take"},
    "REMOVING": {"removing": "remove"},
    "PLACING": {"placing": "place", "putting": "place", "setting": "place"},
    "MOVING": {"moving": "move"},
    "STACKING": {"stacking": "stack"},
    "PUSHING": {"pushing": "push", "sliding": "push", "shoving": "push"},
    "PASS": {"pass": "pass", "cross": "pass"},
    "PASSING": {"passing": "passing", "crossing": "passing"},
    "GO": ("go",),
    "GOING": ("going",),
    "AVOID": ("avoid",),
    "AVOIDING": ("avoiding",),
    "DETOUR": ("detour",),
    "DETOURING": ("detouring",),
    "DO": ("do",),
    "INSTEAD": ("instead",),
    "WHILE": ("while",),
    "WITHOUT": ("without",),
    "USE": ("use",),
    "USING": ("using",),
    "WITH": ("with",),
    "ARM": {"arm": "arm", "hand": "arm", "gripper": "arm"},
    "LENGTH": ("short", "long"),
    "SIDE": {"side": "side", "face": "side", "edge": "side", "end": "side"},
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
    # courtesy: no meaning of its own
    "PLEASE": {"please": "please", "kindly": "please"},
    "THANKS": ("thanks",),
    "THANK": ("thank",),
    "NOW": {"now": "now", "okay": "now", "ok": "now", "alright": "now"},
    "LETS": ("let's",),
    "AHEAD": ("ahead",),
    "MODAL": {"could": "could", "can": "could", "would": "could", "will": "could"},
    "YOU": ("you",),
    "I": ("i",),
    "WANT": {"want": "want", "need": "want", "like": "want"},
    "TASK": {"task": "task", "job": "task", "goal": "task"},
    "POSED": {"located": "posed", "sitting": "posed", "resting": "posed", "lying": "posed",
              "standing": "posed", "situated": "posed", "positioned": "posed"},
}

# Words that stand for several tokens.
_EXPANSIONS: dict[str, tuple[str, ...]] = {
    "isn't": ("is", "not"),
    "aren't": ("is", "not"),
    "don't": ("do", "not"),
    "doesn't": ("does", "not"),
    "nonempty": ("non", "empty"),
    "i'd": ("i", "could"),
    "that's": ("that", "is"),
    "outside": ("not", "in"),
    "something": ("a", "object"),
    "anything": ("a", "object"),
    "nothing": ("no", "object"),
    "lefthand": ("left",),  # 'on the left-hand side'
    "righthand": ("right",),
    "there's": ("there", "is"),

}

_PUNCTUATION = {",": "COMMA", ";": "SEMICOLON", ".": "PERIOD"}
_MARKS = {**_PUNCTUATION, "!": "PERIOD", "?": "PERIOD"}
_SEPARATORS = frozenset(_PUNCTUATION.values())

# "and" joins two noun phrases (AND_NP) before a determiner: "pick up A and the B",
# "between A and the B"; it starts a further modifier (AND_MOD), not a further clause, before
# these terminals.
_NOUN_PHRASE_STARTS = frozenset({"THE", "A"})
_ROUTE_GERUNDS = frozenset({"PASSING", "MOVING", "GOING"})
_MODIFIER_STARTS = frozenset({
    "NOT", "NON", "COLOR", "SIZE", "EXTREME", "LEFT", "RIGHT", "ON", "IN", "INTO", "ONTO",
    "INSIDE", "TO", "AT", "BEHIND", "BESIDE", "NEXT", "TOUCHING", "FROM", "OFF", "OUT", "OVER",
    "VIA", "AROUND", "TOWARDS", "THAT", "WHICH", "BELOW", "BETWEEN", "NEAREST", "FARTHEST",
})
# A separator right before these is implied by them ("A; otherwise B", "A, if not, B").
_ABSORBING = frozenset({"OTHERWISE", "IF"})
# The terminals a word gets from the tokens around it (`_terminals`): a phrase says every
# other (terminal, value) it holds wherever it stands.
CONTEXTUAL = frozenset({"AND", "AND_MOD", "AND_NP", "NOT", "NOT_GOING", "PLEASE", "PLEASE_END",
                        *_SEPARATORS})

_WORD_OR_MARK = re.compile(r"[A-Za-z]+(?:['’][A-Za-z]+)?(?:-[A-Za-z]+)*|[,;.!?]|\S")


@dataclass(frozen=True, slots=True)
class Word:
    terminal: str
    value: str


class WordToken:
    """One token for the LALR parser: its terminal, canonical value, and where it stands.

    Lighter than lark's Token; lark reads only `type` and, for its end-of-input token and
    errors, the position attributes below.
    """

    __slots__ = ("type", "value", "text", "column", "end_column")
    line = end_line = 1

    def __init__(self, type: str, value: str, text: str, column: int, end_column: int):
        self.type = type
        self.value = value
        self.text = text
        self.column = column
        self.end_column = end_column

    @property
    def start_pos(self) -> int:
        return self.column - 1

    @property
    def end_pos(self) -> int:
        return self.end_column - 1

    def __repr__(self) -> str:
        return f"WordToken({self.type}, {self.text!r}, column={self.column})"


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
TERMINALS: frozenset[str] = frozenset(_CLASSES) | {"AND_MOD", "AND_NP", "PLEASE_END", "NOT_GOING",
                                                  *_PUNCTUATION.values()}


@cache
def words_of(terminal: str) -> tuple[str, ...]:
    """The words that make a terminal, for error messages ("expected: 'up', a colour, ...")."""
    if terminal in ("AND_MOD", "AND_NP"):
        return ("and",)
    if terminal == "PLEASE_END":
        return ("please",)
    if terminal == "NOT_GOING":
        return ("not",)
    for mark, name in _PUNCTUATION.items():
        if name == terminal:
            return (mark,)
    return tuple(w for w, entry in VOCABULARY.items() if entry.terminal == terminal)


def suggestions(word: str) -> list[str]:
    """Known words a misspelt one most likely stands for (real near misses only)."""
    return near_misses(word, [*VOCABULARY, *_EXPANSIONS])


_Words = tuple[tuple[str, str, int, int], ...]  # (terminal, value, offset, length)


@lru_cache(maxsize=8192)
def _analyse(piece: str) -> tuple[_Words, tuple[str, int] | None]:
    """One piece (a word or a mark) -> its tokens, or the first unknown part as (word,
    offset)."""
    mark = _MARKS.get(piece)
    if mark is not None:
        return ((mark, piece, 0, 1),), None
    lowered = piece.lower().replace("’", "'")
    if len(lowered) != len(piece):  # case folding changed the length: no vocabulary word
        lowered = piece
    if "-" in lowered and lowered.replace("-", "") in (VOCABULARY.keys() | _EXPANSIONS.keys()):
        parts = [(lowered.replace("-", ""), 0)]
    else:
        parts, offset = [], 0
        for part in lowered.split("-"):
            parts.append((part, offset))
            offset += len(part) + 1
    words = []
    for word, offset in parts:
        for expanded in _EXPANSIONS.get(word, (word,)):
            entry = VOCABULARY.get(expanded)
            if entry is None:
                return (), (piece[offset:offset + len(word)], offset)
            words.append((entry.terminal, entry.value, offset, len(word)))
    return tuple(words), None


def tokenize(text: str) -> list[WordToken]:
    """Split an instruction into terminal tokens, each with its 1-based column in `text`.
    Raises UnknownWordError, or UnsupportedConstructError for a known English word that names
    something the language does not cover."""
    pieces = _pieces(text)
    return [WordToken(terminal, value, text[begin:end], begin + 1, end + 1)
            for (_, value, begin, end), terminal in zip(pieces, _terminals(pieces))
            if terminal is not None]


def terms(text: str) -> list[tuple[str, str]]:
    """(terminal, value) of each token `tokenize` gives, without placing or building the
    tokens (the wording rules ask this of thousands of sentences)."""
    analysed = [_analyse(piece) for piece in _WORD_OR_MARK.findall(text)]
    if any(unknown is not None for _, unknown in analysed):
        tokenize(text)  # raises the error, located
    found = [word for words, _ in analysed for word in words]
    return [(terminal, word[1]) for word, terminal in zip(found, _terminals(found))
            if terminal is not None]


def _pieces(text: str) -> list[tuple[str, str, int, int]]:
    """(terminal, value, begin, end) of each word and mark of `text` (0-based offsets, before
    the two-token decisions of _terminals); raises as `tokenize` says."""
    pieces = []
    for match in _WORD_OR_MARK.finditer(text):
        piece, start = match.group(), match.start()
        words, unknown = _analyse(piece)
        if unknown is not None:
            word, offset = unknown
            construct = unsupported(word)
            if construct is not None:
                raise UnsupportedConstructError(
                    f"not supported: {construct.name} ({word!r}); say instead: "
                    f"{construct.instead}", text=text, column=start + offset + 1,
                    length=len(word))
            raise UnknownWordError(f"unknown word {word!r}", text=text, column=start + offset + 1,
                                   length=max(len(word), 1),
                                   suggestions=tuple(suggestions(word.lower())))
        pieces += [(terminal, value, start + offset, start + offset + length)
                   for terminal, value, offset, length in words]
    return pieces


def _terminals(pieces: list[tuple]) -> list[str | None]:
    """Each piece's terminal (its first item) once the decisions the LALR(1) parser cannot
    make are made (None: dropped): a final '.', '!' or '?' is dropped and '..., please.' closes the instruction
    (PLEASE_END); then, by the next token, 'and' before a modifier is AND_MOD and before a
    noun phrase AND_NP, 'not' before a route's gerund NOT_GOING, and a separator right before
    'otherwise' or 'if' is dropped."""
    types = [piece[0] for piece in pieces]
    end = len(types)
    while end and types[end - 1] == "PERIOD":
        end -= 1
    if end and types[end - 1] == "PLEASE":
        types[end - 1] = "PLEASE_END"
    result: list[str | None] = [None] * len(types)
    kept = False
    for index in range(end):
        terminal = types[index]
        following = types[index + 1] if index + 1 < end else None
        if terminal in _SEPARATORS and following in _ABSORBING and kept:
            continue
        if terminal == "AND" and following in _MODIFIER_STARTS:
            terminal = "AND_MOD"
        elif terminal == "AND" and following in _NOUN_PHRASE_STARTS:
            terminal = "AND_NP"
        elif terminal == "NOT" and following in _ROUTE_GERUNDS:  # 'not passing over X'
            terminal = "NOT_GOING"
        result[index] = terminal
        kept = True
    return result

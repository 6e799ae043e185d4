"""What the instruction language does not cover, said plainly.

An English word outside the vocabulary is either a construct the language does not support
("rotate", "two", "all", "open": the error names the construct and what to say instead) or
a misspelling, for which a suggestion is made only when it is a real near miss: a small edit
distance and the same word form (a gerund for a gerund, a plural for a plural, ...).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Construct:
    name: str  # what the words ask for
    instead: str  # what the language supports instead


_UNSUPPORTED: tuple[tuple[Construct, tuple[str, ...]], ...] = (
    (Construct("rotating an object", "a final orientation when placing: 'place it on X with "
               "the long side facing front'"),
     ("rotate", "rotating", "rotated", "turn", "turning", "flip", "flipping", "spin",
      "spinning", "twist", "twisting", "upside", "orient", "orientate")),
    (Construct("numbers and counts", "name each object: 'pick up the red cube, then pick up "
               "the blue cube'; positions by 'first' to 'fifth' from a side"),
     ("zero", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
      "twice", "thrice", "pair", "couple", "several", "many", "few", "number", "count",
      "dozen", "half", "sixth", "seventh", "eighth", "ninth", "tenth", "last")),
    (Construct("quantifiers over several objects", "name one object per step"),
     ("all", "every", "each", "both", "any", "some", "none", "everything", "whole", "rest", "remaining", "others", "either", "neither", "nor",
      "everyone", "whichever", "whatever")),
    (Construct("opening, closing and pressing", "pick up, place, stack and push"),
     ("open", "opening", "closing", "lid", "drawer", "door", "handle", "press",
      "pressing", "button", "switch", "knob", "unlock", "lock")),
    (Construct("actions other than pick up, place, stack and push",
               "'pick up X', 'place X on Y', 'stack X onto Y', 'push X towards Y'"),
     ("pour", "pouring", "throw", "throwing", "toss", "drop", "dropping", "shake", "wipe",
      "give", "point", "touch", "hold", "holding", "release", "squeeze",
      "insert", "hang", "lean", "tilt", "roll", "rolling", "kick", "hit", "tap", "knock",
      "sweep", "lower", "raise", "carry", "carrying", "bring", "fetch", "get", "pull",
      "pulling", "drag", "dragging", "fold", "cut", "wave", "shift", "transfer",
      "relocate", "return", "unstack", "balance", "draw", "write", "clean", "wash")),
    (HANDOVER := Construct(
        "handing an object from one arm to the other", "one arm places it where the other "
        "reaches, then the other picks it up: 'use your left arm to place the red cube in "
        "front of the bowl, then use your right arm to pick up the red cube'"),
     ("handing", "handover", "handovers", "handoff", "hand-over", "hand-off")),
    (Construct("arranging several objects", "one step per object, in order: 'first ..., "
               "then ...'"),
     ("sort", "sorting", "arrange", "arranging", "line", "align", "aligning", "organize",
      "organise", "tidy", "clear", "swap", "swapping", "exchange", "gather", "collect",
      "separate", "group", "order", "pile", "heap", "reorder", "spread", "scatter")),
    (Construct("properties other than colour, kind and size",
               "colour words, 'larger' / 'smaller', or a position ('leftmost', 'in the bowl')"),
     ("tall", "taller", "tallest", "heavy", "heavier", "heaviest", "light", "lighter",
      "lightest", "wide", "wider", "widest", "narrow", "thin", "thinner", "thick", "thicker",
      "round", "rectangular", "cubic", "spherical", "cylindrical", "shiny", "metal",
      "metallic", "wooden", "plastic", "soft", "hard", "empty-looking", "full", "flat",
      "tiny", "huge", "giant", "medium", "dark", "darker", "bright", "pale", "striped",
      "dotted", "new", "old", "dirty", "hollow", "solid", "higher", "highest",
      "lowest", "upper", "low", "high")),
    (Construct("distances, angles and degrees of nearness", "relations: 'next to X' (or "
               "'near X'), 'closest to X', 'farthest from X', 'to the left of X', 'with the "
               "short side facing front'"),
     ("cm", "mm", "centimeter", "centimeters", "centimetre", "centimetres", "millimeters",
      "meter", "meters", "metre", "metres", "inch", "inches", "foot", "feet", "degree",
      "degrees", "angle", "distance", "far", "close", "closer", "nearer", "farther",
      "further", "away", "apart")),
    (Construct("speed, force and care of a motion (not scored)", "the motion itself: "
               "'pick up X', 'place it on Y'"),
     ("quickly", "slowly", "carefully", "gently", "fast", "slow", "gentle", "careful",
      "firmly", "softly", "quick", "smoothly", "precisely", "exactly", "roughly")),
    (Construct("timing and repetition", "steps in order: 'first ..., then ...'"),
     ("wait", "waiting", "seconds", "minute", "minutes", "later", "again", "once",
      "until", "stop", "pause", "repeat", "meanwhile", "simultaneously", "together",
      "during", "soon", "immediately", "finally", "lastly", "afterwards")),
    (Construct("pointing words and plural pronouns", "name the object ('the red cube') or "
               "say 'it' for the object just handled"),
     ("them", "they", "those", "these", "this", "here", "me", "my", "mine", "him", "her",
      "he", "she", "we", "us", "our", "yours", "someone", "somewhere")),
    (Construct("alternatives and exceptions", "one description ('the cube that is not red') "
               "or a condition ('if ..., otherwise ...')"),
     ("or", "but", "except", "besides", "same", "different",
      "similar", "other", "another", "alternatively", "also", "too")),
    (Construct("comparing with a named object ('than')", "'larger' / 'smaller' among the "
               "objects described, or 'closest to X'"),
     ("than", "as")),
    (Construct("objects and table regions not in the scenes", "the objects on the table: "
               "block, cube, cylinder, sphere (ball), slab (bar), bowl, label, table; "
               "positions by relations ('in front of the bowl', 'the leftmost cube')"),
     ("box", "boxes", "cup", "cups", "mug", "plate", "plates", "tray", "basket", "container",
      "bin", "bottle", "pen", "apple", "banana", "toy", "shelf", "robot", "floor", "ground",
      "corner", "corners", "room", "counter", "desk", "hole", "peg", "ring", "jar",
      "cloth", "towel", "sponge", "lego", "brick", "pyramid", "cone", "cuboid", "disk",
      "coin", "card", "paper", "pot", "pan", "spoon", "fork", "knife", "glass", "sticker",
      "marker", "tile", "mat", "pad", "area", "region", "zone", "target", "row", "column")),
    (Construct("colours other than the scene colours", "red, green, blue, yellow, orange, "
               "purple, pink, white, black, gray (grey), brown"),
     ("violet", "magenta", "cyan", "teal", "beige", "golden", "gold", "silver", "maroon",
      "navy", "lime", "turquoise", "indigo", "crimson", "scarlet", "olive", "tan", "khaki",
      "colored", "coloured", "colorful", "colourful")),
    (Construct("directions in the camera's or the speaker's frame",
               "left, right, front and back as seen from the robot's base"),
     ("north", "south", "east", "west", "clockwise", "counterclockwise", "anticlockwise",
      "upward", "upwards", "downward", "downwards", "sideways", "vertically",
      "horizontally", "diagonally", "diagonal", "opposite", "across", "through", "against",
      "along-side", "alongside", "within", "beyond", "past", "up-side")),
    (Construct("degrees of a relation", "the relation itself: 'behind "
               "X', 'to the right of X'"),
     ("directly", "just", "right-hand", "slightly", "straight")),
)

_GRAMMAR_WORDS = frozenset({"is", "are", "not", "and", "the", "a", "an", "of", "to", "it"})


def _index() -> dict[str, Construct]:
    index: dict[str, Construct] = {}
    for construct, words in _UNSUPPORTED:
        for word in words:
            index.setdefault(word, construct)
    return index


_INDEX = _index()


_POSSESSIVE = Construct("possessives", "a relation: 'to the right of the ball', 'on top of the "
                        "cube'")


def unsupported(word: str) -> Construct | None:
    """The construct a known English word asks for, when the language does not support it."""
    word = word.lower().replace("’", "'")
    if word.endswith("'s") and len(word) > 2:
        return _POSSESSIVE
    return _INDEX.get(word)


_AS_THE_ACTION = {"hand": HANDOVER, "pass": HANDOVER}  # words of the vocabulary ("hand" an
#   arm, "pass" a route) that ask, where the action is expected, for one it does not cover


def unsupported_action(word: str) -> Construct | None:
    """The construct a word of the vocabulary asks for when it stands where the action
    ('pick', 'place', ...) is expected, if the language does not support it."""
    return _AS_THE_ACTION.get(word.lower())


def unsupported_words() -> frozenset[str]:
    return frozenset(_INDEX)


def _form(word: str) -> str:
    """A word's form, as far as its ending tells: gerund, plural, superlative or plain."""
    if word.endswith("ing") and len(word) > 5:
        return "gerund"
    if word.endswith(("est", "most")) and len(word) > 5:
        return "superlative"
    if word.endswith("s") and not word.endswith("ss") and len(word) > 3:
        return "plural"
    return "plain"


def edit_distance(a: str, b: str, limit: int) -> int:
    """Levenshtein distance with transpositions, stopping early once it exceeds `limit`."""
    if abs(len(a) - len(b)) > limit:
        return limit + 1
    previous2: list[int] = []
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i] + [0] * len(b)
        for j, cb in enumerate(b, 1):
            cost = ca != cb
            current[j] = min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost)
            if i > 1 and j > 1 and ca == b[j - 2] and a[i - 2] == cb:
                current[j] = min(current[j], previous2[j - 2] + 1)
        if min(current) > limit:
            return limit + 1
        previous2, previous = previous, current
    return previous[-1]


def near_misses(word: str, known: list[str], count: int = 3) -> list[str]:
    """Known words a misspelling most likely stands for: at most one edit for words of up to
    five letters, two for longer ones; the same word form; never a short grammar word."""
    word = word.lower()
    if len(word) < 3 or word in _INDEX:
        return []
    limit = 1 if len(word) <= 5 else 2
    form = _form(word)
    scored = []
    for candidate in known:
        if candidate in _GRAMMAR_WORDS or _form(candidate) != form or "'" in candidate:
            continue
        distance = edit_distance(word, candidate, limit)
        if distance <= limit:
            scored.append((distance, candidate))
    return [candidate for _, candidate in sorted(scored)[:count]]

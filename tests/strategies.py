"""Hypothesis strategies: logical forms of every shape, and text from the vocabulary."""

from hypothesis import strategies as st

from robofollow.compiler import lf
from robofollow.compiler.lexicon import VOCABULARY


def _values(literal) -> st.SearchStrategy:
    return st.sampled_from(literal.__args__)


nouns = _values(lf.Noun)
arms = st.none() | _values(lf.Arm)

simple_constraints = st.one_of(
    st.builds(lf.ColorIs, color=_values(lf.Color), negated=st.booleans()),
    st.builds(lf.SizeIs, size=_values(lf.Size)),
    st.builds(lf.ExtremeIs, extreme=_values(lf.Extreme), negated=st.booleans()),
    st.builds(lf.NotKind, noun=nouns),
)
simple_refs = st.builds(lf.Ref, noun=nouns,
                        constraints=st.lists(simple_constraints, max_size=3).map(tuple))
relations = st.builds(lf.Related, relation=_values(lf.Relation), landmark=simple_refs,
                      negated=st.booleans())
constraints = st.one_of(simple_constraints, relations)
refs = st.builds(lf.Ref, noun=nouns, constraints=st.lists(constraints, max_size=3).map(tuple))

picks = st.builds(lf.Pick, arm=arms, object=refs)
pushes = st.builds(lf.Push, arm=arms, object=refs, toward=refs)
places = st.builds(
    lf.Place, arm=arms, object=refs,
    destination=st.builds(lf.Placement, relation=_values(lf.PlaceRelation), landmark=refs),
    route=st.lists(st.builds(lf.Waypoint, mode=st.sampled_from(["via", "avoid"]),
                             landmark=simple_refs), max_size=2).map(tuple),
    orientation=st.none() | st.builds(lf.Orientation, side=_values(lf.Side),
                                      facing=_values(lf.Facing)))
commands = st.one_of(picks, pushes, places)
sequences = st.builds(lf.Sequence, steps=st.lists(commands, min_size=2, max_size=3).map(tuple))
bodies = st.one_of(commands, sequences)
conditions = st.one_of(
    st.builds(lf.Exists, ref=refs, negated=st.booleans()),
    st.builds(lf.Holds, subject=refs, property=constraints),
)
conditionals = st.builds(lf.Conditional, condition=conditions, then=bodies,
                         otherwise=st.none() | bodies)
instructions = st.one_of(bodies, conditionals)

# text: sentences of known words (mostly ungrammatical) and arbitrary strings
_words = sorted(VOCABULARY) + [",", ";", ".", "-", "isn't", "non-empty"]
word_salad = st.lists(st.sampled_from(_words), max_size=25).map(" ".join)
any_text = st.text(max_size=80)

# small random specs: a few objects on a slot grid, swap variants, pick and place tasks
_SLOTS = [(x, y) for y in (-0.06, -0.18) for x in (-0.14, -0.02, 0.10)]
_SIZES = {"cube": "half=0.02", "cylinder": "radius=0.02 half_height=0.025",
          "sphere": "radius=0.02"}
_RGB = {"red": "(1, 0, 0)", "green": "(0, 0.8, 0)", "blue": "(0, 0, 1)", "yellow": "(1, 1, 0)"}
_PLACEMENTS = {"behind": "behind", "in_front_of": "in front of", "left_of": "to the left of",
               "right_of": "to the right of"}


@st.composite
def small_specs(draw) -> tuple[str, list[int]]:
    """(spec text, tasks per training layout) for one small random scene."""
    count = draw(st.integers(2, 5))
    objects = draw(st.lists(st.tuples(st.sampled_from(sorted(_SIZES)),
                                      st.sampled_from(["red", "green", "blue", "yellow"])),
                            min_size=count, max_size=count, unique=True))
    slots = draw(st.permutations(range(len(_SLOTS))))[:count]
    lines = ['scene demo "Random" {', "    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]"]
    for index, (kind, colour) in enumerate(objects):
        lines.append(f"    object o{index} {kind} {_SIZES[kind]} color={colour} "
                     f"rgb={_RGB[colour]} mass=0.2 friction=0.5")
    lines.append("    layout base {")
    lines += [f"        o{i} at ({_SLOTS[s][0]}, {_SLOTS[s][1]})" for i, s in enumerate(slots)]
    lines.append("    }")
    variants = draw(st.lists(st.tuples(st.integers(0, count - 1), st.integers(0, count - 1))
                             .filter(lambda p: p[0] != p[1]), min_size=1, max_size=2))
    for index, (a, b) in enumerate(variants):
        lines.append(f"    layout v{index} from base {{ swap o{a} o{b} }}")
    tasks = draw(st.lists(st.tuples(st.integers(0, count - 1),
                                    st.one_of(st.none(), st.tuples(st.integers(0, count - 1),
                                                                   st.sampled_from(sorted(_PLACEMENTS))))),
                          min_size=1, max_size=5))
    name = lambda i: f"the {objects[i][1]} {objects[i][0]}"  # noqa: E731
    for index, (source, place) in enumerate(tasks):
        # the arm on the side of where the object goes, as an author would choose it
        x = _SLOTS[slots[place[0] if place else source]][0]
        text = f"Use your {'left' if x < 0 else 'right'} arm to pick up {name(source)}"
        if place is not None and place[0] != source:
            text += f" and place it {_PLACEMENTS[place[1]]} {name(place[0])}"
        lines += [f"    task t{index} on base {{", f'        "{text}."', "    }"]
    layouts = ", ".join(f"v{i}" for i in range(len(variants)))
    lines += [f"    split L1 layouts=({layouts}) rounds=2 seed=7",
              "    split L2 wordings=(referents) max=12 rounds=2 seed=7",
              f"    split L3 layouts=({layouts}) wordings=(referents) max=12 rounds=2 seed=7",
              "}"]
    return "\n".join(lines) + "\n", [len(tasks)]

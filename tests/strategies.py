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

"""Malformed instructions, each with the error type it must raise and the column of the first
bad word."""

from robofollow.errors import (
    UngrammaticalError,
    UnknownWordError,
    UnsupportedConstructError,
)

UNKNOWN, UNGRAMMATICAL, UNSUPPORTED = UnknownWordError, UngrammaticalError, UnsupportedConstructError

CASES = [
    # unknown words
    ("Pick up the red cyllinder.", UNKNOWN, 17),
    ("Pick up the purple dragon.", UNKNOWN, 20),
    ("Pick up the cube 3.", UNKNOWN, 18),
    ("Pick up the red cube with your left leg.", UNKNOWN, 37),
    ("Pick up the cube @ the bowl.", UNKNOWN, 18),
    ("Pick up the cube that is larger than the ball.", UNSUPPORTED, 33),
    # ungrammatical order, or cut short
    ("", UNGRAMMATICAL, 1),
    ("   ", UNGRAMMATICAL, 1),
    ("Pick up the the red cube.", UNGRAMMATICAL, 13),
    ("Pick up the red cube and", UNGRAMMATICAL, 25),
    ("the red cube pick up", UNGRAMMATICAL, 5),  # "the" may open "the task is to"
    ("Place it behind.", UNGRAMMATICAL, 16),
    ("If the bowl, pick up the cube.", UNGRAMMATICAL, 12),
    ("If there is an object in the bowl pick up the cube otherwise", UNGRAMMATICAL, 61),
    ("Check whether the bowl is empty. If yes, pick up the cube.", UNGRAMMATICAL, 58),
    ("Pick up the cube before pick up the ball.", UNGRAMMATICAL, 25),
    ("Pick up the cube on the left of.", UNGRAMMATICAL, 32),
    # grammatical, but no meaning RoboFollow can represent
    ("Use your left arm to pick up the cube with your right arm.", UNSUPPORTED, 39),
    ("Pick it up.", UNSUPPORTED, 6),
    ("Push it towards the bowl.", UNSUPPORTED, 6),
    ("Pick up that cube.", UNSUPPORTED, 9),
    ("Place the red cube.", UNSUPPORTED, 1),
    ("Push the red cube.", UNSUPPORTED, 1),
    ("Pass over the red slab.", UNSUPPORTED, 1),
    ("Avoid the red slab.", UNSUPPORTED, 1),
    ("Pick up the red slab and pass over the green slab.", UNSUPPORTED, 26),
    ("Move the red slab over the green slab.", UNSUPPORTED, 19),
    ("Pick up the cube with the short side facing front.", UNSUPPORTED, 18),
    ("Pick up the cube onto the bowl.", UNSUPPORTED, 18),
    ("Pick up the cube in the direction of the ball.", UNSUPPORTED, 18),
    ("Pick up the cube that is not larger.", UNSUPPORTED, 18),
    ("Place the cube touching the bowl.", UNSUPPORTED, 16),
    ("Put the cube behind the ball behind it.", UNSUPPORTED, 37),
    ("Use your left arm.", UNSUPPORTED, 1),
    ("Pick up the object that is a cylinder that is a cube.", UNSUPPORTED, 39),
    ("Pick up the cube and place it behind the ball, short side facing front, "
     "long side facing right.", UNSUPPORTED, 73),
]

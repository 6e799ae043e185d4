"""The paper's QA-20 probe (Scene 2, default layout), each question as an Ask.

Six of the twenty ask for "the object to the left / right of X" where the benchmark's
grounding finds two objects within the relation's cone and range (it would reject such an
instruction as ambiguous); a person answers with the nearer one, and so does `answer_all`,
noting the other candidate, when the nearer leads by the grounding's extreme margin.
"""

from __future__ import annotations

import math

from robofollow.compiler.language import lf
from robofollow.compiler.scene.grounding import Grounder, GroundingError, Unclear
from robofollow.compiler.scene.world import EXTREME_MARGIN, World
from robofollow.vqa.answers import Expected
from robofollow.vqa.questions import (
    Ask,
    Question,
    expected,
    referents,
)

SCENE, LAYOUT = "scene2", "default"


def _the(color: str, noun: str) -> lf.Ref:
    return lf.Ref(noun=noun, constraints=(lf.ColorIs(color=color),))


QA20: tuple[tuple[str, Ask], ...] = (
    ("What is the object behind the blue cube?",
     Ask("what", "behind", _the("blue", "cube"))),
    ("Output the color of the object to the right of the green bowl.",
     Ask("color", "right_of", _the("green", "bowl"))),
    ("Output the color of the leftmost bowl.", Ask("extreme", noun="bowl", extreme="leftmost")),
    ("Output the color of the rightmost cube.",
     Ask("extreme", noun="cube", extreme="rightmost")),
    ("Output the color of the cylinder to the left of the red cube.",
     Ask("color", "left_of", _the("red", "cube"), noun="cylinder")),
    ("Output the color of the object in front of the red cube.",
     Ask("color", "in_front_of", _the("red", "cube"))),
    ("Describe the object to the right of the green bowl, such as what it is and what color "
     "it is.", Ask("describe", "right_of", _the("green", "bowl"))),
    ("What are the red objects in the scene, and what are their positions?",
     Ask("property", color="red")),
    ("Which object is located on the right side of the blue cube?",
     Ask("which_side", "right_of", _the("blue", "cube"))),
    ("Output the color of the rightmost cylinder.",
     Ask("extreme", noun="cylinder", extreme="rightmost")),
    ("Looking at the two red objects on the table, which one is on the left and which one is "
     "on the right?", Ask("pair", color="red")),
    ("Output the color of the object on the right side of the red cylinder.",
     Ask("color", "right_of", _the("red", "cylinder"))),
    ("Output the color of the leftmost cylinder.",
     Ask("extreme", noun="cylinder", extreme="leftmost")),
    ("Where are the two bowls located relative to each other? Which bowl is on the left side?",
     Ask("relative", noun="bowl")),
    ("What is the object behind the blue cylinder?",
     Ask("what", "behind", _the("blue", "cylinder"))),
    ("Output the color of the object in front of the red cylinder.",
     Ask("color", "in_front_of", _the("red", "cylinder"))),
    ("Output the color of the object to the right of the red cylinder.",
     Ask("color", "right_of", _the("red", "cylinder"))),
    ("Output the color of the object to the left of the blue cylinder.",
     Ask("color", "left_of", _the("blue", "cylinder"))),
    ("Output the color of the object to the left of the yellow bowl.",
     Ask("color", "left_of", _the("yellow", "bowl"))),
    ("Output the color of the object to the right of the blue cylinder.",
     Ask("color", "right_of", _the("blue", "cylinder"))),
)


def answer_all(world: World) -> list[tuple[Question, str | None]]:
    """Each QA-20 question with its answer in `world`, and a note where the grounding alone
    does not single the answer out."""
    grounder = Grounder(world)
    answered = []
    for number, (text, ask) in enumerate(QA20, start=1):
        found, note = _candidates(grounder, ask)
        if len(found) > 1 and ask.landmark is not None:
            found, nearest = _nearest(grounder, ask, found)
            note = nearest if note is None else f"{note}; {nearest}"
        elif ask.template not in ("pair", "relative", "property") and len(found) != 1:
            raise GroundingError("no-referent", f"QA-20 question {number} has no answer in "
                                                f"layout {world.layout.name}")
        answer: Expected = expected(world, ask, found)
        answered.append((Question(id=f"qa20-{number:02d}", template=ask.template, question=text,
                                  answer=answer.text, expected=answer), note))
    return answered


def _candidates(grounder: Grounder, ask: Ask) -> tuple[list[str], str | None]:
    """The bodies a question can be about, and a note where one stands at its direction's
    edge (the grounding calls that unclear; the question still has the paper's answer)."""
    try:
        return referents(grounder, ask), None
    except Unclear as error:
        world, landmark = grounder.world, grounder.resolve(ask.landmark)
        return [b for b in grounder.domain(ask.noun) if b != landmark and (
            b in error.candidates or world.related(b, ask.relation, landmark))], error.message


def _nearest(grounder: Grounder, ask: Ask, found: list[str]) -> tuple[list[str], str]:
    world = grounder.world
    anchor = world.poses[grounder.resolve(ask.landmark)]
    distance = {b: math.hypot(world.poses[b].x - anchor.x, world.poses[b].y - anchor.y)
                for b in found}
    ranked = sorted(found, key=distance.get)
    if distance[ranked[1]] - distance[ranked[0]] < EXTREME_MARGIN:
        raise GroundingError("ambiguous", f"{', '.join(ranked[:2])} are about as near",
                             tuple(ranked[:2]))
    return ranked[:1], (f"the grounding finds {', '.join(ranked)}; the nearest "
                        f"({distance[ranked[0]] * 100:.0f} cm against "
                        f"{distance[ranked[1]] * 100:.0f} cm) is the answer")

"""Groundings a careful reader shares, judged: generated instructions, each with the reading a
careful reader gives it by the paper's definitions (a test names one object, relation and
branch), and the verdict the rules must give.

- every branch of a conditional grounds, the one not taken too: a reader who meets "the
  cylinder from the right cube" where no cylinder stands on it cannot follow the instruction,
  whichever branch the layout takes.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from robofollow.benchmark.pipeline import compile_specs
from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language import lf
from robofollow.compiler.language.parser import parse
from robofollow.compiler.splits.task_rules import TaskRules, arms_of
from robofollow.compiler.splits.training import check_training

SPECS = Path(__file__).resolve().parent.parent / "specs"
SCENE4 = load_spec(SPECS / "scene4.rf")
TRAINING = check_training(SCENE4)
RULES = TaskRules(SCENE4.scenes["scene4"], TRAINING)

# (level, layout, instruction, origin, the finding a careful reader's verdict gives, why)
JUDGED = [
    ("L1", "scene4_6", "If there is an object on top of the right cube, use your right arm to "
     "place the cylinder from the right cube on the yellow cylinder; otherwise use your left "
     "arm to pick up the blue sphere.", "s41_if_object_on_right_cube_then_r_stack_else_l_pick_"
     "blue", ("no-referent", "in the branch not taken (then)"),
     "nothing stands on the right cube here, so the branch not taken names a cylinder that is "
     "not there: the reader cannot tell what the instruction means"),
]


@pytest.mark.parametrize(("level", "layout", "instruction", "origin", "verdict", "why"), JUDGED)
def test_judged_groundings(level, layout, instruction, origin, verdict, why):
    examined = RULES.examine(level, layout, instruction, parse(instruction),
                             arms_of(TRAINING[origin]))
    kind, words = verdict
    assert any(k == kind and words in message for k, message in examined.findings), (
        why, examined.findings)


def test_the_conditional_grounds_where_a_cylinder_stands_on_the_right_cube():
    """The same words on the training layout, where the green cylinder stands on the right
    cube: both branches name one body each."""
    examined = RULES.examine("L1", "scene4_1", JUDGED[0][2], parse(JUDGED[0][2]),
                             arms_of(TRAINING[JUDGED[0][3]]))
    assert not [f for f in examined.findings if f[0] in ("ambiguous", "no-referent")]
    assert examined.behaviour.other is not None


@pytest.fixture(scope="module")
def compiled():
    return compile_specs(SPECS)


def test_every_conditional_test_grounds_its_branch_not_taken(compiled):
    both = [t for t in compiled.splits.tasks
            if isinstance(t.form, lf.Conditional) and t.form.otherwise is not None]
    assert len(both) > 20
    assert all(t.behaviour.other is not None for t in both), [
        t.id for t in both if t.behaviour.other is None]

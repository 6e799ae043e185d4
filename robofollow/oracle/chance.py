"""What guessing earns, decided from the goal DAGs alone: the Intent a perfectly executed
behaviour earns when another one was asked for. The asked behaviour's stages are compared in
scoring order with the performed one's by their Intent checks (what, which arm, which object
and relation); Intent is credited while they agree and, as the scorer gates it, not from the
first that differs. Doing more than asked (an unstack is a pick-up first) still earns the
finishing stage. A behaviour that passes every Intent check of the asked one counts as
completing it. A language-blind policy choosing among K equally likely behaviours, none of
which passes another's checks, completes the asked one with probability 1/K: the chance level
scene entropy H(T|S) implies."""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.oracle.score import scoring_nodes


def intent_if_performed(asked: Behaviour, performed: Behaviour,
                        profile: ScoringProfile = DEFAULT_PROFILE) -> float:
    """The Intent score (0-1) of performing `performed` perfectly when `asked` is scored."""
    asked_work, asked_finish = _intent_checks(asked, profile)
    performed_work, performed_finish = _intent_checks(performed, profile)
    earned = 0.0
    for index, (weight, check) in enumerate(asked_work):
        if index >= len(performed_work) or performed_work[index][1] != check:
            return round(earned, 6)
        earned += weight
    if asked_finish is not None and asked_finish[1] == (performed_finish or (0, None))[1]:
        earned += asked_finish[0]
    return round(earned, 6)


def _intent_checks(behaviour: Behaviour, profile: ScoringProfile) -> tuple[list, tuple | None]:
    """(weight, Intent check) of the working stages in scoring order, and of the finish."""
    work, finish = [], None
    for _, node, _ in scoring_nodes(behaviour, profile):
        check = (node["weight"], json.dumps([node["name"], node["arm"], node["intent"]],
                                            sort_keys=True))
        if node["name"] == "finish":
            finish = check
        else:
            work.append(check)
    return work, finish


def guessing(asked: Behaviour, choices: Sequence[Behaviour],
             profile: ScoringProfile = DEFAULT_PROFILE) -> dict[str, float]:
    """Expected Intent ("IS") and completion ("CR"), both 0-1, of performing one of `choices`
    uniformly at random, perfectly."""
    if not choices:
        return {"IS": 0.0, "CR": 0.0}
    earned = np.array([intent_if_performed(asked, c, profile) for c in choices])
    return {"IS": round(float(earned.mean()), 6),
            "CR": round(float((earned >= 1.0 - 1e-6).mean()), 6)}

"""What guessing earns, decided from the goal DAGs alone: the Intent a perfectly executed
behaviour earns when another one was asked for. The asked behaviour's stages are compared in
scoring order with the performed one's by their Intent checks (what, which arm, which object
and relation); Intent is credited while they agree and, as the scorer gates it, not from the
first that differs. The finishing stage is credited only when the two finish alike (the same
arms, the same objects kept the same way): doing more than asked is an action the instruction
did not ask for. Completion follows the scorer's rule: a pickup by its scores (Intent at least
`pickup_complete`), any other action when every working check passes. A language-blind policy
choosing among K equally likely behaviours, none of which passes another's checks, completes
the asked one with probability 1/K: the chance level scene entropy H(T|S) implies."""

from __future__ import annotations

import json
from collections.abc import Sequence

import numpy as np

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.goals import scoring_nodes
from robofollow.compiler.profile import DEFAULT_PROFILE, ScoringProfile


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


def passes_work(asked: Behaviour, performed: Behaviour,
                profile: ScoringProfile = DEFAULT_PROFILE) -> bool:
    """Whether performing `performed` passes every working (not finishing) Intent check of
    `asked`, in order."""
    asked_work, _ = _intent_checks(asked, profile)
    performed_work, _ = _intent_checks(performed, profile)
    return [c for _, c in performed_work[:len(asked_work)]] == [c for _, c in asked_work]


def completes_if_performed(asked: Behaviour, performed: Behaviour,
                           profile: ScoringProfile = DEFAULT_PROFILE) -> bool:
    """Whether performing `performed` perfectly completes `asked`."""
    if asked.steps and all(step.action == "pick" for step in asked.steps):
        return intent_if_performed(asked, performed, profile) >= profile.pickup_complete - 1e-6
    if not asked.steps:
        return intent_if_performed(asked, performed, profile) >= 1.0 - 1e-6
    return passes_work(asked, performed, profile)


def _intent_checks(behaviour: Behaviour, profile: ScoringProfile) -> tuple[list, tuple | None]:
    """(weight, Intent check) of the working stages in scoring order, and of the finish."""
    work, finish = [], None
    for _, node, _ in scoring_nodes(behaviour, profile):
        check = (node["weight"], json.dumps([node["name"], node["arm"], node["intent"]],
                                            sort_keys=True, default=dict))  # (read-only views)
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
    earned = [intent_if_performed(asked, c, profile) for c in choices]
    done = [completes_if_performed(asked, c, profile) for c in choices]
    return {"IS": round(float(np.mean(earned)), 6), "CR": round(float(np.mean(done)), 6)}

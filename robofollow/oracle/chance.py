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
from collections.abc import Mapping, Sequence

import numpy as np

from robofollow.compiler.planning.goals import scoring_nodes
from robofollow.compiler.planning.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.world import World

Checks = tuple[list, tuple | None]  # (weight, check) of the working stages, and of the finish


def intent_if_performed(asked: Behaviour, performed: Behaviour,
                        profile: ScoringProfile = DEFAULT_PROFILE) -> float:
    """The Intent score (0-1) of performing `performed` perfectly when `asked` is scored."""
    return _earned(_intent_checks(asked, profile), _intent_checks(performed, profile))


def passes_work(asked: Behaviour, performed: Behaviour,
                profile: ScoringProfile = DEFAULT_PROFILE) -> bool:
    """Whether performing `performed` passes every working (not finishing) Intent check of
    `asked`, in order."""
    return _passes(_intent_checks(asked, profile), _intent_checks(performed, profile))


def completes_if_performed(asked: Behaviour, performed: Behaviour,
                           profile: ScoringProfile = DEFAULT_PROFILE) -> bool:
    """Whether performing `performed` perfectly completes `asked`."""
    return _completes(asked, _intent_checks(asked, profile), _intent_checks(performed, profile),
                      profile)


def _earned(asked: Checks, performed: Checks) -> float:
    (asked_work, asked_finish), (performed_work, performed_finish) = asked, performed
    earned = 0.0
    for index, (weight, check) in enumerate(asked_work):
        if index >= len(performed_work) or performed_work[index][1] != check:
            return round(earned, 6)
        earned += weight
    if asked_finish is not None and asked_finish[1] == (performed_finish or (0, None))[1]:
        earned += asked_finish[0]
    return round(earned, 6)


def _passes(asked: Checks, performed: Checks) -> bool:
    asked_work, performed_work = asked[0], performed[0]
    return [c for _, c in performed_work[:len(asked_work)]] == [c for _, c in asked_work]


def _completes(asked: Behaviour, asked_checks: Checks, performed: Checks,
               profile: ScoringProfile) -> bool:
    if asked.steps and all(step.action == "pick" for step in asked.steps):
        return _earned(asked_checks, performed) >= profile.pickup_complete - 1e-6
    if not asked.steps:
        return _earned(asked_checks, performed) >= 1.0 - 1e-6
    return _passes(asked_checks, performed)


def _intent_checks(behaviour: Behaviour, profile: ScoringProfile) -> Checks:
    """(weight, Intent check) of the working stages in scoring order, and of the finish."""
    work, finish = [], None
    for node, _ in scoring_nodes(behaviour, profile):
        check = (node.weight, json.dumps([node.name, node.arm, node.intent.to_json()],
                                         sort_keys=True))
        if node.name == "finish":
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


def available_behaviours(world: World, training: Mapping[str, Behaviour]) -> list[str]:
    """Labels of the training behaviours whose objects the layout has, in order: what a
    language-blind guess on that layout chooses among."""
    placed = set(world.poses)
    return [label for label, behaviour in training.items()
            if all({s.source, s.target, *(body for _, body in s.waypoints)} - {None} <= placed
                   for s in behaviour.steps)]


def earnings(asked: Sequence[Behaviour], choices: Sequence[Behaviour],
             profile: ScoringProfile = DEFAULT_PROFILE) -> list[list[tuple[float, bool]]]:
    """For each of `choices` performed perfectly, what it earns on each of `asked`: its Intent
    (0-1) and whether it completes it."""
    asked_checks = [_intent_checks(behaviour, profile) for behaviour in asked]
    found = []
    for choice in choices:
        performed = _intent_checks(choice, profile)
        found.append([(_earned(checks, performed), _completes(a, checks, performed, profile))
                      for a, checks in zip(asked, asked_checks, strict=True)])
    return found

"""Stage-wise scoring: walk a behaviour's goal DAG over a recorded trajectory.

Gating is strict: a stage's Intent counts only when every earlier stage's Intent is full; its
Execution only when every earlier stage is full in both and its own Intent is. The instructed
arm is part of the instruction: the source stage is the named arm's, and it earns no Intent when
the other arm grasped first. A sequence's steps must start in order. A conditional is scored on
the branch its condition selects; starting the other branch is reported. Completion: every
stage but the finish executed in full.
"""

from __future__ import annotations

import itertools
import json
from functools import lru_cache

from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.goals import goal_graph, stage_order
from robofollow.compiler.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.compiler.spec import Scene
from robofollow.compiler.training import describe
from robofollow.oracle.instead import describe_actions
from robofollow.oracle.recording import Recording, arm_index
from robofollow.oracle.results import EpisodeScore, ExecutedBehaviour, StageResult
from robofollow.oracle.stages import EVALUATORS, Outcome
from robofollow.trajectory import ARMS, Trajectory

FULL = 0.99  # a score at least this share of its maximum counts as full credit


@lru_cache(maxsize=4096)
def scoring_nodes(behaviour: Behaviour,
                  profile: ScoringProfile) -> tuple[tuple[str, dict, str], ...]:
    """The goal DAG's nodes in scoring order, each with a key naming what it checks (equal
    keys in different behaviours evaluate alike, so a recording evaluates them once)."""
    graph = goal_graph(behaviour, profile)
    return tuple((n, graph.nodes[n], json.dumps([graph.nodes[n][k] for k in (
        "name", "arm", "intent", "execution")], sort_keys=True)) for n in stage_order(graph))


def score(behaviour: Behaviour, trajectory: Trajectory, scene: Scene,
          profile: ScoringProfile = DEFAULT_PROFILE, episode: str | None = None,
          candidates: dict[str, Behaviour] | None = None) -> EpisodeScore:
    """Score a trajectory against the behaviour an episode asks for. `candidates` (e.g. the
    scene's training behaviours by label) are what 'what it did instead' is matched against,
    besides the instructed behaviour and a conditional's other branch."""
    rec = Recording(trajectory, scene, profile)
    stages = evaluate(rec, behaviour)
    other = None
    options = [("instructed", behaviour)]
    if behaviour.other is not None:
        branch = Behaviour(steps=behaviour.other)
        other_stages = evaluate(rec, branch)
        finish = sum(s.weight for s in other_stages if s.name == "finish")
        other = _total(other_stages, "intent") >= (1.0 - finish) * FULL and bool(branch.steps)
        options.append(("other branch", branch))
    options += list((candidates or {}).items())
    return EpisodeScore(episode=episode, intent_score=_total(stages, "intent"),
                        execution_score=_total(stages, "execution"),
                        complete=complete(stages), stages=tuple(stages),
                        executed_behaviour=_closest(rec, options), other_branch=other,
                        profile=profile.model_dump(mode="json"))


def _total(stages: list[StageResult], key: str) -> float:
    return round(sum(getattr(s, key) for s in stages), 6)


def complete(stages: list[StageResult]) -> bool:
    """Every stage but the finish executed in full (the finish alone, when it is all)."""
    scored = [s for s in stages if s.name != "finish"] or stages
    return all(s.execution >= s.weight * FULL for s in scored)


def evaluate(rec: Recording, behaviour: Behaviour) -> list[StageResult]:
    """Each stage of the behaviour's goal DAG, gated."""
    nodes = scoring_nodes(behaviour, rec.profile)
    marks: dict[str, dict] = {}
    reversed_steps = _reverse_order(rec, behaviour)
    results, blocked_intent, blocked_execution = [], None, None
    for node_id, node, key in nodes:
        step = node_id.rpartition(".")[0]
        mark = marks.setdefault(step, {})
        if reversed_steps:
            outcome = Outcome(False, False, None, reversed_steps)
        elif blocked_intent:
            outcome = Outcome(False, False, None, f"not scored: {blocked_intent} not met")
        else:
            _prepare(node, mark, marks, step, behaviour)
            outcome = _evaluate_node(rec, node, key, mark)
            if node["stage"] == 1 and len(behaviour.steps) == 1:
                outcome = _first_arm(rec, node, outcome)
        intent = outcome.intent and not blocked_intent
        execution = outcome.execution and intent and not blocked_execution
        reason = outcome.reason
        if outcome.execution and not execution:
            reason += f" (Execution not scored: {blocked_execution} not met)"
        weight = node["weight"]
        results.append(StageResult(stage=node_id, name=node["name"], weight=weight,
                                   intent=weight if intent else 0.0,
                                   execution=weight if execution else 0.0,
                                   first_step=outcome.frame, reason=reason))
        blocked_intent = blocked_intent or (None if intent else node_id)
        blocked_execution = blocked_execution or (None if execution else node_id)
    return results


def _evaluate_node(rec: Recording, node: dict, key: str, mark: dict) -> Outcome:
    """One stage's outcome, computed once per recording for the same check and start marks."""
    def run() -> tuple[Outcome, dict]:
        outcome = EVALUATORS[node["intent"]["predicate"]](rec, node, mark)
        return outcome, dict(mark)

    outcome, after = rec.cached((key, tuple(sorted(mark.items()))), run)
    mark.update(after)
    return outcome


def _prepare(node: dict, mark: dict, marks: dict, step: str, behaviour: Behaviour) -> None:
    """Hand a stage the frames it starts from: a sequence step's search starts where the
    previous step lifted its object; the finish starts when the last step completed."""
    if node["name"] == "finish":
        last = marks.get(_last_step(behaviour), {})
        mark["completion"] = next((last[k] for k in ("release", "objective", "lift", "grasp")
                                   if k in last), 0)
    elif step.startswith("step") and _step_number(step) > 1:
        previous = marks[f"step{_step_number(step) - 1}"]
        mark.setdefault("start", previous.get("lift", previous.get("grasp", 0)))


def _step_number(step: str) -> int:
    """The number of a sequence step ("step2" -> 2)."""
    return int(step.removeprefix("step"))


def _last_step(behaviour: Behaviour) -> str:
    return f"step{len(behaviour.steps)}" if len(behaviour.steps) > 1 else ""


def _first_arm(rec: Recording, node: dict, outcome: Outcome) -> Outcome:
    """The named arm must make the first grasp: the other arm grasping first (or alone)
    takes the source stage's Intent."""
    if node["arm"] is None:
        return outcome
    other = 1 - arm_index(node["arm"])
    grasp = rec.first_grasp(other)
    if grasp is None or (outcome.frame is not None and grasp.frame > outcome.frame):
        return outcome
    return Outcome(False, False, grasp.frame, f"the {ARMS[other]} arm, not the {node['arm']}, "
                   f"grasped first ({rec.bodies[grasp.body]} at frame {grasp.frame})")


def _reverse_order(rec: Recording, behaviour: Behaviour) -> str | None:
    """A sequence whose later step's object was taken before an earlier step's."""
    starts = []
    for step in behaviour.steps if len(behaviour.steps) > 1 else ():
        source = rec.index(step.source)
        frames = [g.frame for g in rec.grasps(arm_index(step.arm)) if g.body == source]
        starts.append((step.source, frames[0] if frames else None))
    for (earlier, a), (later, b) in itertools.pairwise(starts):
        if b is not None and (a is None or b < a):
            return f"out of order: {later} was taken before {earlier}"
    return None


def _closest(rec: Recording, options: list[tuple[str, Behaviour]]) -> ExecutedBehaviour:
    """The option the trajectory scores best against; on a tie the more specific one (more
    stages), then the earlier one."""
    best, best_key, best_scores = None, (1e-9, 0), (0.0, 0.0)
    seen = set()
    for name, behaviour in options:
        if behaviour.steps in seen or not _bodies(behaviour) <= set(rec.bodies):
            continue  # already matched under another name, or made for another layout
        seen.add(behaviour.steps)
        stages = evaluate(rec, behaviour)
        scores = (_total(stages, "intent"), _total(stages, "execution"))
        key = (round(sum(scores), 6), len(stages))
        if key > best_key:
            best, best_key, best_scores = (name, behaviour), key, scores
    return ExecutedBehaviour(description=describe_actions(rec), match=best and best[0],
                             behaviour=best and describe(best[1]),
                             intent_score=best_scores[0], execution_score=best_scores[1])


def _bodies(behaviour: Behaviour) -> set[str]:
    return {body for step in behaviour.steps
            for body in (step.source, step.target, *(b for _, b in step.waypoints)) if body}

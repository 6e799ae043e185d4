"""Stage-wise scoring: walk a behaviour's goal DAG over a recorded trajectory.

Gating is strict: a stage's Intent counts only when every earlier stage's Intent is full; its
Execution only when every earlier stage is full in both and its own Intent is. The instructed
arm is part of the instruction: a step's source stage earns no Intent when the other arm went
for that step's object first. A sequence's steps must start in order. A conditional is scored
on the branch its condition selects; carrying out the other branch too (at any time) voids the
credit: no branch was chosen. Completion follows the paper (see `complete`).
"""

from __future__ import annotations

import itertools

from robofollow.compiler.planning.goals import GoalNode, scoring_nodes
from robofollow.compiler.planning.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.compiler.scene.behaviour import Behaviour, Step, describe
from robofollow.compiler.scene.spec import Scene
from robofollow.oracle.chance import passes_work
from robofollow.oracle.instead import arms_moved, describe_actions
from robofollow.oracle.outcome import GOING_FOR, Outcome
from robofollow.oracle.recording import Attempt, Recording, arm_index
from robofollow.oracle.results import EpisodeScore, ExecutedBehaviour, StageResult
from robofollow.oracle.stages import AT_REST, EVALUATORS
from robofollow.trajectory import ARMS, Trajectory

FULL = 0.99  # a score at least this share of its maximum counts as full credit
SOURCE_STAGES = ("source_grounding", "push_contact")
END_STAGES = ("objective", "outcome")  # the stages whose execution geometry is a step's end state


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
        other = _carried_out(rec, branch, behaviour)
        options.append(("other branch", branch))
        if other:
            stages = [_void(s) for s in stages]
    options += list((candidates or {}).items())
    return EpisodeScore(episode=episode, intent_score=_total(stages, "intent"),
                        execution_score=_total(stages, "execution"),
                        complete=complete(rec, behaviour, stages, bool(other)),
                        stages=tuple(stages), executed_behaviour=_closest(rec, options),
                        other_branch=other, profile=profile.model_dump(mode="json"))


def _total(stages: list[StageResult], key: str) -> float:
    return round(sum(getattr(s, key) for s in stages), 6)


def _carried_out(rec: Recording, branch: Behaviour, selected: Behaviour) -> bool:
    """Whether the branch not selected was carried out: every stage of it but the finish
    earned its Intent, and performing the selected branch does not already do that (it is
    not contained in it)."""
    if not branch.steps or passes_work(branch, selected, rec.profile):
        return False
    stages = evaluate(rec, branch)
    return all(s.intent >= s.weight * FULL for s in stages if s.name != "finish")


def _void(stage: StageResult) -> StageResult:
    if not stage.intent:
        return stage
    return stage.model_copy(update={"intent": 0.0, "execution": 0.0, "reason": (
        f"{stage.reason} (not credited: the branch the condition does not select was carried "
        "out too)")})


def complete(rec: Recording, behaviour: Behaviour, stages: list[StageResult],
             other_branch: bool = False) -> bool:
    """Completion. Profile 'strict': every stage but the finish executed in full. Profile
    'paper' (the default), action-dependent as the paper defines it: pickups and sequences of
    pickups need final IS and ES of at least `pickup_complete`; every other action needs each
    step's end state over the last `final_frames` frames, brought about by its named arm (an
    object at rest in the asked relation / on / in the target or on the label at the asked
    yaw, and let go of; a pushed object moved far enough towards the target; a picked object
    held), and a transfer (Scene 3) its placement-and-orientation stage executed (gated: the
    route kept) as well. A branch asking for nothing is complete when nothing was done; a
    conditional whose other branch was carried out is not."""
    if other_branch:
        return False
    if rec.profile.completion == "strict" or not behaviour.steps:
        scored = [s for s in stages if s.name != "finish"] or stages
        return all(s.execution >= s.weight * FULL for s in scored)
    if all(step.action == "pick" for step in behaviour.steps):
        least = rec.profile.pickup_complete - 1e-6
        return _total(stages, "intent") >= least and _total(stages, "execution") >= least
    if any(s.name == "orientation" and not s.execution for s in stages):
        return False  # a transfer's route and orientation, as its stages ask (gated)
    objectives = {node.step: node for node, _ in scoring_nodes(behaviour, rec.profile)
                  if node.id.rpartition(".")[2] in END_STAGES}
    return all(_final_state(rec, step, objectives.get(key)) for key, step in _steps(behaviour))


def _final_state(rec: Recording, step: Step, node: GoalNode | None) -> bool:
    """The step's end state over the last frames, brought about by its named arm: a picked
    object still held, any other let go of and its objective's rest geometry holding."""
    arm, source = arm_index(step.arm), rec.index(step.source)
    if _goes_for(rec, arm, step) is None:
        return False
    if node is None:  # a pickup
        return rec.holding(arm)[-1] == source
    if rec.holding(arm)[-1] == source:
        return False
    check = AT_REST[node.execution.name]
    params = node.execution.params
    last = range(max(0, rec.last - rec.profile.final_frames + 1), rec.last + 1)
    return all(check(rec, params, frame) is None for frame in last)


def evaluate(rec: Recording, behaviour: Behaviour) -> list[StageResult]:
    """Each stage of the behaviour's goal DAG, gated."""
    nodes = scoring_nodes(behaviour, rec.profile)
    marks: dict[str, dict] = {}
    reversed_steps = _reverse_order(rec, behaviour)
    results, blocked_intent, blocked_execution = [], None, None
    for node, key in nodes:
        step = node.step
        mark = marks.setdefault(step, {})
        if reversed_steps:
            outcome = Outcome(False, False, None, reversed_steps)
        elif blocked_intent:
            outcome = Outcome(False, False, None, f"not scored: {blocked_intent} not met")
        else:
            _prepare(node, mark, marks, step, behaviour)
            outcome = _evaluate_node(rec, node, key, mark)
            if node.name in SOURCE_STAGES:
                outcome = _first_arm(rec, dict(_steps(behaviour))[step], outcome)
        intent = outcome.intent and not blocked_intent
        execution = outcome.execution and intent and not blocked_execution
        reason = outcome.reason
        if outcome.execution and not execution:
            reason += f" (Execution not scored: {blocked_execution} not met)"
        weight = node.weight
        results.append(StageResult(stage=node.id, name=node.name, weight=weight,
                                   intent=weight if intent else 0.0,
                                   execution=weight if execution else 0.0,
                                   first_step=outcome.frame, reason=reason))
        blocked_intent = blocked_intent or (None if intent else node.id)
        blocked_execution = blocked_execution or (None if execution else node.id)
    return results


def _evaluate_node(rec: Recording, node: GoalNode, key: str, mark: dict) -> Outcome:
    """One stage's outcome, computed once per recording for the same check and start marks."""
    def run() -> tuple[Outcome, dict]:
        outcome = EVALUATORS[node.intent.name](rec, node, mark)
        return outcome, dict(mark)

    outcome, after = rec.cached((key, tuple(sorted(mark.items()))), run)
    mark.update(after)
    return outcome


def _prepare(node: GoalNode, mark: dict, marks: dict, step: str, behaviour: Behaviour) -> None:
    """Hand a stage the frames it starts from: a sequence step's search starts where the
    previous step lifted its object; the finish starts when the last step completed (its
    release, else its objective, lift or attempt) and knows where each handled object came
    to rest."""
    if node.name == "finish":
        last = marks.get(_steps(behaviour)[-1][0], {})
        mark["completion"] = next((last[k] for k in ("release", "objective", "lift", "attempt")
                                   if k in last), 0)
        mark["rests"] = tuple((s.source, marks[key]["rest"]) for key, s in _steps(behaviour)
                              if "rest" in marks.get(key, {}))
    elif step.startswith("step") and _step_number(step) > 1:
        previous = marks[f"step{_step_number(step) - 1}"]
        mark.setdefault("start", previous.get("lift", previous.get("attempt", 0)))


def _steps(behaviour: Behaviour) -> list[tuple[str, Step]]:
    """(marks key, step) of each step."""
    if len(behaviour.steps) == 1:
        return [("", behaviour.steps[0])]
    return [(f"step{i}", s) for i, s in enumerate(behaviour.steps, start=1)]


def _step_number(step: str) -> int:
    """The number of a sequence step ("step2" -> 2)."""
    return int(step.removeprefix("step"))


def _goes_for(rec: Recording, arm: int, step: Step) -> Attempt | None:
    """The arm's first attempt at the step's object of the kinds that go for it."""
    return rec.first_attempt(arm, kinds=GOING_FOR[step.action], body=rec.index(step.source))


def _first_arm(rec: Recording, step: Step, outcome: Outcome) -> Outcome:
    """The named arm must go for its step's object first: the other arm going for that
    object before it (or instead of it) takes the source stage's Intent."""
    named = arm_index(step.arm)
    theirs = _goes_for(rec, 1 - named, step)
    if theirs is None:
        return outcome
    ours = _goes_for(rec, named, step)
    if ours is not None and ours.frame <= theirs.frame:
        return outcome
    return Outcome(False, False, theirs.frame, f"the {ARMS[1 - named]} arm, not the "
                   f"{step.arm}, {theirs.words(rec.bodies)}")


def _reverse_order(rec: Recording, behaviour: Behaviour) -> str | None:
    """A sequence whose later step's object was gone for before an earlier step's."""
    starts = []
    for step in behaviour.steps if len(behaviour.steps) > 1 else ():
        attempt = _goes_for(rec, arm_index(step.arm), step)
        starts.append((step.source, attempt.frame if attempt else None))
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
                             intent_score=best_scores[0], execution_score=best_scores[1],
                             arms_moved=arms_moved(rec))


def _bodies(behaviour: Behaviour) -> set[str]:
    return {body for step in behaviour.steps
            for body in (step.source, step.target, *(b for _, b in step.waypoints)) if body}

"""Behaviour -> goal DAG: the stages an episode is scored on, gated in order.

Stages follow the paper: source grounding (grasp or push contact), the action objective
(relative placement, stack, bowl, push, route), the outcome (placement and orientation), and a
finishing stage for every task (back home and still, the handled objects left as put, nothing
else disturbed, the other arm out of the work area). Each node is a frozen GoalNode: its
weight and the intent and execution predicates, by name, with their parameters (read-only); an
edge a -> b means b is scored only when a is fully achieved. A sequence chains its steps.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from itertools import pairwise
from types import MappingProxyType

import networkx as nx

from robofollow.compiler.planning.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.compiler.scene.behaviour import Behaviour, Step


@dataclass(frozen=True, slots=True)
class Predicate:
    """A predicate the oracle evaluates (stages.EVALUATORS, stages.AT_REST), by name, with its
    parameters: body names, metres, degrees (read-only: lists are tuples)."""

    name: str
    params: Mapping[str, object]

    def to_json(self) -> dict:
        return {"predicate": self.name, "params": _plain(self.params)}


@dataclass(frozen=True, slots=True)
class GoalNode:
    """One stage of a goal DAG: its place in the scoring order, name, weight, arm (None for
    the finish) and the predicates its Intent and Execution are judged by."""

    id: str
    stage: int
    name: str
    weight: float
    arm: str | None
    intent: Predicate
    execution: Predicate

    @property
    def step(self) -> str:
        """The step the stage belongs to ('step2' in a sequence, '' otherwise)."""
        return self.id.rpartition(".")[0]

    def to_json(self) -> dict:
        return {"id": self.id, "stage": self.stage, "name": self.name, "weight": self.weight,
                "arm": self.arm, "intent": self.intent.to_json(),
                "execution": self.execution.to_json()}

    def check_key(self) -> str:
        """What the stage checks, as text: equal keys in different behaviours evaluate alike."""
        return json.dumps([self.name, self.arm, self.intent.to_json(), self.execution.to_json()],
                          sort_keys=True)


def _predicate(name: str, **params) -> Predicate:
    return Predicate(name, _read_only(params))


class _Builder:
    def __init__(self, profile: ScoringProfile):
        self.p = profile
        self.nodes: list[GoalNode] = []

    def add(self, node_id: str, name: str, weight: float, arm: str | None, intent: Predicate,
            execution: Predicate) -> None:
        self.nodes.append(GoalNode(node_id, len(self.nodes) + 1, name, round(weight, 6), arm,
                                   intent, execution))

    def grasp(self, prefix: str, step: Step, weight: float, lift: float) -> None:
        self.add(f"{prefix}source", "source_grounding", weight, step.arm,
                 _predicate("went_for", arm=step.arm, object=step.source,
                            reach=self.p.reach_radius),
                 _predicate("held_and_lifted", object=step.source, min_lift=lift))

    def push_contact(self, prefix: str, step: Step, weight: float) -> None:
        p = self.p
        self.add(f"{prefix}source", "push_contact", weight, step.arm,
                 _predicate("first_pushed", arm=step.arm, object=step.source),
                 _predicate("pushed_closed_low", object=step.source,
                            close=p.push_close_threshold, height=p.push_height_tolerance))

    def objective(self, prefix: str, step: Step, weight: float) -> None:
        p = self.p
        if step.action == "push":
            towards = dict(object=step.source, target=step.target, cone_deg=p.push_cone_deg)
            self.add(f"{prefix}objective", "push", weight, step.arm,
                     _predicate("pushed_towards", min_displacement=p.push_min_intent, **towards),
                     _predicate("pushed_towards_at_rest", min_displacement=p.push_min_execution,
                                **towards))
        elif step.relation == "on":
            self.add(f"{prefix}objective", "stack", weight, step.arm,
                     _predicate("delivered_onto", object=step.source, target=step.target,
                                radius=p.aim_radius),
                     _predicate("rests_on", object=step.source, target=step.target,
                                xy=p.stack_xy, clearance=p.stack_clearance,
                                rest=p.rest_tolerance))
        elif step.relation == "in":
            self.add(f"{prefix}objective", "place_in_bowl", weight, step.arm,
                     _predicate("delivered_into", object=step.source, bowl=step.target,
                                radius=p.aim_radius),
                     _predicate("rests_in", object=step.source, bowl=step.target, xy=p.bowl_xy,
                                height=p.bowl_height))
        else:
            self.add(f"{prefix}objective", "relative_placement", weight, step.arm,
                     _predicate("delivered_towards", object=step.source,
                                relation=step.relation, landmark=step.target,
                                cone_deg=p.relation_cone_deg, reach=p.relation_reach),
                     _predicate("rests_in_relation", object=step.source,
                                relation=step.relation, landmark=step.target,
                                range=p.relation_range, cone_deg=p.relation_cone_deg,
                                rest=p.rest_tolerance))

    def transfer(self, step: Step, weights: tuple[float, float, float, float]) -> None:
        p = self.p
        self.grasp("", step, weights[0], p.min_lift)
        route = [list(w) for w in step.waypoints]
        self.add("route", "route", weights[1], step.arm,
                 _predicate("route_sides", object=step.source, waypoints=route, x=p.route_x,
                            y=p.route_y),
                 _predicate("route_footprints", object=step.source, waypoints=route))
        yaw = dict(object=step.source, target=step.target, yaw_deg=step.yaw_degrees)
        self.add("outcome", "orientation", weights[2], step.arm,
                 _predicate("delivered_to_label", radius=p.aim_radius,
                            tolerance_deg=p.yaw_intent_deg, **yaw),
                 _predicate("rests_on_label", rest=p.rest_tolerance,
                            tolerance_deg=p.yaw_execution_deg, **yaw))
        self.finish(weights[3], [step])

    def finish(self, weight: float, steps: list[Step]) -> None:
        """Back home and still; each handled object held (pickups) or left where it came to
        rest; nothing else disturbed (a push's target may be struck, within its own tolerance);
        the idle arm out of the work area."""
        p = self.p
        keep = [[step.source, _KEEP[step.action], step.arm] for step in steps]
        struck = [step.target for step in steps if step.action == "push"]  # may be hit
        params = dict(arms=[step.arm for step in steps], keep=keep, struck=struck,
                      home_radius=p.home_radius, frames=p.home_frames,
                      still_radius=p.still_radius, deadline_frames=p.home_deadline_frames,
                      leave_radius=p.leave_home_radius, stay=p.stay_tolerance,
                      disturb=p.disturb_tolerance, struck_tolerance=p.struck_tolerance,
                      topple_deg=p.topple_deg,
                      operation_area=[list(a) for a in p.operation_area])
        self.add("finish", "finish", weight, None, _predicate("finished", **params),
                 _predicate("finished", **params))

    def single(self, step: Step) -> None:
        p = self.p
        if step.action == "pick":
            self.grasp("", step, p.pick_weights[0], p.pickup_lift)
            self.finish(p.pick_weights[1], [step])
        elif step.action == "place" and (step.waypoints or step.yaw_degrees is not None):
            self.transfer(step, p.transfer_weights)
        else:
            source, objective, finish = p.action_weights
            if step.action == "push":
                self.push_contact("", step, source)
            else:
                self.grasp("", step, source, p.min_lift)
            self.objective("", step, objective)
            self.finish(finish, [step])

    def sequence(self, steps: tuple[Step, ...]) -> None:
        shared, finish = self.p.sequence_weights
        for index, step in enumerate(steps, start=1):
            weight = shared / len(steps)
            prefix = f"step{index}."
            if step.action == "pick":
                self.grasp(prefix, step, weight, self.p.min_lift)
                continue
            if step.action == "push":
                self.push_contact(prefix, step, weight / 2)
            else:
                self.grasp(prefix, step, weight / 2, self.p.min_lift)
            self.objective(prefix, step, weight / 2)
        self.finish(finish, list(steps))


_KEEP = {"pick": "held", "place": "placed", "push": "pushed"}  # how a handled object ends


def goal_graph(behaviour: Behaviour, profile: ScoringProfile = DEFAULT_PROFILE) -> nx.DiGraph:
    """The goal DAG of a behaviour under a scoring profile (recorded on the graph)."""
    builder = _Builder(profile)
    if not behaviour.steps:  # a conditional whose branch asks for nothing: stay still
        builder.finish(1.0, [])
    elif len(behaviour.steps) == 1:
        builder.single(behaviour.steps[0])
    else:
        builder.sequence(behaviour.steps)
    graph = nx.DiGraph(profile=profile.model_dump(mode="json"), branch=behaviour.branch)
    for node in builder.nodes:
        graph.add_node(node.id, goal=node)
    for a, b in pairwise(builder.nodes):
        graph.add_edge(a.id, b.id, kind="gates")
    return graph


def goal(graph: nx.DiGraph, node_id: str) -> GoalNode:
    """The stage a node of a goal DAG stands for."""
    return graph.nodes[node_id]["goal"]


def stage_order(graph: nx.DiGraph) -> list[str]:
    """Nodes in scoring order (deterministic)."""
    return list(nx.lexicographical_topological_sort(graph, key=lambda n: goal(graph, n).stage))


def graph_to_dict(graph: nx.DiGraph) -> dict:
    """A JSON-ready form: nodes in scoring order, gating edges, the profile's name."""
    return {"profile": graph.graph["profile"]["name"], "branch": graph.graph["branch"],
            "nodes": [goal(graph, n).to_json() for n in stage_order(graph)],
            "edges": [[a, b] for a, b in graph.edges]}


def _read_only(value):
    """Parameters as read-only views (mappings) and tuples (lists), all through."""
    if isinstance(value, dict):
        return MappingProxyType({key: _read_only(item) for key, item in value.items()})
    if isinstance(value, list | tuple):
        return tuple(_read_only(item) for item in value)
    return value


def _plain(value):
    """Read-only parameters back as JSON values: dicts and lists."""
    if isinstance(value, Mapping):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, tuple):
        return [_plain(item) for item in value]
    return value


@lru_cache(maxsize=4096)
def scoring_nodes(behaviour: Behaviour,
                  profile: ScoringProfile) -> tuple[tuple[GoalNode, str], ...]:
    """The goal DAG's stages in scoring order, each with its check key (GoalNode.check_key:
    a recording evaluates equal checks once). Cached and shared by every caller."""
    graph = goal_graph(behaviour, profile)
    return tuple((node, node.check_key()) for node in (goal(graph, n) for n in stage_order(graph)))

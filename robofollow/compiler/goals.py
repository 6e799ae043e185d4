"""Behaviour -> goal DAG: the stages an episode is scored on, gated in order.

Stages follow the paper: source grounding (grasp or push contact), the action objective
(relative placement, stack, bowl, push, route), the outcome (placement and orientation), and a
finishing stage (back home, still, the other arm out of the work area). Each node carries its
weight and the intent and execution predicates, by name, with their parameters; an edge
a -> b means b is scored only when a is fully achieved. A sequence chains its steps.
"""

from __future__ import annotations

from itertools import pairwise

import networkx as nx

from robofollow.compiler.behaviour import Behaviour, Step
from robofollow.compiler.profile import DEFAULT_PROFILE, ScoringProfile


def _predicate(name: str, **params) -> dict:
    return {"predicate": name, "params": params}


class _Builder:
    def __init__(self, profile: ScoringProfile):
        self.p = profile
        self.nodes: list[tuple[str, dict]] = []

    def add(self, node_id: str, name: str, weight: float, arm: str | None, intent: dict,
            execution: dict) -> None:
        self.nodes.append((node_id, {"stage": len(self.nodes) + 1, "name": name,
                                     "weight": round(weight, 6), "arm": arm,
                                     "intent": intent, "execution": execution}))

    def grasp(self, prefix: str, step: Step, weight: float, lift: float) -> None:
        self.add(f"{prefix}source", "source_grounding", weight, step.arm,
                 _predicate("nearest_at_first_close", arm=step.arm, object=step.source,
                            radius=self.p.grasp_radius, close=self.p.close_threshold),
                 _predicate("lifted", object=step.source, min_lift=lift))

    def objective(self, prefix: str, step: Step, weight: float) -> None:
        p = self.p
        if step.action == "push":
            self.add(f"{prefix}objective", "push", weight, step.arm,
                     _predicate("pushed_towards", object=step.source, target=step.target,
                                min_displacement=p.push_min_intent, cone_deg=p.push_cone_deg),
                     _predicate("pushed_towards", object=step.source, target=step.target,
                                min_displacement=p.push_min_execution, cone_deg=p.push_cone_deg))
        elif step.relation == "on":
            self.add(f"{prefix}objective", "stack", weight, step.arm,
                     _predicate("held_above", object=step.source, target=step.target,
                                radius=p.grasp_radius, clearance=p.stack_clearance),
                     _predicate("stacked_on", object=step.source, target=step.target,
                                xy=p.stack_xy, clearance=p.stack_clearance))
        elif step.relation == "in":
            self.add(f"{prefix}objective", "place_in_bowl", weight, step.arm,
                     _predicate("lowered_into", object=step.source, bowl=step.target,
                                xy=p.bowl_xy, height=p.bowl_height),
                     _predicate("released_in", object=step.source, bowl=step.target,
                                xy=p.bowl_xy, height=p.bowl_height))
        else:
            params = dict(object=step.source, relation=step.relation, landmark=step.target,
                          range=p.relation_range, cone_deg=p.relation_cone_deg,
                          on_table=p.on_table_tolerance)
            self.add(f"{prefix}objective", "relative_placement", weight, step.arm,
                     _predicate("set_down_in_relation", **params),
                     _predicate("released_in_relation", **params))

    def transfer(self, step: Step, weights: tuple[float, float, float]) -> None:
        p = self.p
        self.grasp("", step, weights[0], p.min_lift)
        route = [list(w) for w in step.waypoints]
        self.add("route", "route", weights[1], step.arm,
                 _predicate("carried_over", object=step.source, waypoints=route, x=p.route_x,
                            y=p.route_y, clear_y=p.route_clear_y),
                 _predicate("carried_over", object=step.source, waypoints=route, x=p.route_x,
                            y=p.route_y, clear_y=p.route_clear_y))
        placement = dict(object=step.source, relation=step.relation, target=step.target,
                         edge=p.label_edge, yaw_deg=step.yaw_degrees)
        self.add("outcome", "orientation", weights[2], step.arm,
                 _predicate("final_placement", tolerance_deg=p.yaw_intent_deg, **placement),
                 _predicate("final_placement", tolerance_deg=p.yaw_execution_deg, **placement))

    def finish(self, weight: float, arms: list[str | None]) -> None:
        p = self.p
        params = dict(arms=arms, home_radius=p.home_radius, frames=p.home_frames,
                      deadline_frames=p.home_deadline_frames, leave_radius=p.leave_home_radius,
                      operation_area=[list(a) for a in p.operation_area],
                      close=p.close_threshold)
        self.add("finish", "finish", weight, None, _predicate("finished", **params),
                 _predicate("finished", **params))

    def single(self, step: Step) -> None:
        p = self.p
        if step.action == "pick":
            self.grasp("", step, p.pick_weights[0], p.pickup_lift)
            self.finish(p.pick_weights[1], [step.arm])
        elif step.action == "place" and (step.waypoints or step.yaw_degrees is not None):
            self.transfer(step, p.transfer_weights)
        else:
            source, objective, finish = p.action_weights
            if step.action == "push":
                self.add("source", "push_contact", source, step.arm,
                         _predicate("push_contact", arm=step.arm, object=step.source,
                                    radius=p.grasp_radius, close=p.push_close_threshold),
                         _predicate("push_contact_low", arm=step.arm, object=step.source,
                                    radius=p.push_contact_radius,
                                    height=p.push_height_tolerance))
            else:
                self.grasp("", step, source, p.min_lift)
            self.objective("", step, objective)
            self.finish(finish, [step.arm])

    def sequence(self, steps: tuple[Step, ...]) -> None:
        shared, finish = self.p.sequence_weights
        for index, step in enumerate(steps, start=1):
            weight = shared / len(steps)
            if step.action == "pick":
                self.grasp(f"step{index}.", step, weight, self.p.min_lift)
            else:
                self.grasp(f"step{index}.", step, weight / 2, self.p.min_lift)
                self.objective(f"step{index}.", step, weight / 2)
        self.finish(finish, [step.arm for step in steps])


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
    for node_id, attributes in builder.nodes:
        graph.add_node(node_id, **attributes)
    for (a, _), (b, _) in pairwise(builder.nodes):
        graph.add_edge(a, b, kind="gates")
    return graph


def stage_order(graph: nx.DiGraph) -> list[str]:
    """Nodes in scoring order (deterministic)."""
    return list(nx.lexicographical_topological_sort(graph, key=lambda n: graph.nodes[n]["stage"]))


def graph_to_dict(graph: nx.DiGraph) -> dict:
    """A JSON-ready form: nodes in scoring order, gating edges, the profile's name."""
    return {"profile": graph.graph["profile"]["name"], "branch": graph.graph["branch"],
            "nodes": [{"id": n, **graph.nodes[n]} for n in stage_order(graph)],
            "edges": [[a, b] for a, b in graph.edges]}

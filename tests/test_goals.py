"""Goal DAGs: stage chains with the default profile's weights and gating."""

import json
from itertools import pairwise
from pathlib import Path

import networkx as nx
import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.planning.goals import (
    goal,
    goal_graph,
    graph_to_dict,
    stage_order,
)
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.compiler.splits.training import check_training

SPECS = Path(__file__).resolve().parent.parent / "specs"


@pytest.fixture(scope="module")
def behaviours():
    return check_training(load_spec(SPECS))


def test_every_training_graph_is_a_gated_chain_whose_weights_sum_to_one(behaviours):
    for behaviour in behaviours.values():
        graph = goal_graph(behaviour)
        order = stage_order(graph)
        assert nx.is_directed_acyclic_graph(graph)
        assert list(graph.edges) == list(pairwise(order))
        assert sum(goal(graph, n).weight for n in order) == pytest.approx(1.0)


@pytest.mark.parametrize("label,names,weights", [
    ("pickup_yellow_block_1_left", ["source_grounding", "finish"], [0.8, 0.2]),
    ("place_yellow_block_1_behind_red_cylinder",
     ["source_grounding", "relative_placement", "finish"], [0.4, 0.4, 0.2]),
    ("stack_left_cube_on_red_cylinder", ["source_grounding", "stack", "finish"], [0.4, 0.4, 0.2]),
    ("push_left_cube_to_red_cylinder", ["push_contact", "push", "finish"], [0.4, 0.4, 0.2]),
    ("place_right_cube_in_green_bowl", ["source_grounding", "place_in_bowl", "finish"],
     [0.4, 0.4, 0.2]),
    ("r_pick2_via4_to6_short_front", ["source_grounding", "route", "orientation", "finish"],
     [0.24, 0.24, 0.32, 0.2]),
    ("s41_seq_l_bowl_then_r_green_cylinder", ["source_grounding", "source_grounding", "finish"],
     [0.4, 0.4, 0.2]),
])
def test_stage_names_and_weights_follow_the_action(behaviours, label, names, weights):
    graph = goal_graph(behaviours[label])
    order = stage_order(graph)
    assert [goal(graph, n).name for n in order] == names
    assert [goal(graph, n).weight for n in order] == weights


def test_sequences_chain_a_then_b(behaviours):
    graph = goal_graph(behaviours["s41_seq_r_green_cylinder_then_l_bowl"])
    first, second = [goal(graph, n).intent.params for n in stage_order(graph)[:2]]
    assert (first["arm"], first["object"]) == ("right", "green_cylinder")
    assert (second["arm"], second["object"]) == ("left", "red_cube")


def test_nodes_carry_predicates_with_parameters(behaviours):
    graph = goal_graph(behaviours["r_pick2_via4_to6_short_front"])
    route = goal(graph, "route").execution
    assert route.name == "route_footprints"
    assert route.params["waypoints"] == (("via", "yellow_slab"),)  # read-only: tuples
    assert route.to_json()["params"]["waypoints"] == [["via", "yellow_slab"]]
    assert goal(graph, "outcome").execution.params["yaw_deg"] == 0.0
    assert goal(graph, "finish").intent.params["keep"] == (("red_slab", "placed", "right"),)
    assert graph.graph["profile"]["name"] == "default"


def test_the_finish_knows_how_each_handled_object_ends(behaviours):
    keep = {label: goal(goal_graph(behaviours[label]), "finish").intent.to_json()["params"]["keep"]
            for label in ("pickup_left_cube", "push_left_cube_to_red_cylinder",
                          "s41_seq_r_green_cylinder_then_l_bowl")}
    assert keep["pickup_left_cube"] == [["large_blue_cube", "held", "left"]]
    assert keep["push_left_cube_to_red_cylinder"] == [["large_blue_cube", "pushed", "left"]]
    assert keep["s41_seq_r_green_cylinder_then_l_bowl"] == [["green_cylinder", "held", "right"],
                                                            ["red_cube", "held", "left"]]


def test_a_branch_that_asks_for_nothing_is_scored_on_staying_still():
    graph = goal_graph(Behaviour(steps=(), condition=False, branch="otherwise"))
    assert [goal(graph, n).name for n in stage_order(graph)] == ["finish"]


def test_graph_json_is_deterministic(behaviours):
    step = Step(action="pick", arm="left", source="red_cube")
    one = json.dumps(graph_to_dict(goal_graph(Behaviour(steps=(step,)))), sort_keys=True)
    two = json.dumps(graph_to_dict(goal_graph(Behaviour(steps=(step,)))), sort_keys=True)
    assert one == two
    assert json.loads(one)["edges"] == [["source", "finish"]]

"""The oracle's predicates on hand-made arrays (no physics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robofollow.oracle import predicates as P


def test_gripper_events_are_transitions_with_frame_zero_counting_when_closed():
    signal = np.array([1.0, 0.9, 0.3, 0.2, 0.8, 0.1, 0.1, 1.0])
    assert P.falls(signal, 0.35).tolist() == [2, 5]
    assert P.rises(signal, 0.7).tolist() == [4, 7]
    assert P.falls(np.array([0.2, 0.2, 1.0, 0.3]), 0.35).tolist() == [0, 3]
    assert P.rises(np.array([1.0, 1.0]), 0.7).tolist() == []  # open from the start: no event
    assert P.first(np.array([2, 5, 9]), 3) == 5 and P.first(np.array([2]), 3) is None


def test_first_stay_needs_a_full_run_or_a_run_to_the_end():
    mask = np.array([0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1], dtype=bool)
    assert P.first_stay(mask, 0, 3) == 4
    assert P.first_stay(mask, 0, 5) == 9  # only the run to the end is long enough
    assert P.first_stay(mask, 5, 2) == 5
    assert P.first_stay(np.zeros(5, dtype=bool), 0, 2) is None


@given(st.lists(st.booleans(), min_size=1, max_size=40), st.integers(1, 10), st.integers(0, 39))
def test_first_stay_matches_its_definition(values, frames, after):
    mask = np.array(values)
    after = min(after, len(mask) - 1)
    expected = next((t for t in range(after, len(mask))
                     if mask[t:t + min(frames, len(mask) - t)].all()), None)
    assert P.first_stay(mask, after, frames) == expected


def test_relations_in_a_cone_and_within_reach():
    offsets = np.array([[-0.08, 0.0], [-0.08, 0.07], [-0.06, 0.09], [-0.13, 0.0], [0.0, 0.0]])
    assert P.in_cone(offsets, (-1.0, 0.0), 0.12, 45.0).tolist() == [True, True, False, False, False]
    assert P.in_cone(offsets, None, 0.12, 45.0).tolist() == [True, True, True, False, False]


def test_stacking_and_bowls():
    target = np.array([[0.0, 0.0, 0.765]] * 3)
    source = np.array([[0.01, 0.0, 0.81], [0.05, 0.0, 0.81], [0.0, 0.0, 0.78]])
    assert P.stacked(source, target, 0.045, 0.03, 0.005).tolist() == [True, False, False]
    bowl = np.array([[0.0, 0.0, 0.76]] * 3)
    assert P.in_bowl(source, bowl, 0.04, 0.06).tolist() == [True, False, True]


def test_push_progress_counts_only_inside_the_cone():
    moves = np.array([[0.03, 0.0], [0.02, 0.019], [0.0, 0.03], [-0.03, 0.0]])
    got = P.progress(moves, np.array([1.0, 0.0]), 45.0)
    np.testing.assert_allclose(got, [0.03, 0.02, 0.0, 0.0])


def test_crossings_find_a_line_jumped_between_frames():
    path = np.array([[-0.10, -0.10], [-0.02, -0.12], [0.04, -0.18], [0.05, -0.18]])
    frames, ys = P.crossings(path, 0.01, 0.01)
    assert frames.tolist() == [1] and ys[0] == pytest.approx(-0.15)
    frames, ys = P.crossings(path, 0.045, 0.01)
    assert frames.tolist() == [2, 3]


def test_footprints_boxes_and_distances():
    path = np.array([[0.0, 0.0], [0.02, 0.0], [0.0, 0.03]])
    centre = np.zeros((3, 2))
    assert P.over_footprint(path, centre, (0.018, 0.028)).tolist() == [True, False, False]
    points = np.array([[0.0, 0.0, 0.8], [0.3, 0.0, 0.8]])
    assert P.inside_box(points, ((-0.2, 0.15), (-0.15, 0.15), (0.74, 1.0))).tolist() == [True, False]
    assert P.within(points, np.array([0.0, 0.0, 0.85]), 0.10).tolist() == [True, False]
    assert P.nearest(np.array([[0.0, 0.0], [0.1, 0.0], [0.05, 0.0]]), np.array([0.09, 0.0]),
                     np.array([0, 2])) == (2, pytest.approx(0.04))


@pytest.mark.parametrize("angle, target, error", [
    (0.0, 0.0, 0.0), (math.pi, 0.0, 0.0), (math.radians(170), 0.0, math.radians(10)),
    (math.radians(100), math.pi / 2, math.radians(10)), (-math.pi / 2, math.pi / 2, 0.0),
    (math.radians(45), 0.0, math.radians(45)), (math.pi / 2, 0.0, math.pi / 2)])
def test_axis_error_is_modulo_half_a_turn(angle, target, error):
    assert P.axis_error(angle, target) == pytest.approx(error, abs=1e-9)

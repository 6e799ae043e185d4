"""The oracle's predicates on hand-made arrays (no physics)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from robofollow.oracle import predicates as P


def test_falls_are_transitions_with_frame_zero_counting_when_closed():
    signal = np.array([1.0, 0.9, 0.3, 0.2, 0.8, 0.1, 0.1, 1.0])
    assert P.falls(signal, 0.35).tolist() == [2, 5]
    assert P.falls(np.array([0.2, 0.2, 1.0, 0.3]), 0.35).tolist() == [0, 3]
    assert P.first_true(np.array([0, 1, 0, 1], dtype=bool), 2) == 3
    assert P.first_true(np.array([0, 1, 0], dtype=bool), 2) is None


def test_holds_for_needs_a_full_run_or_a_run_to_the_end():
    mask = np.array([0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1], dtype=bool)
    assert P.first_true(P.holds_for(mask, 3)) == 4
    assert P.first_true(P.holds_for(mask, 5)) == 9  # only the run to the end is long enough
    assert P.first_true(P.holds_for(mask, 2), 5) == 5
    assert not P.holds_for(np.zeros(5, dtype=bool), 2).any()


@given(st.lists(st.booleans(), min_size=1, max_size=40), st.integers(1, 10))
def test_holds_for_matches_its_definition(values, frames):
    mask = np.array(values)
    expected = [bool(mask[t:t + frames].all()) for t in range(len(mask))]
    assert P.holds_for(mask, frames).tolist() == expected


@given(st.lists(st.integers(-1000, 1000), min_size=1, max_size=30), st.integers(1, 6),
       st.floats(0.0, 0.05))
def test_steady_matches_its_definition(values, frames, radius):
    points = np.array(values)[:, None] / 10000  # positions on a 0.1 mm grid
    expected = [bool(np.abs(points[t:t + frames] - points[t]).max() <= radius)
                for t in range(len(points))]
    assert P.steady(points, frames, radius).tolist() == expected


def test_directions_in_a_cone():
    offsets = np.array([[-0.08, 0.0], [-0.08, 0.07], [-0.06, 0.09], [-0.30, 0.0], [0.0, 0.0]])
    assert P.in_cone(offsets, (-1.0, 0.0), 45.0).tolist() == [True, True, False, True, False]


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


def test_a_path_is_over_a_footprint_when_its_point_is():
    path = np.array([[0.0, 0.0], [0.02, 0.0], [0.0, 0.03], [0.018, 0.028]])
    assert P.over_footprint(path, np.zeros((4, 2)), np.array([0.018, 0.028])).tolist() == [
        True, False, False, True]


def test_inside_box():
    points = np.array([[0.0, 0.0, 0.8], [0.3, 0.0, 0.8]])
    assert P.inside_box(points, ((-0.2, 0.15), (-0.15, 0.15), (0.74, 1.0))).tolist() == [True,
                                                                                         False]


@pytest.mark.parametrize("angle, target, error", [
    (0.0, 0.0, 0.0), (math.pi, 0.0, 0.0), (math.radians(170), 0.0, math.radians(10)),
    (math.radians(100), math.pi / 2, math.radians(10)), (-math.pi / 2, math.pi / 2, 0.0),
    (math.radians(45), 0.0, math.radians(45)), (math.pi / 2, 0.0, math.pi / 2)])
def test_axis_error_is_modulo_half_a_turn(angle, target, error):
    assert P.axis_error(angle, target) == pytest.approx(error, abs=1e-9)

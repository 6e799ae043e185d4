"""Scoring a recorded trajectory as one compiled episode: check that it was recorded in the
episode's layout, then score it with the scene's training behaviours as 'did instead'
candidates."""

from __future__ import annotations

import dataclasses

from robofollow.benchmark.episode import Benchmark, EpisodeSetup
from robofollow.compiler.planning.profile import DEFAULT_PROFILE, ScoringProfile
from robofollow.errors import RoboFollowError
from robofollow.oracle.results import EpisodeScore
from robofollow.oracle.score import score
from robofollow.trajectory import Trajectory


class RecordingMismatchError(RoboFollowError):
    """A trajectory that was not recorded in the episode's scene layout."""


def score_recording(compiled: Benchmark, episode: EpisodeSetup, trajectory: Trajectory,
                    profile: ScoringProfile = DEFAULT_PROFILE) -> EpisodeScore:
    scene = compiled.spec.scenes[episode.scene]
    layout = trajectory.meta.get("layout")
    if layout is not None and layout != episode.layout:
        raise RecordingMismatchError(f"the trajectory was recorded in layout {layout!r}, but "
                                     f"{episode.id} uses layout {episode.layout!r}")
    expected = set(scene.layouts[episode.layout].placed)
    if set(trajectory.bodies) != expected:
        raise RecordingMismatchError(
            f"the trajectory's bodies ({', '.join(sorted(trajectory.bodies))}) are not those "
            f"of {episode.scene} layout {episode.layout} ({', '.join(sorted(expected))})")
    if layout is None:  # recorded elsewhere without a layout name: the episode's, checked above
        trajectory = dataclasses.replace(trajectory, meta={**trajectory.meta,
                                                           "layout": episode.layout})
    return score(episode.behaviour, trajectory, scene, profile,
                 episode=episode.id, candidates=compiled.candidates(episode.scene))

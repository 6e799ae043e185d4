"""Per-episode references an evaluation record carries, computed symbolically on the
episode's layout (nominal poses):

chance            a language-blind guess: Intent and completion expected from performing,
                  uniformly at random, one of the scene's training behaviours the layout allows
                  (what the blind policy does); among K behaviours that do not pass each
                  other's checks its completion is 1/K.
followed_intent   the Intent earned by perfectly following the instruction the policy was
                  given as the expert understands it (1 for the episode's own; with
                  --instruction-mode shuffled, the credit of the stages the other task shares;
                  None when it does not ground).
"""

from __future__ import annotations

from robofollow.benchmark.episode import Benchmark, Episode
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.eval.policies.reference import understood
from robofollow.oracle.chance import available_behaviours, guessing, intent_if_performed


def references(compiled: Benchmark, episode: Episode, instruction: str) -> dict:
    scene = compiled.spec.scenes[episode.scene]
    world = World(scene, episode.layout)
    asked = episode.behaviour
    training = compiled.candidates(scene.id)
    chance = guessing(asked, [training[label] for label in available_behaviours(world, training)])
    try:
        followed = intent_if_performed(asked, understood(instruction, world, scene, training))
    except RoboFollowError:
        followed = None
    return {"chance": chance, "followed_intent": followed}

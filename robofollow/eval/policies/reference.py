"""Reference policies: the bounds a real policy is read against.

expert  perfect understanding and execution: parses the instruction it is given, grounds it on
        the current layout (privileged object poses) and executes the expert's plan (an arm the
        instruction does not name: see `understood`). It uses no episode metadata, so given
        another task's instruction it performs that one perfectly.
blind   the language-blind control: ignores the instruction and performs, uniformly at random
        (seeded by the episode), one of the scene's training behaviours that the current
        layout allows; its Intent is the chance level.
noop    holds the arms at home.
random  random joint-space motion around home (seeded by the episode).
"""

from __future__ import annotations

import numpy as np

from robofollow.compiler.language.parser import parse
from robofollow.compiler.planning.motions import Repertoire
from robofollow.compiler.planning.plans import plan
from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.grounding import ground
from robofollow.compiler.scene.spec import Scene
from robofollow.compiler.scene.world import World
from robofollow.errors import RoboFollowError
from robofollow.eval.policies.policy import Privileged
from robofollow.oracle.chance import available_behaviours
from robofollow.sim import CHUNK, robot
from robofollow.sim.expert import Expert

RANDOM_REACH = 0.5  # rad: the random policy's targets lie this far around home at most
RANDOM_MOVE_STEPS = 25  # control steps per random motion


class _Scripted:
    """Plays a precomputed action sequence in chunks, then holds the last target."""
    uses = frozenset({"privileged"})
    chunk = CHUNK  # actions per call

    def __init__(self):
        self.actions: np.ndarray | None = None
        self.cursor = 0

    def reset(self) -> None:
        self.actions, self.cursor = None, 0

    def act(self, observation: dict) -> np.ndarray:
        if self.actions is None:
            self.actions = self.script(observation)
        chunk = self.actions[self.cursor:self.cursor + self.chunk]
        self.cursor += len(chunk)
        return chunk if len(chunk) else np.repeat(self.actions[-1:], self.chunk, axis=0)

    def script(self, observation: dict) -> np.ndarray:
        raise NotImplementedError


def _perform(behaviour: Behaviour, privileged: Privileged) -> np.ndarray:
    return Expert(privileged.sim).actions(plan(behaviour, privileged.world))


def _hold() -> np.ndarray:
    return robot.home_state()[None]


def understood(instruction: str, world: World, scene: Scene,
               training: dict[str, Behaviour]) -> Behaviour:
    """What following `instruction` on `world` means: its grounded behaviour, where an arm is
    not named, the one arm the scene's training uses for that step, else the arm nearer the
    object. Raises RoboFollowError when the instruction does not parse or ground."""
    behaviour = ground(parse(instruction), world)
    if all(step.arm for step in behaviour.steps):
        return behaviour
    known = Repertoire(scene, training)
    steps = tuple(step if step.arm else step.model_copy(update={
        "arm": known.arm_for(behaviour, index, world) or _nearer_arm(world, step.source)})
        for index, step in enumerate(behaviour.steps))
    return behaviour.model_copy(update={"steps": steps})


def _nearer_arm(world: World, body: str) -> str:
    return min(workspace.ARMS, key=lambda arm: abs(world.poses[body].x - workspace.BASE_XY[arm][0]))


class ExpertPolicy(_Scripted):
    uses = frozenset({"instruction", "privileged"})

    def script(self, observation: dict) -> np.ndarray:
        privileged = observation["privileged"]
        try:
            behaviour = understood(observation["instruction"], privileged.world,
                                   privileged.scene, privileged.training)
        except RoboFollowError:  # not an instruction it understands here: it stays at home
            return _hold()
        return _perform(behaviour, privileged)


class BlindPolicy(_Scripted):
    def script(self, observation: dict) -> np.ndarray:
        privileged = observation["privileged"]
        labels = available_behaviours(privileged.world, privileged.training)
        if not labels:
            return _hold()
        label = labels[int(np.random.default_rng(privileged.seed).integers(len(labels)))]
        try:
            return _perform(privileged.training[label], privileged)
        except RoboFollowError:
            return _hold()


class NoopPolicy:
    uses = frozenset()

    def reset(self) -> None:
        pass

    def act(self, observation: dict) -> np.ndarray:
        return np.repeat(_hold(), CHUNK, axis=0)


class RandomPolicy(_Scripted):
    def script(self, observation: dict) -> np.ndarray:
        rng = np.random.default_rng(observation["privileged"].seed)
        low, high = robot.ACTION_LOW, robot.ACTION_HIGH
        home = robot.home_state()
        current, actions = home, []
        for _ in range(CHUNK * 10 // RANDOM_MOVE_STEPS):
            target = np.clip(home + rng.uniform(-RANDOM_REACH, RANDOM_REACH, home.shape),
                             low, high)
            target[[6, 13]] = rng.integers(0, 2, 2)  # grippers open or closed
            actions += list(np.linspace(current, target, RANDOM_MOVE_STEPS + 1)[1:])
            current = target
        return np.array(actions)


REFERENCE_POLICIES = {"expert": ExpertPolicy, "blind": BlindPolicy, "noop": NoopPolicy,
                      "random": RandomPolicy}

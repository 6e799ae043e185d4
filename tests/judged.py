"""Scripted imperfect behaviours for the judged catalogue, built from the project's own
planner (plan points, with its approach heights) and IK (the expert turns points into joint
targets), recorded in MuJoCo in an episode's layout and seed, then scored as that episode.

A Script chains building blocks, each continuing from where the last one left the arms:

    Script("scene1/L0/...").pick("right", "yellow_block_3").put_back().perform().score()
"""

from __future__ import annotations

import math

import numpy as np

from robofollow.compiler.planning.plans import (
    CLOSED,
    LIFT,
    OPEN,
    PRE_GRASP,
    PRE_PLACE,
    PUSH_HEIGHT,
    PUSH_SPEED,
    RETREAT,
    STACK_CLEARANCE,
    TABLE_CLEARANCE,
    Plan,
    PlanPoint,
    plan,
    push_points,
)
from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.behaviour import Behaviour, Step
from robofollow.oracle.results import EpisodeScore
from robofollow.scoring import score_recording
from robofollow.sim import robot
from robofollow.sim.expert import Expert
from robofollow.sim.rollout import Rollout
from robofollow.sim.stage import Stage
from robofollow.trajectory import Trajectory
from tests.sim_helpers import shipped

SETTLE = 40  # control steps held at the end of every script (the evaluation's budget holds)


class Script:
    """A scripted motion in one episode's layout and seed: an episode of the release the
    judged catalogue was recorded on, or of `benchmark` (a working compile's generated
    tasks)."""

    def __init__(self, episode_id: str, benchmark=None):
        self.benchmark = benchmark or shipped()
        self.record = self.benchmark.record(episode_id)
        self.scene = self.benchmark.spec.scenes[self.record.scene]
        self.rollout = Rollout(self.benchmark, Stage(64, 48), self.record, render=False)
        self.sim, self.world = self.rollout.sim, self.rollout.world
        self.asked = self.record.behaviour
        self.expert = Expert(self.sim)
        self.actions: list[np.ndarray] = []
        self.command = robot.home_state()
        self.held: dict[str, str] = {}  # arm -> the body it last closed on

    # -- where things are -----------------------------------------------------------------

    def at(self, body: str) -> tuple[float, float, float]:
        pose = self.world.poses[body]
        return (pose.x, pose.y, pose.z)

    def half(self, body: str) -> tuple[float, float, float]:
        return self.world.bodies[body].half_extents

    # -- building blocks --------------------------------------------------------------------

    def points(self, points: list[PlanPoint] | tuple[PlanPoint, ...], hold: int = 0) -> "Script":
        """Execute plan points from where the arms are now."""
        actions = self.expert.actions(Plan(points=tuple(points)), start=self.command, hold=hold)
        if len(actions):
            self.actions += list(actions)
            self.command = actions[-1].copy()
        return self

    def perform(self, behaviour: Behaviour | None = None, edit=None) -> "Script":
        """The expert's plan of a behaviour (default: the asked one), its points changed by
        `edit` (a function of the list of points)."""
        points = list(plan(behaviour or self.asked, self.world).points)
        return self.points(edit(points) if edit else points)

    def variant(self, **change) -> Behaviour:
        """The asked behaviour with every step changed (arm, source, relation, target, ...)."""
        steps = tuple(s.model_copy(update=change) for s in self.asked.steps)
        return Behaviour(steps=steps)

    def wait(self, frames: int) -> "Script":
        self.actions += [self.command.copy() for _ in range(frames)]
        return self

    def move(self, arm: str, position, gripper: float | None = None,
             yaw: float = 0.0) -> "Script":
        if gripper is None:
            gripper = float(self.command[7 * workspace.ARMS.index(arm) + 6])
        return self.points([PlanPoint(name="move", arm=arm, position=tuple(position),
                                      gripper=gripper, yaw_degrees=yaw)])

    def home(self, arm: str, gripper: float | None = None) -> "Script":
        if gripper is None:
            gripper = float(self.command[7 * workspace.ARMS.index(arm) + 6])
        return self.points([PlanPoint(name="home", arm=arm, position=None, gripper=gripper)])

    def grip(self, arm: str, opening: float) -> "Script":
        """Set the gripper command where the arm is."""
        index = 7 * workspace.ARMS.index(arm) + 6
        for value in np.linspace(self.command[index], opening, 11)[1:]:
            self.command[index] = value
            self.actions.append(self.command.copy())
        return self

    def pick(self, arm: str, body: str, lift: float = LIFT, closed: float = CLOSED) -> "Script":
        """Approach from above, close on the body and lift it."""
        x, y, z = self.at(body)
        self.held[arm] = body
        return (self.move(arm, (x, y, z + PRE_GRASP), OPEN).move(arm, (x, y, z))
                .grip(arm, closed).move(arm, (x, y, z + lift)))

    def put(self, arm: str, x: float, y: float, above: float = TABLE_CLEARANCE,
            on: str | None = None, yaw: float = 0.0, release: bool = True) -> "Script":
        """Set the held body down with its centre over (x, y), its bottom `above` metres over
        the table (or over the top of `on`), turned by `yaw`; release and retreat."""
        body = self.held[arm]
        base = self.world.top(on) + STACK_CLEARANCE if on else self.world.table
        z = base + self.half(body)[2] + above
        self.move(arm, (x, y, z + PRE_PLACE), yaw=yaw).move(arm, (x, y, z), yaw=yaw)
        if release:
            self.grip(arm, OPEN).move(arm, (x, y, z + RETREAT), yaw=yaw)
        return self

    def take_again(self, arm: str, body: str, position, yaw: float = 0.0,
                   lift: float = LIFT, opening: float = OPEN) -> "Script":
        """Grasp `body` again where it was set down (its centre then at `position`, turned by
        `yaw`), the fingers coming down `opening` apart, and lift it `lift` metres."""
        x, y, z = position
        self.held[arm] = body
        return (self.move(arm, (x, y, z + PRE_GRASP), opening, yaw).move(arm, (x, y, z), yaw=yaw)
                .grip(arm, CLOSED).move(arm, (x, y, z + lift), yaw=yaw))

    def put_back(self, arm: str) -> "Script":
        """Set the held body down where it was taken from, release, go home."""
        x, y, _ = self.at(self.held[arm])
        return self.put(arm, x, y).home(arm, OPEN)

    def close_at(self, arm: str, position) -> "Script":
        """Shut the fingers in free air at a point, then open them again."""
        return self.move(arm, position, OPEN).grip(arm, CLOSED).grip(arm, OPEN)

    def sweep(self, arm: str, y: float, x_from: float, x_to: float) -> "Script":
        """The closed gripper lowered to push height at one end of a row and moved to the
        other end at the planner's pushing speed, pushing whatever stands in the way; home."""
        z = self.world.table + PUSH_HEIGHT
        yaw = -90.0  # the closed fingers' wide face across the row, as the push planner turns it
        self.move(arm, (x_from, y, z + LIFT), OPEN, yaw).grip(arm, CLOSED)
        self.move(arm, (x_from, y, z), yaw=yaw)
        self.points([PlanPoint(name="sweep", arm=arm, position=(x_to, y, z), gripper=CLOSED,
                               yaw_degrees=yaw, speed=PUSH_SPEED)])
        return self.move(arm, (x_to, y, z + LIFT), yaw=yaw).home(arm)

    def push(self, arm: str, body: str, direction: tuple[float, float]) -> "Script":
        """The planner's push of `body` along a planar direction."""
        return self.points(push_points(self.world, arm, body, direction))

    def shake(self, arm: str, amplitude: float, times: int) -> "Script":
        """Wave the gripper side to side around where it is (the arm's home, say)."""
        index = slice(7 * workspace.ARMS.index(arm), 7 * workspace.ARMS.index(arm) + 6)
        centre = self.command[index].copy()
        for phase in np.linspace(0, 2 * math.pi * times, 12 * times):
            self.command[index] = centre + np.array([amplitude * math.sin(phase), 0, 0, 0, 0, 0])
            self.actions.append(self.command.copy())
        self.command[index] = centre
        self.actions.append(self.command.copy())
        return self

    def edit(self, change) -> "Script":
        """Change every action so far (e.g. the gripper commands a learned policy sends)."""
        self.actions = [change(a.copy()) for a in self.actions]
        self.command = self.actions[-1].copy()
        return self

    # -- results ------------------------------------------------------------------------------

    def trajectory(self) -> Trajectory:
        self.rollout.execute(self.actions + [self.command.copy()] * SETTLE)
        return self.rollout.recorder.trajectory()

    def score(self) -> EpisodeScore:
        return score_recording(self.benchmark, self.record, self.trajectory())


def analog(action: np.ndarray) -> np.ndarray:
    """A learned policy's gripper: 0.4 for closed, 0.65 for open (the fingers still shut on
    a 4 cm block at 0.4 and let go at 0.65)."""
    for column in (6, 13):
        action[column] = 0.4 if action[column] < 0.5 else 0.65
    return action


def released_higher(height: float):
    """A plan edit: set the object down `height` metres higher than planned (a drop)."""
    def edit(points: list[PlanPoint]) -> list[PlanPoint]:
        raised = []
        for point in points:
            if point.name in ("pre_place", "place", "release", "retreat"):
                x, y, z = point.position
                point = point.model_copy(update={"position": (x, y, z + height)})
            raised.append(point)
        return raised
    return edit


def without(*names: str):
    """A plan edit: leave out the points with these names (e.g. 'release', 'home')."""
    def edit(points: list[PlanPoint]) -> list[PlanPoint]:
        return [p for p in points if p.name not in names]
    return edit


def holding_on(points: list[PlanPoint]) -> list[PlanPoint]:
    """A plan edit: never open the gripper after closing it (held without release)."""
    closed = False
    kept = []
    for point in points:
        closed = closed or point.gripper == CLOSED
        kept.append(point.model_copy(update={"gripper": CLOSED}) if closed else point)
    return kept


def step_of(behaviour: Behaviour) -> Step:
    (step,) = behaviour.steps
    return step

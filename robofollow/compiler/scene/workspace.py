"""Where the robot can work, as geometry: the table, the arm bases, each arm's reach, the
gripper's opening. The simulator builds its robot and table from these numbers; the compiler
uses them to refuse tasks no arm can perform before anything is simulated.

Reach model (a ViperX 300 s grasping top-down): the wrist pivot sits WRIST_TO_GRASP above the
grasp point and must lie within REACH of the shoulder pivot, which sits SHOULDER_HEIGHT above
the arm's base on the table; a point closer than MIN_REACH to the base (in the plane) folds
the arm onto itself.
"""

from __future__ import annotations

import math

ARMS = ("left", "right")
BASE_XY = {"left": (-0.24, -0.38), "right": (0.24, -0.38)}  # m: arm bases, on the table top

TABLE_SIZE = (1.2, 0.7, 0.04)  # m
TABLE_CENTRE_Y = -0.05  # m (the table is centred on x = 0)

SHOULDER_HEIGHT = 0.079 + 0.04805  # m: base -> waist -> shoulder pivot
UPPER_ARM = math.hypot(0.05955, 0.3)  # m: shoulder pivot -> elbow pivot
FOREARM = 0.2 + 0.1  # m: elbow pivot -> wrist pivot
WRIST_TO_GRASP = 0.069744 + 0.13  # m: wrist pivot -> grasp centre, along the gripper
REACH_MARGIN = 0.02  # m: kept short of full stretch (the elbow's limits, IK tolerance)
REACH = UPPER_ARM + FOREARM - REACH_MARGIN
MIN_REACH = 0.08  # m
GRIPPER_OPENING = 0.075  # m: between the open fingers
GRIP_CLEARANCE = 0.01  # m: a gripped body is at least this much narrower than the opening
# The fingers and palm as the simulator builds them (sim/robot.py, sim/templates/scene.xml.j2):
# each finger is a box FINGER_THICKNESS thick along the closing axis whose inner face travels
# GRIPPER_OPENING / 2 from the grasp centre, FINGER_WIDTH wide across it, its tip FINGERTIP_DEPTH
# below the grasp centre; the palm is a box PALM_HALF (along, across the closing axis) whose
# underside is PALM_RISE above the grasp centre.
FINGER_THICKNESS = 0.006  # m
FINGER_WIDTH = 0.024  # m
FINGER_LENGTH = 0.06  # m
FINGERTIP_DEPTH = 0.012  # m
PALM_HALF = (0.046, 0.024)  # m
PALM_RISE = 0.05  # m
DEFAULT_FRICTION = 0.5  # an object's sliding friction when its spec gives none
FIXTURE_FRICTION = 0.8  # a fixture's (labels, bowls) sliding friction


def table_bounds() -> tuple[float, float, float, float]:
    """(x low, x high, y low, y high) of the table top."""
    hx, hy = TABLE_SIZE[0] / 2, TABLE_SIZE[1] / 2
    return -hx, hx, TABLE_CENTRE_Y - hy, TABLE_CENTRE_Y + hy


def reach_problem(arm: str, point: tuple[float, float, float], table: float,
                  slack: float = 0.0) -> str | None:
    """Why a top-down grasp centre at `point`, or anywhere within `slack` of it in the plane,
    is out of `arm`'s reach (None: reachable)."""
    base_x, base_y = BASE_XY[arm]
    planar = math.hypot(point[0] - base_x, point[1] - base_y) + slack
    rise = point[2] + WRIST_TO_GRASP - (table + SHOULDER_HEIGHT)
    stretch = math.hypot(planar, rise)
    if stretch > REACH:
        return (f"the {arm} arm would stretch {100 * stretch:.1f} cm to "
                f"({', '.join(f'{100 * v:.1f}' for v in point)}) cm"
                + (" with the jitter" if slack else "") + f", beyond its {100 * REACH:.1f} cm "
                "reach")
    if planar - 2 * slack < MIN_REACH:
        return (f"({', '.join(f'{100 * v:.1f}' for v in point)}) cm comes "
                f"{100 * (planar - 2 * slack):.1f} cm from the {arm} arm's base, closer than "
                f"{100 * MIN_REACH:g} cm")
    return None

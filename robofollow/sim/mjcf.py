"""Scene layout -> MJCF text (jinja2 template `templates/scene.xml.j2`).

Bodies are placed at their nominal layout positions; an episode moves them to its jittered
start (see episode.py). Movable objects get a free joint and an explicit inertial; fixtures
(labels, bowls) are static. A bowl is a floor disk inside a ring of wall boxes. The floor the
table stands on (FLOOR_HEIGHT; a table height is measured from it) catches a body that falls off
the table; only movable objects collide with it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import jinja2
import numpy as np

from robofollow.compiler.scene import workspace
from robofollow.compiler.scene.spec import (
    BOWL_FLOOR,
    BOWL_SEGMENTS,
    BOWL_WALL,
    TABLE_HEIGHT,
    Body,
    Scene,
)
from robofollow.sim import robot
from robofollow.sim.assets import ARM_MESHES, mesh_dir

TIMESTEP = 0.002  # s: physics step
SPAWN_LIFT = 0.001  # m: movable objects start this far above their resting height
FLOOR_HEIGHT = 0.0  # m: the ground the table stands on (the table top is `table_height` above)


@dataclass(frozen=True)
class CameraSpec:
    name: str
    position: tuple[float, float, float]
    target: tuple[float, float, float]
    fovy: float  # degrees; for an orthographic camera, the view's height in metres
    orthographic: bool = False


CAMERAS = (
    CameraSpec("cam_high", (0.0, -0.52, 1.28), (0.0, -0.06, TABLE_HEIGHT), 48.0),
    CameraSpec("cam_top", (0.0, -0.10, 1.60), (0.0, -0.10, TABLE_HEIGHT), 0.62,
               orthographic=True),
)
WRIST_FOVY = 75.0  # deg


def _fmt(values) -> str:
    return " ".join(f"{float(v):.6g}" for v in values)


def _xyaxes(camera: CameraSpec) -> str:
    forward = np.subtract(camera.target, camera.position)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, (0.0, 0.0, 1.0))
    if np.linalg.norm(right) < 1e-6:  # looking straight down: image right is +x
        right = np.array([1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return _fmt(np.concatenate([right, up]))


def _rgba(body: Body) -> str:
    return _fmt((*body.rgb, 1.0))


def _object(body: Body, position) -> dict:
    hx, hy, hz = body.half_extents
    mass = body.mass or 0.1
    if body.kind == "sphere":
        geom, size, inertia = "sphere", (hx,), [0.4 * mass * hx * hx] * 3
    elif body.kind == "cylinder":
        side = mass * (3 * hx * hx + 4 * hz * hz) / 12
        geom, size, inertia = "cylinder", (hx, hz), [side, side, 0.5 * mass * hx * hx]
    else:
        geom, size = "box", (hx, hy, hz)
        inertia = [mass / 3 * (hy * hy + hz * hz), mass / 3 * (hx * hx + hz * hz),
                   mass / 3 * (hx * hx + hy * hy)]
    sphere = body.kind == "sphere"
    return {"id": body.id, "pos": _fmt(position), "mass": f"{mass:.6g}", "inertia": _fmt(inertia),
            "type": geom, "size": _fmt(size), "rgba": _rgba(body),
            "friction": f"{body.friction or workspace.DEFAULT_FRICTION:.6g}", "rolling": "0.002" if sphere else "0.0001",
            "condim": 6 if sphere else 4}


def _fixture(body: Body, position) -> dict:
    hx, hy, hz = body.half_extents
    if body.kind != "bowl":
        geoms = [{"suffix": "", "type": "box", "pos": "0 0 0", "size": _fmt((hx, hy, hz))}]
    else:
        geoms = [{"suffix": "_floor", "type": "cylinder", "pos": _fmt((0, 0, -hz + BOWL_FLOOR / 2)),
                  "size": _fmt((hx, BOWL_FLOOR / 2))}]
        middle = hx - BOWL_WALL / 2
        half_width = hx * math.tan(math.pi / BOWL_SEGMENTS) + BOWL_WALL / 2
        for i in range(BOWL_SEGMENTS):
            angle = 2 * math.pi * i / BOWL_SEGMENTS
            geoms.append({"suffix": f"_wall{i}", "type": "box",
                          "pos": _fmt((middle * math.cos(angle), middle * math.sin(angle), 0)),
                          "size": _fmt((BOWL_WALL / 2, half_width, hz)),
                          "euler": _fmt((0, 0, angle))})
    return {"id": body.id, "pos": _fmt(position), "rgba": _rgba(body), "geoms": geoms,
            "friction": f"{workspace.FIXTURE_FRICTION:.6g}"}


@lru_cache(maxsize=1)
def _template() -> jinja2.Template:
    environment = jinja2.Environment(loader=jinja2.PackageLoader("robofollow.sim", "templates"),
                                     undefined=jinja2.StrictUndefined, autoescape=False)
    return environment.get_template("scene.xml.j2")


def scene_xml(scene: Scene, layout: str, width: int = 320, height: int = 240) -> str:
    """The MJCF of one layout of a scene, bodies at their nominal positions in their colours
    there."""
    placed = scene.layouts[layout].placed
    objects, fixtures = [], []
    for name, body in scene.bodies_in(layout).items():
        where = placed[name]
        if body.fixture:
            fixtures.append(_fixture(body, (where.x, where.y, where.z)))
        else:
            objects.append(_object(body, (where.x, where.y, where.z + SPAWN_LIFT)))
    half = np.multiply(workspace.TABLE_SIZE, 0.5)
    table = {"x": 0.0, "y": workspace.TABLE_CENTRE_Y, "z": scene.table_height - half[2],
             "hx": half[0], "hy": half[1], "hz": half[2]}
    base_quat = _fmt((math.cos(robot.BASE_YAW / 2), 0, 0, math.sin(robot.BASE_YAW / 2)))
    arms = [{"side": side, "quat": base_quat,
             "pos": _fmt((*workspace.BASE_XY[side], scene.table_height))}
            for side in workspace.ARMS]
    cameras = [{"name": c.name, "pos": _fmt(c.position), "xyaxes": _xyaxes(c), "fovy": c.fovy,
                "orthographic": c.orthographic} for c in CAMERAS]
    return _template().render(
        scene=scene.id, layout=layout, mesh_dir=str(mesh_dir()), timestep=TIMESTEP,
        offwidth=max(width, 640), offheight=max(height, 480), meshes=ARM_MESHES,
        table=table, arms=arms, cameras=cameras, arm_joints=robot.ARM_JOINTS,
        finger_travel=robot.FINGER_TRAVEL, tcp_offset=robot.TCP_OFFSET, finger=robot.FINGER,
        palm=robot.PALM, wrist_fovy=WRIST_FOVY, objects=objects, fixtures=fixtures,
        floor_height=FLOOR_HEIGHT)

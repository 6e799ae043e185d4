"""A picture of a layout: the head camera beside a labelled top view."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from robofollow.compiler.scene.spec import Scene
from robofollow.sim.cameras import Cameras
from robofollow.sim.mjcf import CAMERAS
from robofollow.sim.simulation import Simulation

_TOP = next(c for c in CAMERAS if c.name == "cam_top")


def top_view_pixel(x: float, y: float, width: int, height: int) -> tuple[float, float]:
    """Where a world point on the table appears in the orthographic top view."""
    scale = height / _TOP.fovy  # pixels per metre
    return (width / 2 + (x - _TOP.position[0]) * scale,
            height / 2 - (y - _TOP.position[1]) * scale)


def layout_picture(scene: Scene, layout: str, seed: int | None = None, width: int = 640,
                   height: int = 480) -> Image.Image:
    """Head camera (left) and a top view with every body's name (right), after settling."""
    sim = Simulation(scene, layout, width, height)
    world = sim.reset(seed)
    with Cameras(sim, width, height) as cameras:
        head, top = cameras.render("cam_high"), cameras.render("cam_top")
    picture = Image.fromarray(np.concatenate([head, top], axis=1))
    draw = ImageDraw.Draw(picture)
    font = ImageFont.load_default(size=max(10, height // 40))
    for body, pose in world.poses.items():
        u, v = top_view_pixel(pose.x, pose.y, width, height)
        half = scene.bodies[body].half_extents[1] * height / _TOP.fovy
        draw.text((width + u, v + half + 2), body, fill=(255, 255, 255), font=font,
                  anchor="mt", stroke_width=2, stroke_fill=(0, 0, 0))
    draw.text((8, 8), f"{scene.id} / {layout}" + (f" (seed {seed})" if seed is not None else ""),
              fill=(255, 255, 255), font=font, stroke_width=2, stroke_fill=(0, 0, 0))
    return picture

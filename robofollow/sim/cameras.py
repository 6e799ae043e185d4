"""Rendering the three observation cameras (and the top view) with one offscreen renderer."""

from __future__ import annotations

import mujoco
import numpy as np

from robofollow.errors import RoboFollowError
from robofollow.sim.simulation import Simulation

CAMERA_NAMES = ("cam_high", "cam_left_wrist", "cam_right_wrist")
IMAGE_WIDTH, IMAGE_HEIGHT = 320, 240  # what an evaluation renders (datasets may differ)


class RenderingError(RoboFollowError):
    """No OpenGL context for offscreen rendering."""


class Cameras:
    """One mujoco.Renderer per simulation; close() it (or use `with`) when done."""

    def __init__(self, sim: Simulation, width: int = IMAGE_WIDTH,
                 height: int = IMAGE_HEIGHT):
        self.sim, self.width, self.height = sim, width, height
        try:
            self.renderer = mujoco.Renderer(sim.model, height, width)
        except mujoco.FatalError as error:
            raise RenderingError(
                f"MuJoCo cannot render ({error}). Headless rendering needs Mesa EGL (./setup.sh "
                "installs it) and MUJOCO_GL=egl set before mujoco is first imported (importing "
                "robofollow first does that)") from None

    def render(self, camera: str) -> np.ndarray:
        self.renderer.update_scene(self.sim.data, camera)
        return self.renderer.render()

    def project(self, camera: str, point) -> tuple[float, float] | None:
        """Pixel (column, row) where a world point appears in a perspective camera's image,
        or None when it is behind the camera."""
        model, data = self.sim.model, self.sim.data
        index = model.camera(camera).id
        rotation = data.cam_xmat[index].reshape(3, 3)
        x, y, z = rotation.T @ (np.asarray(point, dtype=float) - data.cam_xpos[index])
        if z >= 0:  # cameras look along their -z axis
            return None
        focal = self.height / 2 / np.tan(np.radians(model.cam_fovy[index]) / 2)
        return self.width / 2 + focal * x / -z, self.height / 2 - focal * y / -z

    def images(self) -> dict[str, np.ndarray]:
        """(height, width, 3) uint8 images of cam_high, cam_left_wrist, cam_right_wrist."""
        return {name: self.render(name) for name in CAMERA_NAMES}

    def close(self) -> None:
        self.renderer.close()

    def __enter__(self) -> "Cameras":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def side_by_side(images: dict[str, np.ndarray]) -> np.ndarray:
    """The three camera images in one row."""
    return np.concatenate([images[name] for name in CAMERA_NAMES], axis=1)

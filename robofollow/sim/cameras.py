"""Rendering the three observation cameras (and the top view) with one offscreen renderer."""

from __future__ import annotations

import mujoco
import numpy as np

from robofollow.sim.simulation import Simulation

CAMERA_NAMES = ("cam_high", "cam_left_wrist", "cam_right_wrist")


class Cameras:
    """One mujoco.Renderer per simulation; close() it (or use `with`) when done."""

    def __init__(self, sim: Simulation, width: int = 320, height: int = 240):
        self.sim, self.width, self.height = sim, width, height
        self.renderer = mujoco.Renderer(sim.model, height, width)

    def render(self, camera: str) -> np.ndarray:
        self.renderer.update_scene(self.sim.data, camera)
        return self.renderer.render()

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

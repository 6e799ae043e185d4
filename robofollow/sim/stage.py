"""The simulation (and its cameras) of one layout at a time, reused while the layout stays:
building a model and a renderer costs far more than resetting them."""

from __future__ import annotations

from robofollow.compiler.scene.spec import Scene
from robofollow.sim.cameras import IMAGE_HEIGHT, IMAGE_WIDTH, Cameras
from robofollow.sim.simulation import Simulation


class Stage:
    """Close it (or use `with`) when done: the renderer holds an OpenGL context."""

    def __init__(self, width: int = IMAGE_WIDTH, height: int = IMAGE_HEIGHT):
        self.width, self.height = width, height
        self.sim: Simulation | None = None
        self.cameras: Cameras | None = None

    def simulation(self, scene: Scene, layout: str, render: bool = False) -> Simulation:
        """The layout's simulation, built only when the layout changes; with `render`, its
        cameras too (`self.cameras`)."""
        if self.sim is None or (self.sim.scene.id, self.sim.layout) != (scene.id, layout):
            self.close()
            self.sim = Simulation(scene, layout, self.width, self.height)
        if render and self.cameras is None:
            self.cameras = Cameras(self.sim, self.width, self.height)
        return self.sim

    def close(self) -> None:
        if self.cameras is not None:
            self.cameras.close()
        self.sim, self.cameras = None, None

    def __enter__(self) -> "Stage":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

"""A Python policy behind a server, whatever the protocol: it turns the wire's observations
back into the harness's and, for a privileged (reference) policy, rebuilds the episode's start
from {scene, layout, seed} (deterministic, so it sees what the client's simulation holds)."""

from __future__ import annotations

from importlib.metadata import version

import numpy as np

from robofollow.build import Compiled
from robofollow.eval.loading import load_policy
from robofollow.eval.policy import Privileged
from robofollow.sim.stage import Stage


class ServedPolicy:
    def __init__(self, compiled: Compiled, policy_spec: str):
        self.compiled, self.policy, self.spec = compiled, load_policy(policy_spec), policy_spec
        self.stage = Stage()
        self.start: tuple | None = None
        self.privileged: Privileged | None = None

    @property
    def metadata(self) -> dict:
        """What a RoboFollow client learns of the server: version and the parts used."""
        return {"robofollow": {"version": version("robofollow"),
                               "uses": sorted(self.policy.uses)}, "policy": self.spec}

    def reset(self) -> None:
        self.policy.reset()
        self.start = None

    def act(self, state, instruction: str, images: dict | None, privileged: dict | None,
            step: int = 0) -> np.ndarray:
        """`images`: {camera: (H, W, 3) uint8}; `privileged`: {scene, layout, seed}."""
        obs = {"state": np.asarray(state, dtype=np.float32), "instruction": instruction,
               "step": step}
        if images is not None:
            obs["images"] = images
        if "privileged" in self.policy.uses and privileged is not None:
            obs["privileged"] = self._privileged(privileged)
        return np.asarray(self.policy.act(obs), dtype=np.float32)

    def _privileged(self, message: dict) -> Privileged:
        start = (message["scene"], message["layout"], message["seed"])
        if start != self.start:
            scene = self.compiled.spec.scenes[start[0]]
            sim = self.stage.simulation(scene, start[1])
            world = sim.reset(start[2])
            self.privileged = Privileged(sim, world, scene, self.compiled.candidates(scene.id),
                                         start[2])
            self.start = start
        return self.privileged

    def close(self) -> None:
        self.stage.close()


def privileged_message(privileged: Privileged) -> dict:
    """The start a served reference policy rebuilds: {scene, layout, seed}."""
    return {"scene": privileged.scene.id, "layout": privileged.sim.layout,
            "seed": privileged.seed}

"""The Gymnasium ids, registered on `import robofollow`; nothing is compiled or simulated (and
MuJoCo is not imported) until `gymnasium.make`.

    RoboFollow-v0                    the current release's episodes
    RoboFollow-Scene1-v0, ...        one scene's episodes (one id per built-in scene)

`gymnasium.make`'s keyword arguments go to RoboFollowEnv (episode, level, scene, release,
specs, width, height, max_steps, render_mode). Episodes are truncated after MAX_STEPS control steps, the
benchmark's action budget; for another budget give both max_steps=N and max_episode_steps=N.
"""

from __future__ import annotations

import re
from pathlib import Path

from gymnasium.envs.registration import register, registry

from robofollow.resources import builtin_specs
from robofollow.sim import MAX_STEPS

ENTRY_POINT = "robofollow.sim.env:RoboFollowEnv"
_SCENE = re.compile(r"^\s*scene\s+(\w+)", re.MULTILINE)  # a spec's `scene NAME "title" {`


def builtin_scenes() -> list[str]:
    """The scene ids the built-in spec files define, read without compiling them."""
    return [name for file in sorted(builtin_specs().rglob("*.rf"))
            for name in _SCENE.findall(_text(file))]


def _text(file: Path) -> str:
    try:
        return file.read_text(encoding="utf-8", errors="replace")
    except OSError:  # (`import robofollow` must not fail on it: the compile reports it)
        return ""


def env_ids() -> dict[str, dict]:
    """Each id with the RoboFollowEnv keyword arguments it stands for."""
    ids = {"RoboFollow-v0": {}}
    ids.update({f"RoboFollow-{scene[:1].upper()}{scene[1:]}-v0": {"scene": scene}
                for scene in builtin_scenes()})
    return ids


def register_envs() -> None:
    """Register every id (once: ids already registered are left as they are)."""
    for env_id, kwargs in env_ids().items():
        if env_id not in registry:
            register(id=env_id, entry_point=ENTRY_POINT, kwargs=kwargs,
                     max_episode_steps=MAX_STEPS)

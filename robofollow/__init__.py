"""RoboFollow: measure whether robot policies really follow language instructions."""

import os

# Headless rendering: MuJoCo picks its GL backend when it is first imported, so the default
# (Mesa EGL) is set here, before any RoboFollow module imports it. MUJOCO_GL=osmesa also works.
os.environ.setdefault("MUJOCO_GL", "egl")

from robofollow.sim.registration import register_envs  # noqa: E402

register_envs()  # the Gymnasium ids (MuJoCo is imported, and the specs compiled, on make)

"""RoboFollow: measure whether robot policies really follow language instructions."""

import os

# Headless rendering: MuJoCo picks its GL backend when it is first imported, so the default
# (Mesa EGL) is set here, before any RoboFollow module imports it. MUJOCO_GL=osmesa also works.
os.environ.setdefault("MUJOCO_GL", "egl")

"""MuJoCo world: scene building, the bimanual robot, IK, the scripted expert, the env.

Rendering is headless: MUJOCO_GL defaults to EGL (Mesa) unless the caller chose a backend.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")

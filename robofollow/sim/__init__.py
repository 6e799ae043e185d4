"""MuJoCo world: scene building, the bimanual robot, IK, the scripted expert, the env."""

MAX_STEPS = 500  # control steps per episode (upstream's 10 chunks x 50 actions)
CHUNK = 50  # actions per chunk: what a reference policy returns and the harness executes per call

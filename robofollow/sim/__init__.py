"""MuJoCo world: scene building, the bimanual robot, IK, the scripted expert, the env."""

MAX_STEPS = 500  # control steps per env episode (upstream's 10 chunks x 50 actions)

"""MuJoCo world: scene building, the bimanual robot, IK, the scripted expert, the env."""

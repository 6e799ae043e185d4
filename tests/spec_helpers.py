"""A small valid spec and edits of it, for the spec tests."""

VALID = """\
scene demo "Demo" {
    point p1 (0.1, 0.0)
    object red_cube cube half=0.02 color=red rgb=(1, 0, 0) mass=0.2 friction=0.1
    object blue_cube cube half=0.02 color=blue rgb=(0, 0, 1) mass=0.2 friction=0.1
    fixture bowl bowl radius=0.05 half_height=0.02 color=green rgb=(0, 1, 0)
    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]
    layout base {
        red_cube at (-0.1, 0.0)
        blue_cube at p1
        bowl at (0.0, -0.15)
    }
    layout swapped from base { swap red_cube blue_cube }
    task pick_red on base {
        "Pick up the red cube with your left arm."
        expect pick left red_cube
    }
    split L1 layouts=(swapped) rounds=10 seed=42
}
"""


def edit(old, new):
    assert old in VALID
    return VALID.replace(old, new, 1)

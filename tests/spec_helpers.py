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


# Scene 3's slabs and labels, laid out for the route checks. The blue slab's carry to the green
# label runs along y = -0.10: the red slab stands on it, the green slab (the red slab's column
# mate) 7.8 cm off it, beyond the 5.6 cm within which a carried slab's footprint meets another
# slab's; the yellow slab stands on the red label; the blue label lies on the way.
SLAB = "slab half=(0.018, 0.028, 0.013) mass=0.18 friction=0.8"
ROUTE_SCENE = f"""\
scene routes "Routes" {{
    object blue_slab   {SLAB} color=blue   rgb=(0.1, 0.3, 0.95)
    object yellow_slab {SLAB} color=yellow rgb=(1.0, 0.85, 0.1)
    object red_slab    {SLAB} color=red    rgb=(0.95, 0.25, 0.25)
    object green_slab  {SLAB} color=green  rgb=(0.1, 0.8, 0.2)
    fixture green_label label half=(0.03475, 0.03475, 0.001) color=green rgb=(0.0, 0.8, 0.0)
    fixture blue_label  label half=(0.02, 0.02, 0.001) color=blue rgb=(0.1, 0.3, 0.95)
    fixture red_label   label half=(0.02, 0.02, 0.001) color=red rgb=(0.8, 0.0, 0.0)
    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]
    layout base {{
        blue_slab   at (0.10, -0.10)
        yellow_slab at (0.10, -0.18)
        red_slab    at (-0.02, -0.10)
        green_slab  at (-0.02, -0.022)
        green_label at (-0.16, -0.10)
        red_label   at (0.10, -0.18)
        blue_label  at (0.01, -0.10)
    }}
    layout swapped from base {{ swap red_slab green_slab }}
    layout sources_swapped from base {{ swap blue_slab yellow_slab }}
    layout set_down from base {{ move blue_label to (-0.13, -0.10) }}
    layout lone from base {{ remove green_slab }}
    layout far_mate from base {{ move green_slab to (-0.02, 0.0) }}
}}
"""


def route_task(layout: str, source: str, words: str, label: str = "task") -> str:
    """A training task on `layout` carrying the `source` slab to the green label, `words`."""
    return (f"    task {label} on {layout} {{\n        \"Use your left arm to pick up the "
            f"{source} slab, {words}, and place it on the green square label.\"\n    }}\n")


def routes_with(task: str) -> str:
    """ROUTE_SCENE with `task` added last."""
    at = ROUTE_SCENE.rindex("}")
    return ROUTE_SCENE[:at] + task + ROUTE_SCENE[at:]


# a sound training task: the carry goes round the red slab over the green slab
ROUTES = routes_with(route_task("base", "blue", "avoid passing over the red slab", "carry"))

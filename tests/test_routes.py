"""Route validity (routes.py) on a hand-made layout and its swaps: 'pass over W' and 'avoid X'
accepted where the words ask for something, rejected with the geometry where they do not."""

from pathlib import Path

import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language.parser import parse
from robofollow.compiler.planning.routes import degenerate_routes, passes_over
from robofollow.compiler.scene.grounding import ground
from robofollow.compiler.scene.world import World
from tests.spec_helpers import ROUTES


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    folder = tmp_path_factory.mktemp("routes")
    (folder / "routes.rf").write_text(ROUTES)
    return load_spec(Path(folder)).scenes["routes"]


def problems(scene, layout: str, source: str, words: str) -> list[str]:
    world = World(scene, layout)
    instruction = (f"Use your left arm to pick up the {source} slab, {words}, and place it on "
                   "the green square label.")
    [step] = ground(parse(instruction), world).steps
    return degenerate_routes(step, world)


# (layout, source, route words, the start of the one problem, or None: sound)
CASES = [
    # avoid X: X on the straight path, the detour over its column mate on the way
    ("base", "blue", "avoid passing over the red slab", None),
    ("swapped", "blue", "avoid passing over the green slab", None),
    # avoid X: X 7.8 cm off the path (the green slab, and after the swap the red slab); the
    # carried slab sweeps 2.8 cm either side, X reaches 2.8 cm towards it: never passed over
    ("base", "blue", "avoid passing over the green slab",
     ("'avoid green_slab': green_slab is 7.8 cm off the straight path from blue_slab to "
      "green_label; carried straight, blue_slab sweeps 2.8 cm to either side and green_slab "
      "reaches 2.8 cm towards the path, so a straight carry clears it by 2.2 cm (avoiding it "
      "must change the carry: at most 5.6 cm off)")),
    ("swapped", "blue", "avoid passing over the red slab",
     "'avoid red_slab': red_slab is 7.8 cm off the straight path"),
    # avoid X: X on the path, but no detour body, or one far off the way
    ("lone", "blue", "avoid passing over the red slab",
     ("'avoid red_slab': no other movable body stands in red_slab's column (within 3 cm of its "
      "x) to carry blue_slab over instead")),
    ("far_mate", "blue", "avoid passing over the red slab",
     ("'avoid red_slab' (over green_slab instead): green_slab is 10.0 cm off the straight path "
      "from blue_slab to green_label (at most 8 cm is on the way)")),
    # pass over W: on the way, before and after the swap (7.8 cm off is within the band)
    ("base", "blue", "pass over the red slab", None),
    ("base", "blue", "pass over the green slab", None),
    ("swapped", "blue", "pass over the red slab", None),
    ("base", "blue", "pass over the blue square label", None),
    # pass over W: W under the source (passed over at pick-up), the yellow slab's before the
    # swap and the blue slab's after it
    ("base", "yellow", "pass over the red square label",
     ("'pass over red_label': red_label lies in the footprint of yellow_slab (centres 0.0 cm "
      "apart in x and 0.0 cm in y; clearing it takes 3.8 cm in x or 4.8 cm in y), so the carry "
      "passes over it while picking up")),
    ("sources_swapped", "blue", "pass over the red square label",
     "'pass over red_label': red_label lies in the footprint of blue_slab"),
    # pass over W: W in the destination's footprint (passed over at set-down)
    ("set_down", "blue", "pass over the blue square label",
     ("'pass over blue_label': blue_label lies in the footprint of green_label (centres 3.0 cm "
      "apart in x and 0.0 cm in y; clearing it takes 5.5 cm in x or 5.5 cm in y), so the carry "
      "passes over it while setting down")),
    # behind the source: neither word is on the way
    ("base", "blue", "pass over the red square label",
     "'pass over red_label': red_label is not between blue_slab and green_label"),
]


@pytest.mark.parametrize("layout, source, words, expected", CASES)
def test_route_words_are_judged_by_the_geometry(scene, layout, source, words, expected):
    found = problems(scene, layout, source, words)
    if expected is None:
        assert found == []
    else:
        assert len(found) == 1 and found[0].startswith(expected), found


def test_avoiding_routes_over_the_column_mate_on_the_way(scene):
    """The body a sound 'avoid X' carries over is X's column mate, before and after a swap."""
    for layout, avoided, mate in (("base", "red_slab", "green_slab"),
                                  ("swapped", "green_slab", "red_slab")):
        world = World(scene, layout)
        [step] = ground(parse("Use your left arm to pick up the blue slab, avoid passing over "
                              f"the {avoided.replace('_', ' ')}, and place it on the green "
                              "square label."), world).steps
        assert passes_over(step, world) == (mate,)
        assert degenerate_routes(step, world) == []

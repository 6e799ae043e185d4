"""Hypothesis strategies: logical forms of every shape, and text from the vocabulary."""

from hypothesis import strategies as st

from robofollow.compiler.language import lf
from robofollow.compiler.language.lexicon import VOCABULARY


def _values(literal) -> st.SearchStrategy:
    return st.sampled_from(literal.__args__)


nouns = _values(lf.Noun)
arms = st.none() | _values(lf.Arm)

simple_constraints = st.one_of(
    st.builds(lf.ColorIs, color=_values(lf.Color), negated=st.booleans()),
    st.builds(lf.SizeIs, size=_values(lf.Size)),
    st.builds(lf.ExtremeIs, extreme=_values(lf.Extreme), negated=st.booleans()),
    st.builds(lf.NotKind, noun=nouns),
    st.builds(lf.OrdinalIs, rank=st.integers(1, 5), side=_values(lf.Facing)),
    st.just(lf.MiddleIs()),
)


def _one_position(constraints: list) -> bool:
    return sum(isinstance(c, (lf.OrdinalIs, lf.MiddleIs)) for c in constraints) <= 1


simple_refs = st.builds(lf.Ref, noun=nouns, constraints=st.lists(
    simple_constraints, max_size=3).filter(_one_position).map(tuple))
relations = st.one_of(
    st.builds(lf.Related, relation=_values(lf.Relation), landmark=simple_refs,
              negated=st.booleans()),
    st.builds(lf.Between, landmarks=st.tuples(simple_refs, simple_refs).filter(
        lambda pair: pair[0] != pair[1]), negated=st.booleans()),
    st.builds(lf.NearestIs, nearness=_values(lf.Nearness), landmark=simple_refs,
              negated=st.booleans()),
)
constraints = st.one_of(simple_constraints, relations)
refs = st.builds(lf.Ref, noun=nouns, constraints=st.lists(
    constraints, max_size=3).filter(_one_position).map(tuple))

picks = st.builds(lf.Pick, arm=arms, object=refs)
pushes = st.builds(lf.Push, arm=arms, object=refs, toward=refs)
places = st.builds(
    lf.Place, arm=arms, object=refs,
    destination=st.builds(lf.Placement, relation=_values(lf.PlaceRelation), landmark=refs),
    route=st.lists(st.builds(lf.Waypoint, mode=st.sampled_from(["via", "avoid"]),
                             landmark=simple_refs), max_size=2,
                   unique_by=lambda w: w.landmark).map(tuple),
    orientation=st.none() | st.builds(lf.Orientation, side=_values(lf.Side),
                                      facing=_values(lf.Facing)))
commands = st.one_of(picks, pushes, places)
sequences = st.builds(lf.Sequence, steps=st.lists(commands, min_size=2, max_size=3).map(tuple))
bodies = st.one_of(commands, sequences)
conditions = st.one_of(
    st.builds(lf.Exists, ref=refs, negated=st.booleans()),
    st.builds(lf.Holds, subject=refs, property=constraints),
)
conditionals = st.builds(lf.Conditional, condition=conditions, then=bodies,
                         otherwise=st.none() | bodies)
instructions = st.one_of(bodies, conditionals)

# text: sentences of known words (mostly ungrammatical) and arbitrary strings
_words = sorted(VOCABULARY) + [",", ";", ".", "-", "isn't", "non-empty"]
word_salad = st.lists(st.sampled_from(_words), max_size=25).map(" ".join)
any_text = st.text(max_size=80)

# small random specs: a few objects on a slot grid, swap variants, pick and place tasks
_SLOTS = [(x, y) for y in (-0.06, -0.18) for x in (-0.14, -0.02, 0.10)]
_SIZES = {"cube": "half=0.02", "cylinder": "radius=0.02 half_height=0.025",
          "sphere": "radius=0.02"}
_RGB = {"red": "(1, 0, 0)", "green": "(0, 0.8, 0)", "blue": "(0, 0, 1)", "yellow": "(1, 1, 0)"}
_PLACEMENTS = {"behind": "behind", "in_front_of": "in front of", "left_of": "to the left of",
               "right_of": "to the right of"}


@st.composite
def small_specs(draw) -> tuple[str, list[int]]:
    """(spec text, tasks per training layout) for one small random scene."""
    count = draw(st.integers(2, 5))
    objects = draw(st.lists(st.tuples(st.sampled_from(sorted(_SIZES)),
                                      st.sampled_from(["red", "green", "blue", "yellow"])),
                            min_size=count, max_size=count, unique=True))
    slots = draw(st.permutations(range(len(_SLOTS))))[:count]
    lines = ['scene demo "Random" {', "    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]"]
    for index, (kind, colour) in enumerate(objects):
        lines.append(f"    object o{index} {kind} {_SIZES[kind]} color={colour} "
                     f"rgb={_RGB[colour]} mass=0.2 friction=0.5")
    lines.append("    layout base {")
    lines += [f"        o{i} at ({_SLOTS[s][0]}, {_SLOTS[s][1]})" for i, s in enumerate(slots)]
    lines.append("    }")
    variants = draw(st.lists(st.tuples(st.integers(0, count - 1), st.integers(0, count - 1))
                             .filter(lambda p: p[0] != p[1]), min_size=1, max_size=2))
    for index, (a, b) in enumerate(variants):
        lines.append(f"    layout v{index} from base {{ swap o{a} o{b} }}")
    tasks = draw(st.lists(st.tuples(st.integers(0, count - 1),
                                    st.one_of(st.none(), st.tuples(st.integers(0, count - 1),
                                                                   st.sampled_from(sorted(_PLACEMENTS))))),
                          min_size=1, max_size=5))
    name = lambda i: f"the {objects[i][1]} {objects[i][0]}"
    for index, (source, place) in enumerate(tasks):
        # the arm on the side of where the object goes, as an author would choose it
        x = _SLOTS[slots[place[0] if place else source]][0]
        text = f"Use your {'left' if x < 0 else 'right'} arm to pick up {name(source)}"
        if place is not None and place[0] != source:
            text += f" and place it {_PLACEMENTS[place[1]]} {name(place[0])}"
        lines += [f"    task t{index} on base {{", f'        "{text}."', "    }"]
    layouts = ", ".join(f"v{i}" for i in range(len(variants)))
    lines += [f"    split L1 layouts=({layouts}) rounds=2 seed=7",
              "    split L2 wordings=(referents) max=12 rounds=2 seed=7",
              f"    split L3 layouts=({layouts}) wordings=(referents) max=12 rounds=2 seed=7",
              "}"]
    return "\n".join(lines) + "\n", [len(tasks)]


# richer random specs: what the shipped specs use -- bowls, pushes, stacks, sequences,
# conditionals, routes over slabs onto labels, identical-looking bodies and swaps
_GRID = [(x, y) for y in (-0.05, -0.17) for x in (-0.16, -0.05, 0.06, 0.17)]


def _arm(x: float) -> str:
    return "left" if x < 0 else "right"


@st.composite
def rich_specs(draw) -> dict:
    """{"text": spec text, "twins": (a, b) | None, "look_alike": layout | None} for one random
    scene: 2-4 distinct objects on a grid, maybe a bowl and a label, maybe a second
    (identical-looking) copy of the first object, maybe a stack, and tasks of every action
    kind, routes included."""
    count = draw(st.integers(2, 4))
    objects = draw(st.lists(st.tuples(st.sampled_from(sorted(_SIZES)),
                                      st.sampled_from(["red", "green", "blue", "yellow"])),
                            min_size=count, max_size=count, unique=True))
    slots = list(draw(st.permutations(range(len(_GRID)))))
    at = {f"o{i}": _GRID[slots[i]] for i in range(count)}
    lines = ['scene demo "Random" {', "    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]"]
    for index, (kind, colour) in enumerate(objects):
        lines.append(f"    object o{index} {kind} {_SIZES[kind]} color={colour} "
                     f"rgb={_RGB[colour]} mass=0.2 friction=0.5")
    name = {f"o{i}": f"the {objects[i][1]} {objects[i][0]}" for i in range(count)}
    twins = None
    if draw(st.booleans()):  # an identical-looking copy of o0, never named in a task
        kind, colour = objects[0]
        lines.append(f"    object t0 {kind} {_SIZES[kind]} color={colour} rgb={_RGB[colour]} "
                     "mass=0.2 friction=0.5")
        at["t0"] = _GRID[slots[count]]
        twins = ("o0", "t0")
    bowl = draw(st.booleans())
    if bowl:
        lines.append("    fixture bowl bowl radius=0.045 half_height=0.02 color=green "
                     "rgb=(0.1, 0.7, 0.2)")
        at["bowl"] = _GRID[slots[-1]]
    label = draw(st.booleans())
    if label:
        lines.append("    fixture label label half=(0.035, 0.035, 0.001) color=green "
                     "rgb=(0, 0.8, 0)")
        at["label"] = _GRID[slots[-2]]
    stacked = None
    if count >= 3 and objects[2][0] == "cube" and objects[1][0] != "sphere" and \
            draw(st.booleans()):
        stacked = "o2"  # o2 rests on o1 in the base layout
    lines.append("    layout base {")
    for body, (x, y) in at.items():
        if body != stacked:
            lines.append(f"        {body} at ({x}, {y})")
    if stacked:
        lines.append(f"        {stacked} on o1")
    lines.append("    }")
    layouts = []
    if twins:
        lines.append("    layout look_alike from base { swap o0 t0 }")
    a, b = draw(st.tuples(st.integers(0, count - 1), st.integers(0, count - 1))
                .filter(lambda p: p[0] != p[1]))
    if stacked not in (f"o{a}", f"o{b}"):
        lines.append(f"    layout v0 from base {{ swap o{a} o{b} }}")
        layouts.append("v0")
    # what tasks may move: not o1 under a stack, not o0 when its twin makes "the red cube"
    # ambiguous
    free = [f"o{i}" for i in range(count)
            if not (stacked and i == 1) and not (twins and i == 0)]
    if not free:
        free = [f"o{count - 1}"]
    kinds = draw(st.lists(st.sampled_from(["pick", "place", "push", "bowl", "sequence",
                                           "conditional", "route"]), min_size=1, max_size=5))
    texts = []
    for kind in kinds:
        source, other = draw(st.permutations(free))[:2] if len(free) >= 2 else (free[0], None)
        sx = at[source][0]
        if kind == "pick" or other is None:
            texts.append(f"Use your {_arm(sx)} arm to pick up {name[source]}")
        elif kind == "place":
            where = draw(st.sampled_from(sorted(_PLACEMENTS)))
            texts.append(f"Use your {_arm(at[other][0])} arm to pick up {name[source]} and "
                         f"place it {_PLACEMENTS[where]} {name[other]}")
        elif kind == "push":
            texts.append(f"Use your {_arm(sx)} arm to push {name[source]} towards "
                         f"{name[other]}")
        elif kind == "bowl" and bowl:
            texts.append(f"Use your {_arm(at['bowl'][0])} arm to pick up {name[source]} and "
                         "place it in the bowl")
        elif kind == "route" and label:
            mode = draw(st.sampled_from(["pass over", "avoid passing over"]))
            texts.append(f"Use your {_arm(at['label'][0])} arm to pick up {name[source]}, "
                         f"{mode} {name[other]}, and place it on the green label")
        elif kind == "sequence" and _arm(sx) != _arm(at[other][0]):
            texts.append(f"First use your {_arm(sx)} arm to pick up {name[source]}, then use "
                         f"your {_arm(at[other][0])} arm to pick up {name[other]}")
        elif kind == "conditional" and at[source][1] == at[other][1]:  # a row: left is clear
            texts.append(f"If {name[source]} is to the left of {name[other]}, use your "
                         f"{_arm(sx)} arm to pick up {name[source]}; otherwise use your "
                         f"{_arm(at[other][0])} arm to pick up {name[other]}")
        else:
            texts.append(f"Use your {_arm(sx)} arm to pick up {name[source]}")
    for index, text in enumerate(dict.fromkeys(texts)):
        lines += [f"    task t{index}_{kinds[0]} on base {{", f'        "{text}."', "    }"]
    if layouts:
        lines += [f"    split L1 layouts=({', '.join(layouts)}) rounds=2 seed=7",
                  (f"    split L3 layouts=({', '.join(layouts)}) wordings=(referents) max=12 "
                   "rounds=2 seed=7")]
    lines += [("    split L2 wordings=(referents, routes, conditions, branches) max=12 rounds=2 "
               "seed=7"),
              "}"]
    return {"text": "\n".join(lines) + "\n", "twins": twins,
            "look_alike": "look_alike" if twins else None}


# a route step's geometry: a source, a destination at least 20 cm away, and where the body
# it names stands, as (along the path, across it) in metres
route_geometry = st.tuples(
    st.floats(-0.2, 0.2), st.floats(-0.25, 0.0),  # source x, y
    st.floats(0.20, 0.35), st.floats(0, 2 * 3.141592653589793),  # path length, heading
)


# several small scenes compiled together: distinct referents, a group of two or three
# look-alike bodies (same kind, size and colour) that no training task names, or that look
# like a referent the tasks then name by its side ('the leftmost red cube'), extra labels,
# layouts that swap or move the bodies training tasks refer to, a layout where only the
# look-alikes trade places, listed tests, and L1-L3 rules with a max
_COLOURS = ["red", "green", "blue", "yellow"]
_LABEL_HALF = "half=(0.03, 0.03, 0.001)"


def _object_line(name: str, kind: str, colour: str) -> str:
    return (f"    object {name} {kind} {_SIZES[kind]} color={colour} rgb={_RGB[colour]} "
            "mass=0.2 friction=0.5")


@st.composite
def scene_specs(draw, scene: str = "demo") -> dict:
    """{"id", "text", "max": {level: N}, "listed": [level, ...]} for one small random scene
    named `scene` (its task labels start with the scene's id, as labels are global)."""
    count = draw(st.integers(2, 3))
    looks = draw(st.lists(st.tuples(st.sampled_from(sorted(_SIZES)), st.sampled_from(_COLOURS)),
                          min_size=count + 1, max_size=count + 1, unique=True))
    objects, decoy = looks[:count], looks[count]
    copies = draw(st.sampled_from([0, 0, 2, 3]))
    labels = draw(st.lists(st.sampled_from(_COLOURS), max_size=2, unique=True))
    slots = list(draw(st.permutations(range(len(_GRID)))))
    referents = [f"o{i}" for i in range(count)]
    look_alikes = [f"d{i}" for i in range(copies)]
    fixtures = [f"{colour}_label" for colour in labels]
    bodies = referents + look_alikes + fixtures
    at = {body: slots[index] for index, body in enumerate(bodies)}
    lines = [f'scene {scene} "Random {scene}" {{',
             "    jitter * x=[-0.01, 0.01] y=[-0.01, 0.01]"]
    lines += [_object_line(name, *look) for name, look in zip(referents, objects, strict=True)]
    name = {f"o{i}": f"the {objects[i][1]} {objects[i][0]}" for i in range(count)}
    x = {body: _GRID[slot][0] for body, slot in at.items()}
    if copies and draw(st.booleans()):  # the look-alikes look like o0, named by its side
        others = [x[body] for body in look_alikes]
        side = ("leftmost" if x["o0"] < min(others) else
                "rightmost" if x["o0"] > max(others) else None)
        if side:
            decoy = objects[0]
            name["o0"] = f"the {side} {objects[0][1]} {objects[0][0]}"
    lines += [_object_line(name, *decoy) for name in look_alikes]
    lines += [f"    fixture {name} label {_LABEL_HALF} color={colour} rgb={_RGB[colour]}"
              for name, colour in zip(fixtures, labels, strict=True)]
    lines.append("    layout base {")
    lines += [f"        {body} at ({_GRID[slot][0]}, {_GRID[slot][1]})"
              for body, slot in at.items()]
    lines.append("    }")
    # training tasks: each names one or two referents (never a look-alike)
    texts = []
    for kind in draw(st.lists(st.sampled_from(["pick", "place", "push", "label",
                                               "conditional"]), min_size=1, max_size=3)):
        source, other = draw(st.permutations(referents))[:2]
        if kind == "place":
            where = draw(st.sampled_from(sorted(_PLACEMENTS)))
            texts.append(f"Use your {_arm(x[other])} arm to pick up {name[source]} and place "
                         f"it {_PLACEMENTS[where]} {name[other]}")
        elif kind == "push":
            texts.append(f"Use your {_arm(x[source])} arm to push {name[source]} towards "
                         f"{name[other]}")
        elif kind == "label" and fixtures:
            label = draw(st.sampled_from(fixtures))
            texts.append(f"Use your {_arm(x[label])} arm to pick up {name[source]} and place "
                         f"it on the {label.removesuffix('_label')} label")
        elif kind == "conditional" and _GRID[at[source]][1] == _GRID[at[other]][1] \
                and _arm(x[source]) != _arm(x[other]):
            texts.append(f"If {name[source]} is to the left of {name[other]}, use your "
                         f"{_arm(x[source])} arm to pick up {name[source]}; otherwise use your "
                         f"{_arm(x[other])} arm to pick up {name[other]}")
        else:
            texts.append(f"Use your {_arm(x[source])} arm to pick up {name[source]}")
    texts = list(dict.fromkeys(texts))
    for index, text in enumerate(texts):
        lines += [f"    task {scene}_t{index} on base {{", f'        "{text}."', "    }"]
    # layouts that move referents: swaps with any other body, moves to a free slot
    named = sorted({body for body in referents if any(name[body] in t for t in texts)})
    looks_of = {**dict(zip(referents, objects, strict=True)),
                **{body: decoy for body in look_alikes}, **{f: f for f in fixtures}}

    def view(places: dict) -> set:
        return {(slot, looks_of[body]) for body, slot in places.items()}

    layouts, moved = [], {}
    for index in range(draw(st.integers(1, 2))):
        where = dict(at)
        ops = []
        for _ in range(draw(st.integers(1, 2))):
            body = draw(st.sampled_from(named))
            free = [s for s in range(len(_GRID)) if s not in where.values()]
            if free and draw(st.booleans()):
                slot = draw(st.sampled_from(free))
                where[body] = slot
                ops.append(f"move {body} to ({_GRID[slot][0]}, {_GRID[slot][1]})")
            else:
                other = draw(st.sampled_from([b for b in bodies if b != body]))
                where[body], where[other] = where[other], where[body]
                ops.append(f"swap {body} {other}")
        lines.append(f"    layout v{index} from base {{ {' '.join(ops)} }}")
        if view(where) != view(at):  # (a rule may not test where only look-alikes traded)
            layouts.append(f"v{index}")
            moved[f"v{index}"] = {body for body in bodies if where[body] != at[body]}
    if copies:  # only the look-alikes trade places: it looks the same as base
        lines.append("    layout same from base { swap d0 d1 }")
    wordings = ["referents"] + (["conditions", "branches"] if any(
        t.startswith("If") for t in texts) else [])
    maximum = {level: draw(st.integers(1, 6)) for level in ("L1", "L2", "L3")}
    listed = []
    # a training instruction listed on a changed layout where what it names stays put (a pick,
    # or a place on a label: where a place beside a body or a push goes depends on the rest)
    mentions = {text: {b for b in referents if name[b] in text}
                | {f for f in fixtures if f"the {f.removesuffix('_label')} label" in text}
                | (set(look_alikes) if decoy == objects[0] and name["o0"] in text else set())
                for text in texts}  # (o0 named by its side among its look-alikes)
    unmoved = [(layout, text) for layout, changed in moved.items() for text in texts
               if not changed & mentions[text] and not text.startswith("If")
               and " towards " not in text and (" place it " not in text or "label" in text)]
    if unmoved and draw(st.booleans()):
        layout, text = draw(st.sampled_from(unmoved))
        lines += [f"    test L1 listed_{scene}_l1 on {layout} {{", f'        "{text}."', "    }"]
        listed.append("L1")
    kinds = [kind for kind, _ in objects + [decoy] * copies]  # (decoy: the look-alikes')
    picked = [(text, body) for text in texts for body in named
              if text.endswith(f"pick up {name[body]}") and not text.startswith("If")]
    if picked and draw(st.booleans()):  # the noun alone where it is the only one of its kind
        text, body = draw(st.sampled_from(picked))
        kind = objects[int(body[1:])][0]
        if kinds.count(kind) == 1:
            lines += [f"    test L2 listed_{scene}_l2 on base {{",
                      f'        "{text.replace(name[body], f"the {kind}")}."', "    }"]
            listed.append("L2")
    rule = f"layouts=({', '.join(layouts)}) " if layouts else ""
    lines += [f"    split L1 {rule}max={maximum['L1']} rounds=2 seed=7",
              (f"    split L2 wordings=({', '.join(wordings)}) max={maximum['L2']} rounds=2 "
               "seed=7"),
              (f"    split L3 {rule}wordings=(referents) max={maximum['L3']} "
               "rounds=2 seed=7"),
              "}"]
    return {"id": scene, "text": "\n".join(lines) + "\n", "max": maximum, "listed": listed}


@st.composite
def several_scenes(draw) -> dict:
    """{"scenes": [scene_specs, ...], "one_file": bool}: two or three scenes with distinct
    ids, written one to a file or all in one file; the second is sometimes the first under
    another id (the same bodies, layouts and words)."""
    ids = draw(st.lists(st.sampled_from(["alpha", "beta", "gamma", "delta"]), min_size=2,
                        max_size=3, unique=True))
    scenes = [draw(scene_specs(scene)) for scene in ids]
    if draw(st.integers(0, 3)) == 0:
        first, second = scenes[0], ids[1]
        scenes[1] = {**first, "id": second, "text": first["text"].replace(first["id"], second)}
    return {"scenes": scenes, "one_file": draw(st.booleans())}

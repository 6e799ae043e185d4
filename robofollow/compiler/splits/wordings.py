"""Novel wordings for L2 and L3: new logical forms built from training concepts.

Each generator takes a task's logical form, a Describer of the world it is said in and a
`Rank` (a sort key for a choice's canonical text), and lazily yields other forms: other
referring expressions for the same objects ("referents"), equivalent route and orientation
wording ("routes", "orientation"), other or negated observable conditions ("conditions") and
swapped branches ("branches"). A generator offers its choices in rank order, taking turns
among the places it rewords, so a form is built only when the split generator asks for the
next one. The split generator keeps a form only when it is new, its words are training words,
and what it asks for is in the training repertoire.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator

from robofollow.compiler.language import lf
from robofollow.compiler.language.lexicon import terms
from robofollow.compiler.scene.grounding import Grounder, GroundingError
from robofollow.compiler.splits.wording_rules import vacuous_comparisons

_PUNCTUATION = frozenset({"COMMA", "SEMICOLON", "PERIOD"})
_RELATIONS = ("left_of", "right_of", "behind", "in_front_of", "on", "in")
_VERTICAL = ("above", "below")
_NEARNESS = ("nearest", "farthest")
_EXTREMES = ("leftmost", "rightmost")
_SIDES = ("short", "long")
_FACINGS = ("front", "back", "left", "right")

Rank = Callable[[str], str]  # a choice's canonical text -> its sort key
_END = object()


def round_robin(streams: Iterable[Iterator]) -> Iterator:
    """The streams' items taking turns, each stream dropped once it runs out."""
    active = list(streams)
    while active:
        still = []
        for stream in active:
            item = next(stream, _END)
            if item is not _END:
                still.append(stream)
                yield item
        active = still


def concepts(text: str) -> set[tuple[str, str]]:
    """The words of an instruction as the lexicon knows them (synonyms collapsed)."""
    return {(terminal, value) for terminal, value in terms(text) if terminal not in _PUNCTUATION}


class Describer:
    """Descriptions of bodies that pick them out uniquely in one world (memoised), using the
    kinds of description training instructions use (`constructs`, see lf.constructs; the
    colour, size, leftmost / rightmost and horizontal relations always)."""

    def __init__(self, grounder: Grounder, constructs: set[str] = frozenset()):
        self.world = grounder.world
        self.grounder = grounder
        self.constructs = constructs
        self._simple: dict[str, lf.Ref | None] = {}
        self._descriptions: dict[str, list[lf.Ref]] = {}
        self._conditions: list[lf.Condition] | None = None
        self._texts: dict[int, tuple[object, str]] = {}  # id -> (node, canonical JSON)

    def text(self, node: lf.Ref | lf.Condition) -> str:
        """The canonical JSON of a description or condition this describer made (memoised:
        it ranks them for every source of its world)."""
        hit = self._texts.get(id(node))
        if hit is None or hit[0] is not node:
            hit = self._texts[id(node)] = node, node.model_dump_json()
        return hit[1]

    def ranked(self, nodes: list, rank: Rank) -> list:
        """The descriptions or conditions in rank order."""
        return sorted(nodes, key=lambda node: rank(self.text(node)))

    def unique(self, ref: lf.Ref, body: str) -> bool:
        try:
            return self.grounder.referents(ref) == [body]
        except GroundingError:  # a landmark inside the description is itself unclear
            return False

    def simple(self, body: str) -> lf.Ref | None:
        """The shortest description by kind and colour alone, if any is unique."""
        if body not in self._simple:
            spec = self.world.bodies[body]
            options = [lf.Ref(noun=spec.kind),
                       lf.Ref(noun=spec.kind, constraints=(lf.ColorIs(color=spec.color),))]
            self._simple[body] = next((r for r in options if self.unique(r, body)), None)
        return self._simple[body]

    def descriptions(self, body: str) -> list[lf.Ref]:
        """Every description of one or two constraints that picks out `body`, with no
        comparison made among fewer than two bodies."""
        if body not in self._descriptions:
            self._descriptions[body] = self._describe(body)
        return self._descriptions[body]

    def _describe(self, body: str) -> list[lf.Ref]:
        spec = self.world.bodies[body]
        nouns = [spec.kind] + ([] if spec.fixture else ["object"])
        if spec.kind in ("cube", "slab"):
            nouns.append("block")
        colour = lf.ColorIs(color=spec.color)
        options: list[tuple] = [(), (colour,)]
        for word in ("larger", "smaller"):
            options += [(lf.SizeIs(size=word),), (colour, lf.SizeIs(size=word))]
        for extreme in _EXTREMES:
            options += [(lf.ExtremeIs(extreme=extreme),),
                        (colour, lf.ExtremeIs(extreme=extreme))]
        relations = _RELATIONS + tuple(r for r in _VERTICAL if f"relation:{r}" in self.constructs)
        landmarks = [self.simple(other) for other in self.world.bodies if other != body]
        landmarks = [landmark for landmark in landmarks if landmark is not None]
        for landmark in landmarks:
            options += [(lf.Related(relation=r, landmark=landmark),) for r in relations]
            if "nearest" in self.constructs:
                options += [(lf.NearestIs(nearness=n, landmark=landmark),) for n in _NEARNESS]
        if "between" in self.constructs:
            options += [(lf.Between(landmarks=(a, b)),) for i, a in enumerate(landmarks)
                        for b in landmarks[i + 1:] if a != b]
        if "ordinal" in self.constructs:
            options += [(lf.OrdinalIs(rank=rank, side=side),) for side in _FACINGS
                        for rank in (1, 2, 3)]
        if "middle" in self.constructs:
            options.append((lf.MiddleIs(),))
        options = [constraints for constraints in options if self._meets(body, constraints)]
        refs = (lf.Ref(noun=noun, constraints=constraints)
                for noun in nouns for constraints in options)  # distinct by construction
        return [ref for ref in refs
                if self.unique(ref, body) and not vacuous_comparisons(ref, self.grounder)]

    def conditions(self) -> list[lf.Condition]:
        """The observable conditions of the world, each as it is and negated (memoised):
        something on (in) each body the simplest description picks out, and each movable
        body left or right of another."""
        if self._conditions is None:
            world = self.world
            found: list[lf.Condition] = []
            for body in world.bodies:
                landmark = self.simple(body)
                if landmark is None:
                    continue
                relation = "in" if world.bodies[body].kind == "bowl" else "on"
                if world.bodies[body].kind != "label":
                    found.append(lf.Exists(ref=lf.Ref(noun="object", constraints=(
                        lf.Related(relation=relation, landmark=landmark),))))
            movable = [b for b in world.movable if self.simple(b) is not None]
            for a in movable:
                for b in movable:
                    if a != b:
                        for relation in ("left_of", "right_of"):
                            found.append(lf.Holds(subject=self.simple(a), property=lf.Related(
                                relation=relation, landmark=self.simple(b))))
            self._conditions = [
                condition.model_copy(update={"negated": negated})
                if isinstance(condition, lf.Exists) else
                condition.model_copy(update={"property": condition.property.model_copy(
                    update={"negated": negated})})
                for condition in found for negated in (False, True)]
        return self._conditions

    def _meets(self, body: str, constraints: tuple) -> bool:
        """Whether `body` meets the plain constraints (those of a description that picks it
        out do): most options fail here, before a description is built."""
        try:
            return all(self.grounder.satisfies(body, c) for c in constraints
                       if not isinstance(c, lf.COMPARATIVES))
        except GroundingError:  # a landmark that is itself unclear: `unique` says no too
            return False


def _replace(form: lf.Instruction, path: str, command) -> lf.Instruction:
    """The form with the command at `path` (as `lf.commands` names it) replaced."""
    if not path:
        return command
    head, _, rest = path.partition(".")
    if head in ("then", "otherwise"):
        return form.model_copy(update={head: _replace(getattr(form, head), rest, command)})
    steps = list(form.steps)
    steps[int(head.removeprefix("step"))] = command
    return form.model_copy(update={"steps": tuple(steps)})


def referents(form: lf.Instruction, describer: Describer, rank: Rank
              ) -> Iterator[lf.Instruction]:
    """The same commands, with one object, destination or push target described otherwise:
    each place in turn, its other descriptions in rank order."""
    grounder = describer.grounder
    streams = []
    for path, command in lf.commands(form):
        slots = ["object"] + (["destination"] if isinstance(command, lf.Place) else []) + (
            ["toward"] if isinstance(command, lf.Push) else [])
        for slot in slots:
            current = command.destination.landmark if slot == "destination" else getattr(
                command, slot)
            try:
                body = grounder.resolve(current)
            except GroundingError:
                continue
            others = [ref for ref in describer.descriptions(body) if ref != current]
            streams.append(_described(form, path, command, slot,
                                      describer.ranked(others, rank)))
    return round_robin(streams)


def _described(form: lf.Instruction, path: str, command, slot: str, refs: list[lf.Ref]
               ) -> Iterator[lf.Instruction]:
    """The form with the command at `path` naming each ref in its `slot`."""
    for ref in refs:
        if slot == "destination":
            update = {"destination": command.destination.model_copy(update={"landmark": ref})}
        else:
            update = {slot: ref}
        yield _replace(form, path, command.model_copy(update=update))


def routes(form: lf.Instruction, describer: Describer, rank: Rank
           ) -> Iterator[lf.Instruction]:
    """'pass over W' said as 'avoid passing over X' (X beside W in its column), and back (one
    choice per command: nothing to rank)."""
    for path, command in lf.commands(form):
        if not isinstance(command, lf.Place) or len(command.route) != 1:
            continue
        waypoint = command.route[0]
        try:
            body = describer.grounder.resolve(waypoint.landmark)
            source = describer.grounder.resolve(command.object)
        except GroundingError:
            continue
        mates = describer.world.column_mates(body, excluding=(source,))
        if len(mates) != 1 or describer.simple(mates[0]) is None:
            continue
        other = "avoid" if waypoint.mode == "via" else "via"
        swapped = lf.Waypoint(mode=other, landmark=describer.simple(mates[0]))
        yield _replace(form, path, command.model_copy(update={"route": (swapped,)}))


def orientation(form: lf.Instruction, describer: Describer, rank: Rank
                ) -> Iterator[lf.Instruction]:
    """The same final yaw said with the other side facing another way, in rank order."""
    grounder = describer.grounder
    for path, command in lf.commands(form):
        if not isinstance(command, lf.Place) or command.orientation is None:
            continue
        try:
            body = grounder.resolve(command.object)
            yaw = grounder.yaw(body, command.orientation)
        except GroundingError:
            continue
        others = [(side, facing) for side in _SIDES for facing in _FACINGS]
        for side, facing in sorted(others, key=lambda pair: rank(" ".join(pair))):
            other = lf.Orientation(side=side, facing=facing)
            if other != command.orientation and grounder.yaw(body, other) == yaw:
                yield _replace(form, path, command.model_copy(update={"orientation": other}))


def conditions(form: lf.Instruction, describer: Describer, rank: Rank
               ) -> Iterator[lf.Instruction]:
    """Other observable conditions (and their negations) over the same branches, in rank
    order."""
    if not isinstance(form, lf.Conditional):
        return
    for variant in describer.ranked(describer.conditions(), rank):
        if variant != form.condition:
            yield form.model_copy(update={"condition": variant})


def branches(form: lf.Instruction, describer: Describer, rank: Rank
             ) -> Iterator[lf.Instruction]:
    """The branches swapped, with the condition as it was and negated (in that order: nothing
    to rank)."""
    if not isinstance(form, lf.Conditional) or form.otherwise is None:
        return
    swapped = form.model_copy(update={"then": form.otherwise, "otherwise": form.then})
    yield swapped
    condition = form.condition
    if isinstance(condition, lf.Exists):
        yield swapped.model_copy(update={"condition": condition.model_copy(
            update={"negated": not condition.negated})})
    elif hasattr(condition.property, "negated"):
        yield swapped.model_copy(update={"condition": condition.model_copy(update={
            "property": condition.property.model_copy(
                update={"negated": not condition.property.negated})})})


GENERATORS = {"referents": referents, "routes": routes, "orientation": orientation,
              "conditions": conditions, "branches": branches}

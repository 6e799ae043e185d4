"""A scene's split rules as written (`split L1 layouts=(...) rounds=10 ...`): each attribute
checked where it is written, and the layouts an L1 or L3 rule tests on checked to look
different from every training layout, unless the rule allows repeats (`repeats=allowed`)."""

from __future__ import annotations

from lark import Token

from robofollow.compiler.authoring.spec_checks import Checks
from robofollow.compiler.authoring.spec_syntax import Attribute, Name, SplitNode, Values
from robofollow.compiler.scene.observation import look_alike
from robofollow.compiler.scene.spec import (
    MAX_ROUNDS,
    MAX_SEED,
    MAX_TASKS,
    MOTION_LEVELS,
    SPLIT_MOTIONS,
    SPLIT_REPEATS,
    Scene,
    SplitRule,
)
from robofollow.errors import did_you_mean

WORDINGS = ("referents", "routes", "orientation", "conditions", "branches")
# a split rule's attributes: the lists of names, the numbers (SplitRule field, range), and the
# choices of the levels on changed layouts (what each choice means)
_SPLIT_NAMES = ("layouts", "wordings")
_SPLIT_NUMBERS = {
    "max": ("max_tasks", (1, MAX_TASKS)), "rounds": ("rounds", (1, MAX_ROUNDS)),
    "seed": ("seed", (0, MAX_SEED))}
_SPLIT_CHOICES = {
    "motion": (SPLIT_MOTIONS, ("every task, or only those whose expert motion differs from "
                               "the training task's")),
    "repeats": (SPLIT_REPEATS, ("a layout that looks the same as a training layout is an "
                                "error, or a distractor-free repeat the rule means"))}


class SplitChecks(Checks):
    """The checks of split rules (a part of the loader's)."""

    def split(self, item: SplitNode, layouts: dict[str, None]) -> SplitRule:
        found = self.attributes(item.attributes,
                                (*_SPLIT_NAMES, *_SPLIT_NUMBERS, *_SPLIT_CHOICES))
        values: dict = {"level": str(item.level)}
        for key in _SPLIT_NAMES:
            if key in found:
                value = found[key].value
                names = value.items if isinstance(value, Values) else (value,)
                if not all(isinstance(n, Name) for n in names):
                    self.error("bad-value", f"{key} takes names: {key}=(a, b, ...)",
                               found[key].key)
                    continue
                tokens = [n.token for n in names]
                known = layouts if key == "layouts" else WORDINGS
                for token in tokens:
                    if token not in known:
                        code = "undefined-layout" if key == "layouts" else "unknown-wording"
                        self.unknown_name(code, key[:-1], token, known)
                values[key] = tuple(str(t) for t in tokens)
        for key, (name, bounds) in _SPLIT_NUMBERS.items():
            if key in found:
                number = self.number(found[key], bounds, whole=True)
                if number is not None:
                    values[name] = int(number)
        for key in _SPLIT_CHOICES:
            if key in found:
                choice = self.split_choice(found[key], str(item.level))
                if choice is not None:
                    values[key] = choice
        return SplitRule(**values, source=self.source(item.level))

    def split_choice(self, node: Attribute, level: str) -> str | None:
        """A split rule's `motion=` or `repeats=`: one of its choices, on a level of changed
        layouts."""
        key = str(node.key)
        choices, meaning = _SPLIT_CHOICES[key]
        if level not in MOTION_LEVELS:
            self.error("unknown-attribute", f"{key} applies to {' and '.join(MOTION_LEVELS)} "
                       f"(the levels on changed layouts), not to {level}", node.key)
            return None
        known = " | ".join(choices)
        if not isinstance(node.value, Name):
            self.error("bad-value", f"{key} takes a name: {key}={known}", node.key)
            return None
        token = node.value.token
        if token not in choices:
            hint = did_you_mean(str(token), choices)
            self.error("bad-value", f"unknown {key} {token!s}; {f'{hint} ' if hint else ''}"
                       f"(known: {known}: {meaning})", token)
            return None
        return str(token)

    def repeated_layouts(self, scene: Scene, names: dict[str, Token], skip: set[str]) -> None:
        """A layout that an L1 or L3 rule tests on (changed layouts) and that looks the same as
        a training layout is an error at the layout, unless each rule that names it allows
        repeats; the layouts in `skip` (not posed, or with a problem reported) are not
        looked at."""
        levels: dict[str, list[str]] = {}
        for rule in scene.splits.values():
            if rule.level in MOTION_LEVELS and rule.repeats == "refused":
                for layout in rule.layouts:
                    levels.setdefault(layout, []).append(rule.level)
        posed = [name for name in scene.training_layouts  # (a broken one has its error)
                 if name in scene.layouts and name not in skip]
        for layout, refused in levels.items():
            if layout not in scene.layouts or layout in skip:
                continue
            same = look_alike(scene, layout, posed)
            if same is None:
                continue
            what = ("is a training layout" if same == layout else "looks the same as the "
                    f"training layout {same} (the same bodies in the same places, up to "
                    "bodies that look alike)")
            self.error("looks-like-training", f"layout {layout} {what}, so the "
                       f"{' and '.join(refused)} tasks on it would not test a changed layout; "
                       "change it, or write repeats=allowed on the split rule if a "
                       "distractor-free repeat is meant", names[layout])

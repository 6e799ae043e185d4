"""Split generation from rules: candidates for each level, each kept or rejected with a reason.

- L0: each training task's first paraphrase on its training layout.
- L1: training first paraphrases on the split rule's changed layouts, kept when they still
  ground to exactly one behaviour inside the training repertoire.
- L2: the training layouts with new wording from the rule's generators (wordings.py): a
  logical form no training instruction has, said in words training instructions use.
- L3: the kept L1 tasks reworded the same way on their changed layouts.

A candidate is kept when it grounds to one behaviour (also with the jitter at its extremes),
its route, if any, is on the way (routes.py), training performs its motions (motions.py), and
the expert can perform it (feasibility.py). L1 and L3 layouts must look different from every
training layout (observation.py).
"""

from __future__ import annotations

import hashlib

from robofollow.compiler import lf
from robofollow.compiler.behaviour import Behaviour
from robofollow.compiler.feasibility import infeasible
from robofollow.compiler.grounding import Grounder, GroundingError, instability
from robofollow.compiler.model import Model
from robofollow.compiler.motions import COMPOSING_LEVELS, Repertoire
from robofollow.compiler.observation import look_alike
from robofollow.compiler.realize import STYLES, realize
from robofollow.compiler.routes import degenerate_routes
from robofollow.compiler.spec import Level, Scene, Spec
from robofollow.compiler.wordings import GENERATORS, Describer, concepts
from robofollow.compiler.world import jitter_worlds


class TestTask(Model):
    id: str
    scene: str
    level: Level
    layout: str
    instruction: str
    form: lf.Instruction
    behaviour: Behaviour
    origin: str  # the training task it derives from
    wording: str  # "training", or the generator that reworded it


class Rejection(Model):
    scene: str
    level: Level
    layout: str
    instruction: str
    origin: str
    reason: str


class Splits(Model):
    tasks: tuple[TestTask, ...]
    rejected: tuple[Rejection, ...]

    def of(self, scene: str, level: Level) -> list[TestTask]:
        return [t for t in self.tasks if t.scene == scene and t.level == level]


def episode_seed(task_id: str, round_index: int, base: int) -> int:
    """The seed of a task's round: fixed by the task id, the round and the split's seed base."""
    offset = int(hashlib.sha256(task_id.encode()).hexdigest()[:8], 16) % 1000
    return base + 100 * round_index + offset


def _digest_of(task_id: str) -> str:
    return hashlib.sha256(task_id.encode()).hexdigest()


def _variants(form: lf.Instruction, describer: Describer, wordings: tuple[str, ...]):
    """(wording, form) from each generator alone, then from each ordered pair of the
    generators that reword one aspect ('referents' alone already varies every object)."""
    for wording in wordings:
        for novel in GENERATORS[wording](form, describer):
            yield wording, novel
    composable = [w for w in wordings if w != "referents"]
    for index, first in enumerate(composable):
        for second in composable[index + 1:]:
            for middle in GENERATORS[first](form, describer):
                for novel in GENERATORS[second](middle, describer):
                    yield f"{first}+{second}", novel


class _Generator:
    def __init__(self, scene: Scene, training: dict[str, Behaviour], training_forms: set[str],
                 vocabulary: set[tuple[str, str]], constructs: set[str]):
        self.scene = scene
        self.training = training
        self.training_forms = training_forms
        self.vocabulary = vocabulary
        self.constructs = constructs
        self.repertoire = Repertoire(scene, training)
        self.tasks: list[TestTask] = []
        self.rejected: list[Rejection] = []
        self.seen: dict[tuple[str, str], str] = {}
        self.grounders: dict[str, list[Grounder]] = {}  # per layout: nominal, then jittered
        self.describers: dict[str, Describer] = {}

    def reject(self, level: Level, layout: str, instruction: str, origin: str,
               reason: str) -> None:
        self.rejected.append(Rejection(scene=self.scene.id, level=level, layout=layout,
                                       instruction=instruction, origin=origin, reason=reason))

    def fill_arms(self, behaviour: Behaviour, origin: str) -> Behaviour:
        """Unnamed arms take the training task's arms (its paraphrases name them)."""
        arms = [s.arm for s in self.training[origin].steps]
        if len(arms) != len(behaviour.steps):
            return behaviour
        steps = tuple(s if s.arm else s.model_copy(update={"arm": a})
                      for s, a in zip(behaviour.steps, arms, strict=True))
        return behaviour.model_copy(update={"steps": steps})

    def consider(self, level: Level, layout: str, instruction: str, form: lf.Instruction,
                 origin: str, wording: str, task_id: str | None = None) -> bool:
        """Keep the candidate as a test task, or reject it with the reason; whether kept."""
        key = (layout, instruction if wording == "training" else lf.to_json(form))
        if key in self.seen:
            self.reject(level, layout, instruction, origin, f"duplicate of {self.seen[key]}")
            return False
        nominal = self.grounders_of(layout)[0]
        world = nominal.world
        try:
            behaviour = self.fill_arms(nominal.behaviour(form), origin)
        except GroundingError as error:
            self.reject(level, layout, instruction, origin, f"{error.code}: {error.message}")
            return False
        degenerate = [p for step in behaviour.steps for p in degenerate_routes(step, world)]
        if degenerate:
            self.reject(level, layout, instruction, origin,
                        f"degenerate route: {'; '.join(degenerate)}")
            return False
        missing = self.repertoire.missing(behaviour, world, compose=level in COMPOSING_LEVELS)
        if missing:
            self.reject(level, layout, instruction, origin,
                        f"outside the training repertoire: {missing}")
            return False
        problems = infeasible(behaviour, world)
        if problems:
            self.reject(level, layout, instruction, origin, f"infeasible: {'; '.join(problems)}")
            return False
        unstable = instability(form, self.grounders_of(layout)[1:], behaviour, first_case=1)
        if unstable:
            self.reject(level, layout, instruction, origin, unstable)
            return False
        if task_id is None:
            task_id = f"{self.scene.id}/{level}/{origin}" + ("" if level == "L0" else f"@{layout}")
        self.seen[key] = task_id
        self.tasks.append(TestTask(id=task_id, scene=self.scene.id, level=level, layout=layout,
                                   instruction=instruction, form=form, behaviour=behaviour,
                                   origin=origin, wording=wording))
        return True

    def grounders_of(self, layout: str) -> list[Grounder]:
        if layout not in self.grounders:  # the corner worlds come first
            self.grounders[layout] = [Grounder(w) for w in jitter_worlds(self.scene, layout)]
        return self.grounders[layout]

    def level0(self) -> None:
        for task in self.scene.tasks:
            self.consider("L0", task.layout, task.paraphrases[0], task.forms[0], task.label,
                          "training")

    def level1(self) -> None:
        rule = self.scene.splits.get("L1")
        for index, layout in enumerate(rule.layouts if rule else ()):
            training = look_alike(self.scene, layout, self.scene.training_layouts)
            earlier = look_alike(self.scene, layout, rule.layouts[:index])
            for task in self.scene.tasks:
                if training or earlier:
                    self.reject("L1", layout, task.paraphrases[0], task.label,
                                f"{layout} looks the same as "
                                + (f"the training layout {training}" if training else
                                   f"{earlier}, earlier in the rule")
                                + " (identical-looking bodies trade places at most)")
                    continue
                self.consider("L1", layout, task.paraphrases[0], task.forms[0], task.label,
                              "training")

    def reworded(self, level: Level, layout: str, form: lf.Instruction, origin: str,
                 wordings: tuple[str, ...]) -> None:
        """Candidates from each generator, and from each pair of generators in rule order,
        considered in the order the cap ranks them (id digest) until the rule's `max` are kept:
        the cap could choose none after those."""
        if layout not in self.describers:
            self.describers[layout] = Describer(self.grounders_of(layout)[0], self.constructs)
        candidates = []
        for wording, novel in _variants(form, self.describers[layout], wordings):
            data = lf.to_json(novel)
            digest = hashlib.sha256(data.encode()).hexdigest()
            task_id = f"{self.scene.id}/{level}/{origin}@{layout}/{wording}-{digest[:8]}"
            candidates.append((_digest_of(task_id), task_id, wording, novel, data, digest))
        limit = self.scene.splits[level].max_tasks
        kept = 0
        for _, task_id, wording, novel, data, digest in sorted(candidates, key=lambda c: c[:2]):
            if limit is not None and kept >= limit:
                return
            text, unknown = self.speak(novel, int(digest[:8], 16))
            if data in self.training_forms:
                self.reject(level, layout, text, origin, "a training task has this form")
            elif unknown:
                words = ", ".join(sorted(value for _, value in unknown))
                self.reject(level, layout, text, origin, f"words no training instruction "
                                                         f"uses: {words}")
            else:
                kept += self.consider(level, layout, text, novel, origin, wording, task_id)

    def speak(self, form: lf.Instruction, pick: int) -> tuple[str, set]:
        """English for a form in the first style (from `pick` on) that uses only training
        words; else the first style's text and its unknown words."""
        styles = sorted(STYLES)
        first = None
        for offset in range(len(styles)):
            text = realize(form, styles[(pick + offset) % len(styles)])
            unknown = concepts(text) - self.vocabulary
            if not unknown:
                return text, set()
            first = first or (text, unknown)
        return first

    def cap(self, level: Level) -> None:
        """Keep at most the rule's `max` tasks of a level, spread over the (training task,
        layout) pairs they come from: a task ranks by its place in its pair's queue (ordered
        by id digest), then by its own id digest. The ranks do not depend on other tasks, so a
        new task or layout displaces only as many tests as it gets; the rest are rejected."""
        rule = self.scene.splits.get(level)
        tasks = [t for t in self.tasks if t.level == level]
        if rule is None or rule.max_tasks is None or len(tasks) <= rule.max_tasks:
            return
        queues: dict[tuple[str, str], int] = {}
        ranked = []
        for task in sorted(tasks, key=lambda t: (_digest_of(t.id), t.id)):
            pair = task.origin, task.layout
            queues[pair] = queues.get(pair, -1) + 1
            ranked.append(((queues[pair], _digest_of(task.id)), task.id))
        chosen = {task_id for _, task_id in sorted(ranked)[:rule.max_tasks]}
        for task in tasks:
            if task.id not in chosen:
                self.reject(level, task.layout, task.instruction, task.origin,
                            f"over the split's max of {rule.max_tasks} tasks")
        self.tasks = [t for t in self.tasks if t.level != level or t.id in chosen]

    def level2(self) -> None:
        rule = self.scene.splits.get("L2")
        for task in self.scene.tasks if rule else ():
            self.reworded("L2", task.layout, task.forms[0], task.label, rule.wordings)

    def level3(self) -> None:
        rule = self.scene.splits.get("L3")
        for task in [t for t in self.tasks if t.level == "L1"] if rule else []:
            if task.layout in rule.layouts:
                self.reworded("L3", task.layout, task.form, task.origin, rule.wordings)


def generate(spec: Spec, training: dict[str, Behaviour],
             levels: tuple[Level, ...] = ("L0", "L1", "L2", "L3")) -> Splits:
    """Test tasks for the given levels of every scene, with every rejected candidate."""
    tasks: list[TestTask] = []
    rejected: list[Rejection] = []
    training_forms = {lf.to_json(f) for t in spec.tasks for f in t.forms}
    vocabulary = {c for t in spec.tasks for p in t.paraphrases for c in concepts(p)}
    constructs = {c for t in spec.tasks for f in t.forms for c in lf.constructs(f)}
    for scene in spec.scenes.values():
        generator = _Generator(scene, training, training_forms, vocabulary, constructs)
        for level in levels:
            getattr(generator, f"level{level[1]}")()
            generator.cap(level)
        tasks += generator.tasks
        rejected += generator.rejected
    return Splits(tasks=tuple(tasks), rejected=tuple(rejected))

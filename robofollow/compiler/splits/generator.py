"""Split generation from rules: candidates for each level, each kept or rejected with a reason.

- L0: each training task's first paraphrase on its training layout.
- L1: training first paraphrases on the split rule's changed layouts.
- L2: the training layouts with new wording from the rule's generators (wordings.py): a
  logical form no training instruction has, said in words training instructions use.
- L3: the kept L1 tasks reworded the same way on their changed layouts.

A candidate is kept when it passes every rule of task_rules.py, the same check the audit
applies to a compiled task (grounding, also with the jitter at its extremes, route, repertoire,
feasibility, level, leakage, duplicates and truthful wording), so the audit of a fresh build
finds nothing the generator kept. A scene's candidates, words and rules come from its own
spec only: a scene's splits do not depend on the scenes compiled beside it. Tests a spec lists
are kept first and count toward the rule's `max`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterator
from dataclasses import dataclass

from robofollow.compiler.language import lf
from robofollow.compiler.language.lexicon import CONTEXTUAL
from robofollow.compiler.language.realize import STYLES, Realizer
from robofollow.compiler.scene.behaviour import Behaviour
from robofollow.compiler.scene.observation import look_alike
from robofollow.compiler.scene.spec import Level, Scene, Spec
from robofollow.compiler.splits.task_rules import TaskRules, arms_of
from robofollow.compiler.splits.tasks import Rejection, Splits, TestTask
from robofollow.compiler.splits.wordings import (
    GENERATORS,
    Describer,
    Rank,
    concepts,
    round_robin,
)

MOVED_LEVELS = ("L1", "L3")  # levels whose tasks say whether the referent's motion moved
_STYLES = sorted(STYLES)


def _digest_of(task_id: str) -> str:
    return hashlib.sha256(task_id.encode()).hexdigest()


def _rank(source: str) -> Rank:
    """The sort key of a choice's canonical text for one source's candidates: the digest of
    both, so the order is fixed by the source and its choices alone."""
    return lambda text: hashlib.sha256(f"{source}\0{text}".encode()).hexdigest()


def _variants(form: lf.Instruction, describer: Describer, wordings: tuple[str, ...],
              rank: Rank) -> Iterator[tuple[str, lf.Instruction]]:
    """(wording, form), lazily, the generators taking turns: each generator alone, then each
    ordered pair of the generators that reword one aspect ('referents' alone already varies
    every object), each in rank order."""
    streams = [_alone(form, describer, wording, rank) for wording in wordings]
    composable = [w for w in wordings if w != "referents"]
    streams += [_paired(form, describer, first, second, rank)
                for index, first in enumerate(composable) for second in composable[index + 1:]]
    return round_robin(streams)


def _alone(form: lf.Instruction, describer: Describer, wording: str,
           rank: Rank) -> Iterator[tuple[str, lf.Instruction]]:
    for novel in GENERATORS[wording](form, describer, rank):
        yield wording, novel


def _paired(form: lf.Instruction, describer: Describer, first: str, second: str,
            rank: Rank) -> Iterator[tuple[str, lf.Instruction]]:
    """The `second` generator's forms of each of the `first` generator's forms."""
    for middle in GENERATORS[first](form, describer, rank):
        for novel in GENERATORS[second](middle, describer, rank):
            yield f"{first}+{second}", novel


def motion_kind(rules: TaskRules, behaviour: Behaviour, layout: str, origin: str) -> str:
    """'as-trained' when the expert moves as the origin training task does, else 'moved'."""
    world = rules.grounders(layout)[0].world
    return "as-trained" if rules.repertoire.as_trained(behaviour, world, origin) else "moved"


@dataclass
class _Queue:
    """One source's reworded candidates (`_variants`), each built when it is examined, until
    the level's limit of them are kept."""
    origin: str
    layout: str
    variants: Iterator[tuple[str, lf.Instruction]]
    examined: int = 0
    kept: int = 0
    exhausted: bool = False

    def next(self) -> tuple[str, lf.Instruction] | None:
        """The next candidate, or None once there are no more."""
        found = next(self.variants, None)
        self.exhausted = found is None
        return found

    def done(self, limit: int | None) -> bool:
        return self.exhausted or (limit is not None and self.kept >= limit)


class _Generator:
    """One scene's splits: its own training words, forms and rules only."""

    def __init__(self, scene: Scene, training: dict[str, Behaviour],
                 listed: tuple[TestTask, ...]):
        self.scene = scene
        self.training = training
        self.vocabulary = {c for t in scene.tasks for p in t.paraphrases for c in concepts(p)}
        self.constructs = {c for t in scene.tasks for f in t.forms for c in lf.constructs(f)}
        self.rules = TaskRules(scene, training)
        self.listed = listed
        self.listed_count: dict[str, int] = {}
        self.tasks: list[TestTask] = []
        self.rejected: list[Rejection] = []
        self.describers: dict[str, Describer] = {}
        self.spoken: dict[tuple[str, str], tuple[str, str | None]] = {}
        self.unsaid: dict[tuple[int, str], tuple[lf.Body, bool]] = {}
        self.realizers = {name: Realizer(style) for name, style in STYLES.items()}

    def reject(self, level: Level, layout: str, instruction: str, origin: str,
               reason: str) -> None:
        self.rejected.append(Rejection(scene=self.scene.id, level=level, layout=layout,
                                       instruction=instruction, origin=origin, reason=reason))

    def consider(self, level: Level, layout: str, instruction: str, form: lf.Instruction,
                 origin: str, wording: str, task_id: str | None = None,
                 form_json: str | None = None) -> bool:
        """Keep the candidate as a test task, or reject it with the first rule it breaks;
        whether kept."""
        form_json = form_json or lf.to_json(form)
        examined = self.rules.examine(level, layout, instruction, form,
                                      arms_of(self.training[origin]), every=False,
                                      form_json=form_json)
        if examined.findings:
            kind, message = examined.findings[0]
            self.reject(level, layout, instruction, origin, f"{kind}: {message}")
            return False
        if task_id is None:
            task_id = f"{self.scene.id}/{level}/{origin}" + ("" if level == "L0" else f"@{layout}")
        motion = (motion_kind(self.rules, examined.behaviour, layout, origin)
                  if level in MOVED_LEVELS else None)
        rule = self.scene.splits.get(level)
        if motion == "as-trained" and rule is not None and rule.motion == "moved":
            self.reject(level, layout, instruction, origin,
                        f"as-trained: the expert moves as {origin} does")
            return False
        self.keep(TestTask(id=task_id, scene=self.scene.id, level=level, layout=layout,
                           instruction=instruction, form=form, behaviour=examined.behaviour,
                           origin=origin, wording=wording, motion=motion), form_json)
        return True

    def keep(self, task: TestTask, form_json: str | None = None) -> None:
        self.rules.keep(task.id, task.level, task.layout, task.form, form_json)
        self.tasks.append(task)

    def keep_listed(self, level: Level) -> None:
        """The spec's listed tests of a level, kept first."""
        listed = [t for t in self.listed if t.level == level]
        for task in listed:
            self.keep(task)
        self.listed_count[level] = len(listed)

    def level0(self) -> None:
        for task in self.scene.tasks:
            self.consider("L0", task.layout, task.paraphrases[0], task.forms[0], task.label,
                          "training")

    def level1(self) -> None:
        rule = self.scene.splits.get("L1")
        for index, layout in enumerate(rule.layouts if rule else ()):
            earlier = look_alike(self.scene, layout, rule.layouts[:index])
            for task in self.scene.tasks:
                if earlier:
                    self.reject("L1", layout, task.paraphrases[0], task.label,
                                f"duplicate: {layout} looks the same as {earlier}, earlier in "
                                "the rule (identical-looking bodies trade places at most)")
                    continue
                self.consider("L1", layout, task.paraphrases[0], task.forms[0], task.label,
                              "training")

    def reworded(self, level: Level, sources: list[tuple[str, lf.Instruction, str]],
                 wordings: tuple[str, ...]) -> None:
        """Candidates for each (layout, form, origin) source from each generator, and from
        each pair of generators in rule order, taking turns (`_variants`); a source's queue
        stops at the level's limit of kept ones. The queues take turns too, place by place
        (every queue's next kept candidate, in source order) until the kept ones so far fill
        the limit, and the rules weigh each candidate against the tasks kept before it."""
        limit = self.limit(level)
        queues = [self.queue(level, layout, form, origin, wordings)
                  for layout, form, origin in sources]
        order: dict[str, tuple[int, int]] = {}  # kept task id -> (queue, place)
        rank = 0
        while any(not queue.done(limit) for queue in queues):
            for index, queue in enumerate(queues):
                while queue.kept <= rank and self.examine_next(level, queue, index, limit,
                                                               order):
                    pass
            if limit is not None and sum(min(q.kept, rank + 1) for q in queues) >= limit:
                break
            rank += 1
        mine = [t for t in self.tasks if t.id in order]
        self.tasks = [t for t in self.tasks if t.id not in order] + sorted(
            mine, key=lambda t: order[t.id])

    def queue(self, level: Level, layout: str, form: lf.Instruction, origin: str,
              wordings: tuple[str, ...]) -> _Queue:
        """One source's candidates, in the order its rank gives (`_variants`)."""
        if layout not in self.describers:
            self.describers[layout] = Describer(self.rules.grounders(layout)[0],
                                                self.constructs)
        rank = _rank(f"{self.scene.id}/{level}/{origin}@{layout}")
        return _Queue(origin, layout, _variants(form, self.describers[layout], wordings, rank))

    def examine_next(self, level: Level, queue: _Queue, index: int, limit: int | None,
                     order: dict[str, tuple[int, int]]) -> bool:
        """Speak and consider the queue's next candidate; whether there was one."""
        found = None if queue.done(limit) else queue.next()
        if found is None:
            return False
        wording, novel = found
        place = queue.examined
        queue.examined += 1
        data = lf.to_json(novel)
        digest = hashlib.sha256(data.encode()).hexdigest()
        task_id = f"{self.scene.id}/{level}/{queue.origin}@{queue.layout}/{wording}-{digest[:8]}"
        text, problem = self.speak(novel, data, int(digest[:8], 16), queue.layout)
        if problem:
            self.reject(level, queue.layout, text, queue.origin, problem)
        elif self.consider(level, queue.layout, text, novel, queue.origin, wording, task_id,
                           data):
            queue.kept += 1
            order[task_id] = index, place
        return True

    def speak(self, form: lf.Instruction, form_json: str, pick: int,
              layout: str) -> tuple[str, str | None]:
        """English for a form in the first style (from `pick` on) that uses only the scene's
        training words and reads as it is scored; else the first style's text and why not."""
        first = None
        for offset in range(len(_STYLES)):
            style = _STYLES[(pick + offset) % len(_STYLES)]
            if offset and self.branch_unsaid(form, style):
                continue  # (the instruction says that word too: no need to speak it)
            text, problem = self.words(form, form_json, style)
            if problem is None:
                problems = self.rules.wording(layout, text, form, form_json)
                problem = f"wording: {problems[0]}" if problems else None
            if problem is None:
                return text, None
            first = first or (text, problem)
        return first

    def words(self, form: lf.Instruction, form_json: str, style: str) -> tuple[str, str | None]:
        """The form in a style, and why not if it uses words no training instruction of the
        scene uses (memoised: the same forms come up on other layouts and from other tasks)."""
        key = form_json, style
        if key not in self.spoken:
            text = self.realizers[style].instruction(form)
            unknown = concepts(text) - self.vocabulary
            words = ", ".join(sorted(value for _, value in unknown))
            self.spoken[key] = text, (f"words: no training instruction of {self.scene.id} "
                                      f"uses {words}" if unknown else None)
        return self.spoken[key]

    def branch_unsaid(self, form: lf.Instruction, style: str) -> bool:
        """Whether a branch of a conditional form says, in this style, a word no training
        instruction of the scene uses, whatever surrounds it (`lexicon.CONTEXTUAL` aside): then
        the instruction does too, as it says its branches word for word. (Most conditions and
        branches rewordings of a conditional keep a branch that some styles cannot say.)"""
        if not isinstance(form, lf.Conditional):
            return False
        for body in (form.then, form.otherwise):
            if body is None:
                continue
            key = id(body), style  # (the entry keeps its body alive: an id is not reused)
            hit = self.unsaid.get(key)
            if hit is None or hit[0] is not body:
                unknown = concepts(self.realizers[style].body(body)) - self.vocabulary
                hit = self.unsaid[key] = body, any(terminal not in CONTEXTUAL
                                                   for terminal, _ in unknown)
            if hit[1]:
                return True
        return False

    def cap(self, level: Level) -> None:
        """Keep at most the rule's `max` tasks of a level, listed tests first, then generated
        ones spread over the (training task, layout) pairs they come from: a task ranks by its
        place among its pair's kept tasks (the order its queue examined them), then by its
        own id digest. A pair's ranks do not depend on the other pairs' tasks, so a new task
        or layout displaces only as many tests as it gets; the rest are rejected."""
        limit = self.limit(level)
        tasks = [t for t in self.tasks if t.level == level and t.wording != "listed"]
        if limit is None or len(tasks) <= limit:
            return
        places: dict[tuple[str, str], int] = {}
        ranked = []
        for task in tasks:  # (a pair's tasks in the order its queue kept them)
            pair = task.origin, task.layout
            places[pair] = places.get(pair, -1) + 1
            ranked.append(((places[pair], _digest_of(task.id)), task.id))
        chosen = {task_id for _, task_id in sorted(ranked)[:limit]}
        maximum = self.scene.splits[level].max_tasks
        for task in tasks:
            if task.id not in chosen:
                self.reject(level, task.layout, task.instruction, task.origin,
                            f"over the split's max of {maximum} tasks")
        self.tasks = [t for t in self.tasks if t.level != level or t.wording == "listed"
                      or t.id in chosen]

    def limit(self, level: Level) -> int | None:
        """How many generated tasks a level keeps: its `max` less its listed tests."""
        rule = self.scene.splits.get(level)
        if rule is None or rule.max_tasks is None:
            return None
        return max(rule.max_tasks - self.listed_count.get(level, 0), 0)

    def level2(self) -> None:
        rule = self.scene.splits.get("L2")
        if rule:
            self.reworded("L2", [(t.layout, t.forms[0], t.label) for t in self.scene.tasks],
                          rule.wordings)

    def level3(self) -> None:
        rule = self.scene.splits.get("L3")
        generated_l1 = [t for t in self.tasks if t.level == "L1" and t.wording == "training"]
        if rule:
            self.reworded("L3", [(t.layout, t.form, t.origin) for t in generated_l1
                                 if t.layout in rule.layouts], rule.wordings)

    def run(self, levels: tuple[Level, ...]) -> None:
        for level in levels:
            self.keep_listed(level)
            getattr(self, f"level{level[1]}")()
            self.cap(level)


def generate(spec: Spec, training: dict[str, Behaviour], listed: tuple[TestTask, ...] = (),
             levels: tuple[Level, ...] = ("L0", "L1", "L2", "L3")) -> Splits:
    """Test tasks for the given levels of every scene (the spec's `listed` tests included),
    with every rejected candidate. Each scene is generated from its own spec alone."""
    return generate_examined(spec, training, listed, levels)[0]


def generate_examined(spec: Spec, training: dict[str, Behaviour],
                      listed: tuple[TestTask, ...] = (),
                      levels: tuple[Level, ...] = ("L0", "L1", "L2", "L3")
                      ) -> tuple[Splits, frozenset[TestTask]]:
    """`generate`, and the test tasks it examined by every rule of task_rules.py and kept
    (all but the listed ones): their verdicts, for the audit of these splits."""
    tasks: list[TestTask] = []
    rejected: list[Rejection] = []
    for scene in spec.scenes.values():
        generator = _Generator(scene, training, tuple(t for t in listed if t.scene == scene.id))
        generator.run(levels)
        tasks += generator.tasks
        rejected += generator.rejected
    examined = frozenset(task for task in tasks if task.wording != "listed")
    return Splits(tasks=tuple(tasks), rejected=tuple(rejected)), examined

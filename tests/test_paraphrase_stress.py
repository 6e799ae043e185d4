"""The paraphrase stress corpus (tests/data/stress/*.json): for every training task, natural
rewordings written for this project (synonyms, word order, adjuncts, politeness, clause order,
relative clauses, ellipsis, and the extended constructs), each with the behaviour it must
ground to on the task's training layout."""

import json
from functools import cache
from pathlib import Path

import pytest

from robofollow.compiler.authoring.spec_loader import load_spec
from robofollow.compiler.language.parser import parse
from robofollow.compiler.scene.behaviour import describe_steps
from robofollow.compiler.scene.grounding import Grounder
from robofollow.compiler.scene.world import World

DATA = Path(__file__).parent / "data"
SPECS = Path(__file__).resolve().parent.parent / "specs"
ENTRIES = [entry for file in sorted((DATA / "stress").glob("*.json"))
           for entry in json.loads(file.read_text())]
REWORDINGS = [(entry, text) for entry in ENTRIES for text in entry["rewordings"]]
TRAINING = json.loads((DATA / "training_instructions.json").read_text())


@cache
def grounder(scene: str, layout: str) -> Grounder:
    return Grounder(World(load_spec(SPECS).scenes[scene], layout))


def test_every_training_task_has_ten_new_rewordings():
    assert sorted(e["label"] for e in ENTRIES) == sorted(t["label"] for t in TRAINING)
    assert all(len(e["rewordings"]) >= 10 for e in ENTRIES), \
        [e["label"] for e in ENTRIES if len(e["rewordings"]) < 10]
    assert len(REWORDINGS) >= 750
    training = {p.lower() for t in TRAINING for p in t["paraphrases"]}
    texts = [text.lower() for _, text in REWORDINGS]
    assert len(set(texts)) == len(texts)  # no rewording twice
    assert not training & set(texts)  # none is a training paraphrase


@pytest.mark.parametrize("entry,text", REWORDINGS,
                         ids=[f"{e['scene']}:{e['label']}:{t[:40]}" for e, t in REWORDINGS])
def test_rewording_grounds_to_the_tasks_behaviour(entry, text):
    """The same steps (and for a conditional the same branch not taken); a rewording may state
    the condition the other way round ('if the bowl is empty, B; otherwise A')."""
    behaviour = grounder(entry["scene"], entry["layout"]).behaviour(parse(text))
    expected = entry["expect"].removeprefix("then: ").removeprefix("otherwise: ")
    assert describe_steps(behaviour.steps) == expected
    assert ("other" in entry) == (behaviour.branch is not None)
    if "other" in entry:
        assert behaviour.other is not None and describe_steps(behaviour.other) == entry["other"]

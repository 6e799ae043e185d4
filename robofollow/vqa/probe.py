"""`robofollow vqa`: head-camera images of a layout with questions and their answers.

DIR/images/<scene>_<layout>_<seed>.png  cam_high after the layout settles (jitter by seed)
DIR/questions.jsonl    one record per question: id, image, question, answer, expected, scene,
                       layout, seed
DIR/qa_lerobot.jsonl   the same as LeRobot-style records for co-training:
                       observation.images.cam_high (the image path), task (the question),
                       answer
DIR/qa_sharegpt.json   the same as image-grounded conversations (LLaVA / ShareGPT4V layout)

Each image is a new jitter seed (seed, seed + 1, ...) and contributes up to PER_IMAGE of its
uniquely answerable questions, drawn with its seed. The paper's QA-20 is asked of one image of
scene 2's default layout at its nominal positions.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image
from tqdm import tqdm

from robofollow.benchmark.episode import Benchmark
from robofollow.errors import RoboFollowError
from robofollow.files import write_json, write_jsonl
from robofollow.sim.stage import Stage
from robofollow.vqa import paper
from robofollow.vqa.questions import Question, questions

PER_IMAGE = 5
CAMERA = "cam_high"


def write_probe(compiled: Benchmark, scene_id: str, layout: str, out: Path, count: int,
                seed: int, qa20: bool = False, progress: bool = True) -> list[dict]:
    """Write `count` questions and their images to `out` (with `qa20`: the paper's 20)."""
    scene = compiled.spec.scenes[scene_id]
    count = len(paper.QA20) if qa20 else count
    (out / "images").mkdir(parents=True, exist_ok=True)
    records: list[dict] = []
    with Stage() as stage, tqdm(total=count, desc="questions", unit="question",
                                disable=not progress) as bar:
        image_seed = None if qa20 else seed  # QA-20: the nominal positions
        while len(records) < count:
            world = stage.simulation(scene, layout, render=True).reset(image_seed)
            chosen = ([question for question, _ in paper.answer_all(world)] if qa20 else
                      _draw(questions(world), min(PER_IMAGE, count - len(records)), image_seed))
            if not chosen:
                raise RoboFollowError(f"{scene_id}/{layout} (seed {image_seed}): no question "
                                      "has a unique answer")
            image = Path("images") / (f"{scene_id}_{layout}_" + (
                "nominal" if image_seed is None else f"{image_seed:06d}") + ".png")
            Image.fromarray(stage.cameras.render(CAMERA)).save(out / image)
            records += [_record(q, image, scene_id, layout, image_seed) for q in chosen]
            bar.update(len(chosen))
            image_seed = None if qa20 else image_seed + 1
    write_jsonl(out / "questions.jsonl", records)
    write_jsonl(out / "qa_lerobot.jsonl", [
        {f"observation.images.{CAMERA}": r["image"], "task": r["question"],
         "answer": r["answer"], "id": r["id"]} for r in records])
    write_json(out / "qa_sharegpt.json", [
        {"id": r["id"], "image": r["image"], "conversations": [
            {"from": "human", "value": f"<image>\n{r['question']}"},
            {"from": "gpt", "value": r["answer"]}]} for r in records])
    return records


def _draw(pool: list[Question], count: int, seed: int) -> list[Question]:
    if len(pool) <= count:
        return pool
    picked = np.random.default_rng(seed).choice(len(pool), size=count, replace=False)
    return [pool[i] for i in sorted(picked)]


def _record(question: Question, image: Path, scene: str, layout: str,
            seed: int | None) -> dict:
    image_id = "nominal" if seed is None else seed
    return {"id": f"{scene}/{layout}/{image_id}/{question.id}", "image": image.as_posix(),
            "question": question.question, "answer": question.answer,
            "expected": question.expected.model_dump(mode="json"), "scene": scene,
            "layout": layout, "seed": seed}

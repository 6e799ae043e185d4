"""An episode's hash: over what decides the episode and nothing else, so that an episode no
change touched keeps its hash from one release to the next (and runs of two releases pair on
it). What decides an episode: the world it starts in (the layout's bodies as placed there,
where they stand, their jitter, the table's height), and the record's id, layout, seed,
instruction and behaviour. Not its scene's other layouts, tasks or split rules, not its motion
label or logical form (read off the rest), not the split it belongs to."""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping

from robofollow.compiler.scene.spec import Scene
from robofollow.files import json_line_of, json_value

HASHED = ("episode", "scene", "layout", "seed", "instruction", "behaviour")  # record fields


def world_digest(scene: Scene, layout: str) -> str:
    """sha256 over the world an episode on `layout` starts in: its bodies as placed there
    (kind, size, colour), where they stand and on what, their jitter, the table's height (in
    the layout's order, which the jitter draws follow)."""
    placed = scene.layouts[layout].placed
    world = {"bodies": {name: body.model_dump(mode="json")
                        for name, body in scene.bodies_in(layout).items()},
             "placed": {name: spot.model_dump(mode="json") for name, spot in placed.items()},
             "jitter": {name: scene.jitter_of(name).model_dump(mode="json") for name in placed},
             "table_height": scene.table_height}
    return hashlib.sha256(json.dumps(world).encode()).hexdigest()


def episode_hash(world: str, encoded: Mapping[str, str]) -> str:
    """An episode's hash (16 hex digits): sha256 over its world digest and its HASHED fields,
    each encoded as files.json_value writes it."""
    content = world + json_line_of({key: encoded[key] for key in HASHED})
    return hashlib.sha256(content.encode()).hexdigest()[:16]


def record_hash(scene: Scene, record: Mapping, worlds: dict | None = None) -> str:
    """The hash of an episode record as a release or a build holds it (JSON values);
    `worlds` caches world digests by (scene, layout) over many records."""
    key = (scene.id, record["layout"])
    worlds = {} if worlds is None else worlds
    if key not in worlds:
        worlds[key] = world_digest(scene, record["layout"])
    return episode_hash(worlds[key], {field: json_value(record[field]) for field in HASHED})

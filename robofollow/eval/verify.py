"""The scripted expert on compiled episodes in simulation, each scored by the oracle: what
`robofollow compile --verify` and bench/expert_success.py run. A task whose expert episode
is not scored in full (Intent 1, Execution 1, complete) is listed with the stages it lost."""

from __future__ import annotations

import multiprocessing
from pathlib import Path

from tqdm import tqdm

from robofollow.build import compile_specs

_SCENES: dict = {}


def _init(specs: str) -> None:
    _SCENES.update(compile_specs(Path(specs)).spec.scenes)


def _run(episode: dict) -> dict:
    from robofollow.sim.rollout import run_expert

    try:
        result = run_expert(_SCENES[episode["scene"]], episode).summary()
    except Exception as error:  # a crash is a failure with its cause, not a lost episode
        result = {"episode": episode["episode"], "achieved": False, "steps": 0, "seconds": 0.0,
                  "intent_score": 0.0, "execution_score": 0.0,
                  "reasons": [f"{type(error).__name__}: {error}"]}
    full = result["achieved"] and min(result["intent_score"], result["execution_score"]) >= 0.99
    return dict(result, full=full, scene=episode["scene"], level=episode["level"])


def run_expert_episodes(specs: Path, episodes: list[dict], workers: int,
                        quiet: bool = False) -> list[dict]:
    """Each episode's expert result (`full`, `reasons`, scores, `scene`, `level`), sorted by
    episode id; `workers` processes, each compiling `specs` once."""
    with multiprocessing.get_context("spawn").Pool(workers, _init, (str(specs),)) as pool:
        results = list(tqdm(pool.imap_unordered(_run, episodes, chunksize=4),
                            total=len(episodes), desc="expert episodes", unit="ep",
                            mininterval=10, disable=quiet))
    return sorted(results, key=lambda r: r["episode"])

"""The scripted expert on compiled episodes in simulation, each scored by the oracle: what
`robofollow compile --verify` / `--verify-all` and bench/expert_success.py run. A task whose expert episode
is not scored in full (Intent 1, Execution 1, complete) is listed with the stages it lost; an
episode whose worker process died (a crash in the simulator) is listed with how it ended."""

from __future__ import annotations

from functools import partial
from pathlib import Path

from tqdm import tqdm

from robofollow.benchmark.episode import Episode
from robofollow.compiled_cache import load
from robofollow.workers import results


def _failed(episode: Episode, reason: str) -> dict:
    return {"episode": episode.id, "achieved": False, "steps": 0, "seconds": 0.0,
            "intent_score": 0.0, "execution_score": 0.0, "reasons": [reason],
            "full": False, "scene": episode.scene, "level": episode.level}


class _Verifier:
    """One worker process: the compiled benchmark, then episodes one at a time."""

    def __init__(self, specs: str):
        self.compiled = load(Path(specs))

    def __call__(self, episode: Episode) -> dict:
        from robofollow.sim.rollout import run_expert

        try:
            result = run_expert(self.compiled, episode).summary()
        except Exception as error:  # a crash is a failure with its cause, not a lost episode
            return _failed(episode, f"{type(error).__name__}: {error}")
        full = (result["achieved"]
                and min(result["intent_score"], result["execution_score"]) >= 0.99)
        return dict(result, full=full, scene=episode.scene, level=episode.level)

    def close(self) -> None:
        pass


def _lost(episode: Episode, what: str) -> dict:
    return _failed(episode, f"the worker process {what} during the episode")


def run_expert_episodes(specs: Path, episodes: list[Episode], workers: int,
                        quiet: bool = False) -> list[dict]:
    """Each episode's expert result (`full`, `reasons`, scores, `scene`, `level`), sorted by
    episode id; `workers` supervised processes, each reading `specs` compiled from the cache
    (compiled_cache)."""
    found = tqdm(results(partial(_Verifier, str(specs)), episodes, workers, lost=_lost,
                         isolate=True),
                 total=len(episodes), desc="expert episodes", unit="ep", mininterval=10,
                 disable=quiet)
    return sorted(found, key=lambda r: r["episode"])

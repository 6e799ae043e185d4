"""What a policy did in an episode, as the reports count it: the behaviour closest to what
the arms did (as instructed, a conditional's other branch, a training task) or, where none is
close, what kind of nothing it was; and the first stage that failed, with its reason.

Read from full records (RUN/episodes.jsonl) and from the compact records of a score file
(scores.py), which carry both answers already worked out ("did", "first_failure")."""

from __future__ import annotations

from robofollow.oracle.instead import NOTHING_MOVED, TOUCHED_NOTHING

AS_INSTRUCTED, TRAINING, OTHER_BRANCH = "as instructed", "another training task", "other branch"
STILL, UNTOUCHED, UNTRAINED = ("nothing moved", "moved but touched nothing",
                               "handled objects in no trained way")
UNRECORDED = "touched nothing, arm motion not recorded"  # records before arms_moved
UNRECOGNISED = (STILL, UNTOUCHED, UNTRAINED, UNRECORDED)  # no known behaviour is close
DID = (AS_INSTRUCTED, TRAINING, OTHER_BRANCH, *UNRECOGNISED)
NO_CONTACT = (NOTHING_MOVED, TOUCHED_NOTHING)  # the oracle's words where nothing was touched


def closest(record: dict) -> str:
    """The behaviour closest to what the arms did: as instructed, the other branch, a training
    task's label, or the kind of unrecognised behaviour (UNRECOGNISED)."""
    if "did" in record:  # a compact record
        return record["did"]
    behaviour = record["executed_behaviour"] or {}
    match = behaviour.get("match")
    if match:
        return {"instructed": AS_INSTRUCTED, "other branch": OTHER_BRANCH}.get(match, match)
    if behaviour.get("description") not in NO_CONTACT:
        return UNTRAINED
    moved = behaviour.get("arms_moved")
    return UNRECORDED if moved is None else UNTOUCHED if moved else STILL


def kinds(records: list[dict]) -> tuple[str, ...]:
    """The rows of the "what the policy did" table: DID, but UNRECORDED where no record is."""
    return tuple(k for k in DID if k != UNRECORDED
                 or any(closest(r) == UNRECORDED for r in records))


def kind(record: dict) -> str:
    """The row of the reports' "what the policy did" table (DID) the episode counts in."""
    found = closest(record)
    return found if found in DID else TRAINING


def first_failure(record: dict) -> tuple[str, str] | None:
    """The first stage that did not earn full credit, and why; None for a perfect episode."""
    if "first_failure" in record:  # a compact record
        return record["first_failure"]
    failed = next((s for s in record["stages"]
                   if s["intent"] < s["weight"] or s["execution"] < s["weight"]), None)
    return None if failed is None else (failed["stage"], failed["reason"])

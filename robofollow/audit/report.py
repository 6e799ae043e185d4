"""The audit as a report: its finding lists, and a benchmark's audit put together from its
scenes' parts."""

from __future__ import annotations

from robofollow.audit.entropy import behaviour_entropy_bits, entropy_bits

# the audit's finding lists, by the rule kinds that fill them
FINDING_LISTS = {"leakage": ("leakage",), "level_inconsistencies": ("level",),
                 "repertoire_violations": ("repertoire",), "degenerate_routes": ("route",),
                 "infeasible": ("infeasible",), "duplicates": ("duplicate",),
                 "ambiguities": ("ambiguous", "no-referent"),
                 "misleading_wordings": ("wording",)}
FINDING_KEYS = tuple(FINDING_LISTS)


KEYED = ("counts", "blind_best")  # {scene: ...} in a scene's part
RULES_KEYED, RULES_LISTED = ("layouts",), ("capped", "warnings")  # in its split_rules
TOTALS = ("spec_digest", "scene_entropy_bits", "behaviour_entropy_bits")  # what combine adds


def combine(digest: str, parts: list[dict]) -> dict:
    """The audit of a benchmark from its scenes' parts, in scene order (`scene_audit`, with
    whatever else is kept by scene beside it, or audits `combine` made of some scenes):
    {scene: ...} entries side by side, lists one after the other, rejected candidates summed,
    and the TOTALS over every scene's groups. What a benchmark audits is its scenes' parts,
    so a scene compiled alone or beside others contributes the same."""
    report: dict = {"spec_digest": digest, "rejected": sum(part["rejected"] for part in parts),
                    "counts": {}, "groups": [], "same_behaviour": [],
                    **{key: [] for key in FINDING_KEYS},
                    "split_rules": {key: {} for key in RULES_KEYED}
                    | {key: [] for key in RULES_LISTED}}
    for part in parts:
        for key, value in part.items():
            if key == "split_rules":
                for inner, entries in value.items():
                    if inner in RULES_KEYED:
                        report[key][inner].update(entries)
                    else:
                        report[key][inner] += entries
            elif key in KEYED:
                report.setdefault(key, {}).update(value)
            elif key not in ("rejected", *TOTALS):
                report.setdefault(key, []).extend(value)
    groups = report["groups"]
    report["scene_entropy_bits"] = round(entropy_bits([len(g["tasks"]) for g in groups]), 6)
    report["behaviour_entropy_bits"] = round(behaviour_entropy_bits(
        [[len(b) for b in g["behaviours"]] for g in groups]), 6)
    return report


def findings(report: dict) -> int:
    return sum(len(report[k]) for k in FINDING_KEYS)

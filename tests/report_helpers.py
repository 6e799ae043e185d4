"""Hand-made run result records and options, for the report tests."""

from __future__ import annotations

from robofollow.eval.running.runner import EvalOptions

OPTIONS = EvalOptions("mine:make", ("scene2",), ("L0", "L1"), 1, "normal", "none", "0" * 64)


def fake_record(task: str, level: str, intent: float, execution: float, complete: bool,
                match: str | None, reason: str = "", error: str | None = None,
                instruction: str = "", layout: str = "default") -> dict:
    stages = [{"stage": "source", "name": "source_grounding", "weight": 0.8,
               "intent": 0.8 * intent, "execution": 0.8 * execution, "first_step": None,
               "reason": reason},
              {"stage": "finish", "name": "finish", "weight": 0.2, "intent": 0.2 * intent,
               "execution": 0.2 * execution, "first_step": None, "reason": ""}]
    return {"episode": f"scene2/{level}/{task}#r1", "scene": "scene2", "level": level,
            "task": f"scene2/{level}/{task}", "layout": layout,
            "instruction": instruction or f"Use your left arm to {task.replace('_', ' ')}.",
            "intent_score": intent,
            "execution_score": execution, "complete": complete, "stages": stages,
            "executed_behaviour": {"match": match, "description": "", "behaviour": None,
                                   "intent_score": 0, "execution_score": 0},
            "error": error}

"""Split validity on generated specs: the compiled splits always pass their own audit."""

import math
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings

from robofollow.build import compile_specs
from robofollow.oracle.audit import FINDING_KEYS, findings, leakage
from tests.strategies import small_specs

HEAVY = settings(max_examples=25, deadline=None,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def compile_text(text: str):
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "demo.rf").write_text(text)
        return compile_specs(Path(folder))


@HEAVY
@given(generated=small_specs())
def test_compiled_splits_pass_the_audit(generated):
    text, _ = generated
    compiled = compile_text(text)
    report = compiled.report
    assert findings(report) == 0, {key: report[key] for key in FINDING_KEYS if report[key]}
    ids = [t.id for t in compiled.splits.tasks]
    assert len(ids) == len(set(ids))
    assert len(compiled.splits.of("demo", "L0")) <= len(compiled.spec.tasks)


@HEAVY
@given(generated=small_specs())
def test_entropy_is_the_group_formula(generated):
    text, sizes = generated
    report = compile_text(text).report
    expected = sum(k / sum(sizes) * math.log2(k) for k in sizes)
    assert math.isclose(report["scene_entropy_bits"], expected, abs_tol=1e-6)


@HEAVY
@given(generated=small_specs())
def test_injected_leaks_are_always_caught(generated):
    text, _ = generated
    compiled = compile_text(text)
    spec, splits = compiled.spec, compiled.splits
    training = spec.tasks[0]
    victim = (splits.of("demo", "L1") + splits.of("demo", "L2") + splits.of("demo", "L0"))[0]
    copied = victim.model_copy(update={"id": victim.id + "/copied", "level": "L2",
                                       "form": training.forms[0]})
    named = victim.model_copy(update={"id": victim.id + "/named",
                                      "instruction": f"{victim.instruction} ({training.label})"})
    tampered = splits.model_copy(update={"tasks": splits.tasks + (copied, named)})
    flagged = {f["task"] for f in leakage(spec, tampered)}
    assert {copied.id, named.id} <= flagged

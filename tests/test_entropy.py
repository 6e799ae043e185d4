"""Scene entropy: the shipped benchmark's 3.782 bits, and LIBERO's suites from a small spec."""

from pathlib import Path

import pytest

from robofollow.audit.entropy import entropy_bits, scene_entropy, scene_groups
from robofollow.compiler.authoring.spec_loader import load_spec

SPECS = Path(__file__).resolve().parent.parent / "specs"


def test_the_benchmark_has_six_groups_and_3_782_bits():
    spec = load_spec(SPECS)
    sizes = sorted(len(g["tasks"]) for g in scene_groups(spec))
    assert sizes == [4, 7, 16, 16, 16, 16]
    assert round(scene_entropy(spec), 3) == 3.782


def _suite(name: str, tasks_per_layout: list[int]) -> str:
    """A scene whose layouts each hold the given number of tasks (same objects throughout)."""
    lines = [f'scene {name} "{name}" {{',
             "    object cube cube half=0.02 color=red rgb=(1, 0, 0) mass=0.2 friction=0.1"]
    for index, count in enumerate(tasks_per_layout):
        lines.append(f"    layout l{index} {{ cube at ({index * 0.01:.2f}, 0) }}")
        for task in range(count):
            lines += [f"    task {name}_{index}_{task} on l{index} {{",
                      '        "Pick up the red cube with your left arm."', "    }"]
    return "\n".join(lines + ["}"])


LIBERO = {  # suite -> tasks per initial scene, as LIBERO groups its ten tasks
    "spatial": [1] * 10,
    "object": [1] * 10,
    "goal": [10],
    "long": [2] + [1] * 8,
}


@pytest.mark.parametrize("suite,bits", [("spatial", 0.0), ("object", 0.0), ("goal", 3.322),
                                        ("long", 0.200)])
def test_libero_suite_entropies(tmp_path, suite, bits):
    (tmp_path / f"{suite}.rf").write_text(_suite(suite, LIBERO[suite]))
    assert round(scene_entropy(load_spec(tmp_path)), 3) == bits


def test_libero_mean_is_0_880(tmp_path):
    values = []
    for suite, sizes in LIBERO.items():
        folder = tmp_path / suite
        folder.mkdir()
        (folder / "suite.rf").write_text(_suite(suite, sizes))
        values.append(scene_entropy(load_spec(folder)))
    assert round(sum(values) / 4, 3) == 0.880


def test_entropy_formula():
    assert entropy_bits([]) == 0.0
    assert entropy_bits([1, 1, 1]) == 0.0
    assert entropy_bits([4]) == 2.0
    assert entropy_bits([2, 2]) == 1.0

"""`robofollow expert` and `robofollow render`."""

from __future__ import annotations

import json

import av
import numpy as np
from PIL import Image

from robofollow.resources import builtin_specs
from tests.cli_helpers import run

SPECS = str(builtin_specs())


def test_expert_json(capsys):
    status, out, _ = run(capsys, "expert", "--episode", "scene1/L0/pickup_yellow_block_2#r1",
                         "--specs", SPECS, "--json")
    result = json.loads(out)
    assert status == 0
    assert result["episode"] == "scene1/L0/pickup_yellow_block_2#r1"
    assert result["achieved"] is True and result["reasons"] == []
    assert result["steps"] > 50 and result["seconds"] > 0


def test_expert_video_has_three_cameras_side_by_side(capsys, tmp_path):
    video, saved = tmp_path / "out.mp4", tmp_path / "t.npz"
    status, out, _ = run(capsys, "expert", "--episode", "scene2/L0/pickup_left_cube#r1",
                         "--specs", SPECS, "--video", str(video), "--trajectory", str(saved),
                         "--image-size", "160x120")
    assert status == 0 and "achieved in" in out
    with av.open(str(video)) as container:
        frames = [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]
    steps = int(out.split("achieved in ")[1].split()[0])
    assert len(frames) == steps + 1 and frames[0].shape == (120, 480, 3)
    assert np.load(saved)["positions"].shape[0] == steps + 1


def test_expert_unknown_episode_is_a_clear_error(capsys):
    status, _, err = run(capsys, "expert", "--episode", "scene2/L0/pickup_left_cub#r1",
                         "--specs", SPECS)
    assert status == 1
    assert "no episode 'scene2/L0/pickup_left_cub#r1'" in err and "pickup_left_cube#r1" in err
    assert "Traceback" not in err


def test_render_draws_head_and_top_views(capsys, tmp_path):
    out_file = tmp_path / "s.png"
    status, out, _ = run(capsys, "render", "--scene", "scene3", "--layout", "scene3_2", "-o",
                         str(out_file), "--specs", SPECS, "--image-size", "320x240")
    assert status == 0 and "scene3/scene3_2" in out
    image = np.asarray(Image.open(out_file))
    assert image.shape == (240, 640, 3)
    assert image[:, :320].std() > 10 and image[:, 320:].std() > 10


def test_render_unknown_layout(capsys, tmp_path):
    status, _, err = run(capsys, "render", "--scene", "scene3", "--layout", "nowhere", "-o",
                         str(tmp_path / "x.png"), "--specs", SPECS)
    assert status == 1 and "has no layout 'nowhere'" in err and "scene3_1" in err


SLIPPERY = """\
scene tiny "Two cubes, one too heavy and slippery to lift" {
    object red_cube  cube half=0.02 color=red  rgb=(1, 0, 0) mass=0.2 friction=0.5
    object blue_cube cube half=0.02 color=blue rgb=(0, 0, 1) mass=5.0 friction=0.01
    layout base {
        red_cube  at (-0.08, -0.10)
        blue_cube at (0.08, -0.10)
    }
    task pick_red on base {
        "Use your left arm to pick up the red cube."
    }
    task pick_blue on base {
        "Use your right arm to pick up the blue cube."
    }
}
"""


def test_compile_verify_lists_what_only_simulation_finds(capsys, tmp_path):
    """Both tasks are feasible by geometry; the expert cannot lift the slippery cube."""
    (tmp_path / "specs").mkdir()
    (tmp_path / "specs" / "tiny.rf").write_text(SLIPPERY)
    status, out, _ = run(capsys, "compile", str(tmp_path / "specs"), "--out",
                         str(tmp_path / "build"), "--verify", "--workers", "1")
    assert status == 1
    assert "the expert on 2 episodes (1 round of every test task)" in out
    assert "the expert scored in full on 1 of 2; failures: 1" in out
    assert "tiny/L0/pick_blue#r1: source: grasped blue_cube" in out and "but lifted it" in out

"""Where the ViperX 300 s arm meshes come from: the installed `robosuite-models` package.

The meshes are read at run time from that package (MIT; the ALOHA meshes carry Trossen's
BSD-3 notice); nothing of it is copied into this project. The package is located without
importing it (its __init__ needs robosuite, which we do not use).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from robofollow.errors import RoboFollowError

ARM_MESHES = ("vx300s_1_base", "vx300s_2_shoulder", "vx300s_3_upper_arm",
              "vx300s_4_upper_forearm", "vx300s_5_lower_forearm", "vx300s_6_wrist")


class AssetError(RoboFollowError):
    """A simulation asset is missing."""


def mesh_dir() -> Path:
    """The folder holding the ViperX 300 s STL meshes."""
    spec = importlib.util.find_spec("robosuite_models")
    if spec is None or not spec.submodule_search_locations:
        raise AssetError("the arm meshes come from the 'robosuite-models' package, which is not "
                         "installed: pip install robosuite-models")
    folder = Path(list(spec.submodule_search_locations)[0]) / "assets" / "robots" / "aloha" / "meshes"
    missing = [name for name in ARM_MESHES if not (folder / f"{name}.stl").is_file()]
    if missing:
        raise AssetError(f"robosuite-models at {folder} lacks meshes: {', '.join(missing)}")
    return folder

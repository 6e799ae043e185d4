#!/usr/bin/env bash
# Install RoboFollow (editable, with the test tools) and what headless MuJoCo rendering needs:
# Mesa's EGL from the Debian/Ubuntu packages below (skipped when already present).
# The Python packages come at the versions in requirements.lock, the ones the shipped results
# (docs/results) and CI were made with. ROBOFOLLOW_UNLOCKED=1 ./setup.sh installs without the lock:
# the newest releases that pyproject.toml's bounds allow. Trajectory hashes reproduce bit for bit
# only with the locked versions and the same kind of CPU; scores almost always, not always.
set -euo pipefail
cd "$(dirname "$0")"
PACKAGES="libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1"
if command -v dpkg >/dev/null 2>&1; then
    missing=""
    for package in $PACKAGES; do
        dpkg -s "$package" >/dev/null 2>&1 || missing="$missing $package"
    done
    if [ -n "$missing" ]; then
        sudo=""
        [ "$(id -u)" -ne 0 ] && sudo="sudo"
        echo "installing for headless rendering:$missing"
        $sudo apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing
    fi
else
    echo "note: not a Debian/Ubuntu system; make sure Mesa EGL (or OSMesa, with MUJOCO_GL=osmesa)" \
         "is installed for headless rendering" >&2
fi
if [ "${ROBOFOLLOW_UNLOCKED:-0}" = "1" ]; then
    echo "ROBOFOLLOW_UNLOCKED=1: installing without requirements.lock"
    pip install -e '.[test]'
else
    pip install -c requirements.lock -e '.[test]'
fi

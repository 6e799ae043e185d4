#!/usr/bin/env bash
# Install RoboFollow (editable) and what headless MuJoCo rendering needs: Mesa's EGL from the
# Debian/Ubuntu packages below (skipped when already present).
#   ./setup.sh          with the test tools (the extra `test`: JAX, Ray, vla-eval, pytest, ...)
#   ./setup.sh figures  only what evaluating and reporting need (any extras, comma-separated:
#                       figures, train, ray, vla-eval; see pyproject.toml)
# It installs into the Python that `python3` is: a virtual environment's when one is active. A
# system Python that refuses pip (Debian's, "externally managed") is refused here, with the
# commands that make a virtual environment.
# The Python packages come at the versions in requirements.lock, the ones the shipped results
# (docs/results) and CI were made with. ROBOFOLLOW_UNLOCKED=1 ./setup.sh installs without the lock:
# the newest releases that pyproject.toml's bounds allow. Trajectory hashes reproduce bit for bit
# only with the locked versions and the same kind of CPU; scores almost always, not always.
set -euo pipefail
cd "$(dirname "$0")"
EXTRAS="${1:-test}"
if python3 - <<'PY'
import os, sys, sysconfig
managed = os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED")
sys.exit(0 if sys.prefix == sys.base_prefix and os.path.exists(managed) else 1)
PY
then
    echo "error: $(command -v python3) is the system's Python, which refuses pip installs" \
         "(externally managed); make a virtual environment and run setup.sh in it:" >&2
    echo "  python3 -m venv .venv && . .venv/bin/activate && ./setup.sh $*" >&2
    exit 1
fi
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
echo "installing RoboFollow[$EXTRAS] into $(python3 -c 'import sys; print(sys.prefix)')"
if [ "${ROBOFOLLOW_UNLOCKED:-0}" = "1" ]; then
    echo "ROBOFOLLOW_UNLOCKED=1: installing without requirements.lock"
    python3 -m pip install -e ".[$EXTRAS]"
else
    python3 -m pip install -c requirements.lock -e ".[$EXTRAS]"
fi

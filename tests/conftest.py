"""Hypothesis profiles: `dev` (quick, default) and `ci` (more examples, derandomized);
RoboFollow imported first, so MuJoCo loads with the headless GL default whatever the test
modules import first; and `stage`, one simulation + renderer shared by a test module."""

import os

import pytest
from hypothesis import HealthCheck, settings

import robofollow  # noqa: F401

settings.register_profile("dev", max_examples=60, deadline=None)
settings.register_profile("ci", max_examples=400, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") else "dev"))


@pytest.fixture(scope="module")
def stage():
    from robofollow.sim.stage import Stage

    with Stage() as shared:
        yield shared

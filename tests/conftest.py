"""Shared fixtures: headless rendering, offline hub, small fast envs."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("HF_HUB_OFFLINE", "1")

import pytest  # noqa: E402
import robosuite as suite  # noqa: E402

import colorsort  # noqa: E402,F401  (registers the task)


def make_env(robot: str = "IRB140", **kwargs):
    """A ColorSort env without cameras unless asked for; episodes never end on their own."""
    kwargs.setdefault("has_offscreen_renderer", False)
    kwargs.setdefault("use_camera_obs", False)
    kwargs.setdefault("ignore_done", True)
    kwargs.setdefault("seed", 0)
    return suite.make("ColorSort", robots=robot, **kwargs)


@pytest.fixture
def env():
    e = make_env()
    e.reset()
    yield e
    e.close()

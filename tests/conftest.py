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


TINY = dict(episodes=2, image_size=(64, 64), cameras=("scene", "wrist"))  # two one-box episodes


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory):
    """Two one-box episodes of the expert, 64x64 scene and wrist cameras, recorded once per session."""
    from colorsort.data.collect import collect
    from colorsort.data.config import CollectConfig

    root = tmp_path_factory.mktemp("datasets") / "tiny"
    summary = collect(CollectConfig(out=str(root), **TINY), progress=False, log=lambda _: None)
    assert summary.kept == 2 and not summary.errors, summary
    return root

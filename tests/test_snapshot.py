"""The snapshot camera: the sensor's photo taken when the ray starts seeing a box, held until the next."""

import numpy as np
import pytest

from colorsort.cell.snapshot import Snapshot
from colorsort.data.collect import collect
from colorsort.data.config import CollectConfig
from colorsort.data.replay import MIN_PSNR_DB, replay
from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.expert.factory import make_expert


def test_latch_takes_a_photo_on_the_rays_rising_edge_only():
    shots = iter(np.full((4, 6, 3), k, np.uint8) for k in (10, 20, 30))
    latch = Snapshot()
    assert not latch.image(6, 4).any()  # black before the first box; asking registers the size
    render = lambda w, h: next(shots)  # noqa: E731
    latch.observe(False, render)
    assert not latch.image(6, 4).any()
    latch.observe(True, render)
    assert (latch.image(6, 4) == 10).all() and latch.triggers == 1
    latch.observe(True, render)  # the same box still at the ray: no new photo
    latch.observe(False, render)  # the box was picked: the photo is held
    assert (latch.image(6, 4) == 10).all()
    latch.observe(True, render)
    assert (latch.image(6, 4) == 20).all() and latch.triggers == 2
    latch.image(6, 4)[:] = 0  # a caller's copy: the held photo is untouched
    assert (latch.image(6, 4) == 20).all()
    latch.clear()
    assert not latch.image(6, 4).any() and latch.triggers == 0


def test_snapshot_holds_the_sensors_view_of_the_arriving_box(make_env):
    env = make_env(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["sensor", "snapshot"],
                   camera_heights=32, camera_widths=32, spawn_period=600.0)
    obs = env.reset()
    hold = np.r_[env.robots[0].init_qpos, 0.0, -1.0]
    assert not obs["snapshot_image"].any()
    x, y, _ = env.layout.pick_point
    box = env.put_box("red", x, y)
    obs, *_ = env.step(hold)
    assert env.box_detected
    assert np.array_equal(obs["snapshot_image"], obs["sensor_image"])
    red = obs["snapshot_image"][..., 0].astype(int) - obs["snapshot_image"][..., 1]
    assert (red > 100).sum() >= 4  # the red box is in the photo
    photo = obs["snapshot_image"]
    env.remove_box(box)  # the box leaves the sensor's view: the live view changes, the photo does not
    obs, *_ = env.step(hold)
    assert not env.box_detected and not np.array_equal(obs["sensor_image"], photo)
    assert np.array_equal(obs["snapshot_image"], photo)
    with pytest.raises(ValueError, match="no depth"):
        env.camera_image("snapshot", 32, 32, depth=True)
    assert not env.reset()["snapshot_image"].any()


def test_recorded_snapshots_replay_from_the_states(tmp_path):
    root = tmp_path / "snap"
    summary = collect(CollectConfig(out=str(root), episodes=1, boxes_per_episode=1, image_size=(32, 32),
                                    cameras=("snapshot",)), progress=False, log=lambda _: None)
    assert summary.kept == 1
    report = replay(root, 0, "snapshot", None, progress=False)
    assert report.state_mismatches == 0 and report.min_psnr_db >= MIN_PSNR_DB


@pytest.mark.slow
def test_over_the_experts_carry_the_snapshot_shows_the_box_in_the_cup(make_env):
    """The photo is of the box the cup holds at every step of every carry, turned and offset boxes too."""
    env = make_env(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["sensor", "snapshot"],
                   camera_heights=32, camera_widths=32, lateral_jitter=0.05, yaw_jitter=45.0)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    pick_xy = np.array(env.layout.pick_point[:2])
    photographed, carried, saw_box = None, 0, False
    while len(env.events) < 3 and env.cur_time < 60.0:
        obs, *_ = env.step(expert.act(obs))
        if env.box_detected and not saw_box:  # the photo is taken now: of the box nearest the ray
            photographed = min(env.boxes_in_play(), key=lambda b: np.linalg.norm(env.box_pos(b)[:2] - pick_xy))
            assert np.array_equal(obs["snapshot_image"], obs["sensor_image"])
        saw_box = env.box_detected
        if env.plant.seal.held is not None:
            assert env.boxes[env.plant.seal.held] is photographed
            carried += 1
    assert [e.outcome for e in env.events[:3]] == ["placed"] * 3 and carried > 60


def test_a_gymnasium_env_renders_the_snapshot_for_a_policy(closing):
    env = closing(ColorSortGymEnv("default", cameras=("snapshot", "wrist"), image_size=(32, 32)))
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs) and not obs["pixels"]["snapshot"].any()
    hold = np.r_[env.env.robots[0].init_qpos, 0.0, -1.0].astype(np.float32)
    for _ in range(600):
        obs, *_ = env.step(hold)
        if env.env.box_detected:
            break
    assert env.env.box_detected and obs["pixels"]["snapshot"].std() > 5  # the arriving box's photo
    assert np.array_equal(obs["pixels"]["snapshot"], env.env.camera_image("sensor", 32, 32))

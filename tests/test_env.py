"""The task as a whole: configuration, determinism, stability, observations, success."""

import numpy as np
import pytest
import robosuite as suite

from colorsort.config import PRESETS, TaskConfig, make_config
from colorsort.robots import ROBOTS


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"belt_speed": -0.1}, "belt_speed"),
        ({"belt_speed": 30.0}, "belt_speed"),
        ({"preset": "turbo"}, "Valid presets"),
        ({"box_colors": ("red", "pink")}, "Valid colours"),
        ({"bin_capacity": 0}, "bin_capacity"),
        ({"bin_capacity": 6, "pool_size": 8}, "pool_size"),
        ({"robots": "Sawyer"}, "Valid robots"),
        ({"gripper_types": "PandaGripper"}, "Valid grippers"),
        ({"belt_sped": 0.1}, "Valid fields"),
        ({"camera_names": ["top"]}, "Valid cameras"),
    ],
)
def test_invalid_configuration_raises_naming_valid_choices(kwargs, message):
    kwargs = {"robots": "IRB140", **kwargs}
    with pytest.raises(ValueError, match=message):
        suite.make("ColorSort", has_offscreen_renderer=False, **kwargs)


def test_presets_and_overrides(make_env):
    seed = make_config("seed")
    assert (seed.belt_speed, seed.spawn_period, seed.bin_capacity) == (0.05, 30.0, 2)
    assert make_config("seed", belt_speed=0.08).belt_speed == 0.08
    assert set(PRESETS) >= {"seed", "default"}
    with pytest.raises(ValueError, match="box_colors"):
        TaskConfig(box_colors="red")
    env = make_env(preset="seed", bin_capacity=3)
    assert env.config.belt_speed == 0.05 and env.config.bin_capacity == 3


def rollout(make_env, seed: int, steps: int = 60):
    env = make_env(seed=seed, spawn_period=0.5, lateral_jitter=0.03, yaw_jitter=20.0)
    env.reset()
    actions = np.random.default_rng(123).uniform(-0.2, 0.2, (steps, 8)) + np.r_[env.robots[0].init_qpos, 0, -1]
    for a in actions:
        env.step(a)
    state = env.sim.get_state().flatten()
    colors = [b.color for b in env.boxes if b.status.value != "parked"]
    return state, colors


def test_same_seed_same_state_different_seed_different_boxes(make_env):
    s0, c0 = rollout(make_env, 0)
    s0b, c0b = rollout(make_env, 0)
    s1, c1 = rollout(make_env, 1)
    assert np.array_equal(s0, s0b) and c0 == c0b
    assert len(c0) >= 4
    assert c0 != c1 or not np.array_equal(s0, s1)


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_random_actions_for_1s_no_warnings_no_nan(robot, preset, make_env):
    env = make_env(robot, preset=preset, spawn_period=0.5, lateral_jitter=0.05, yaw_jitter=45.0)
    env.reset()
    low, high = env.action_spec
    rng = np.random.default_rng(0)
    for _ in range(int(env.control_freq)):
        obs, reward, _, info = env.step(rng.uniform(low, high))
    d = env.mj_data
    assert all(w.number == 0 for w in d.warning), [(i, w.number) for i, w in enumerate(d.warning) if w.number]
    assert np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))
    assert np.all(np.isfinite(obs["robot0_proprio-state"]))


@pytest.mark.parametrize("robot", ["Panda", "UR5e"])
def test_other_robots_run_the_cell(robot, make_env):
    env = make_env(robot)
    env.reset()
    hold = np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]])
    for _ in range(int(6 / env.control_timestep)):
        _, _, _, info = env.step(hold)
    assert info["box_detected"] and not info["belt_running"]
    assert info["spawned"] >= 2


def test_info_keys_and_success(make_env):
    env = make_env(boxes_to_sort=1, spawn_period=100.0, ignore_done=False)
    env.reset()
    (box,) = env.boxes_in_play()
    _, _, done, info = env.step(np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]]))
    for key in ("belt_running", "box_detected", "placed", "misplaced", "dropped", "bins_emptied", "spawned",
                "is_success"):
        assert key in info
    assert not done and not info["is_success"]
    x, y = env.layout.bin_center(["red", "green", "blue"].index(box.color))
    qa = env.plant.pool.qpos[box.index]
    env.sim.data.qpos[qa : qa + 3] = (x, y, 0.4)
    env.sim.forward()
    for _ in range(40):
        _, reward, done, info = env.step(np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]]))
        if done:
            break
    assert done and info["is_success"] and reward == 1.0


def test_camera_images_right_side_up(make_env):
    env = make_env(has_offscreen_renderer=True, use_camera_obs=True, camera_heights=96, camera_widths=128)
    obs = env.reset()
    for cam in ("scene", "sensor", "wrist"):
        img = obs[f"{cam}_image"]
        assert img.shape == (96, 128, 3) and img.dtype == np.uint8
    # The sensor camera looks down with world +y up in the image: the red bin (+y of the belt)
    # fills the top rows, the floor and the sensor's side the bottom rows.
    img = obs["sensor_image"].astype(int)
    red = (img[..., 0] > 150) & (img[..., 1] < 80) & (img[..., 2] < 80)
    assert red[:20].mean() > 0.3 and red[-20:].mean() == 0.0
    # The scene camera: sky (bright, bluish-grey) above, floor (grey) below, never the other way.
    scene = obs["scene_image"].astype(int)
    assert scene[:5].mean() > scene[-5:].mean()


def test_close_frees_the_gl_context_at_once_without_a_full_collection(monkeypatch):
    """``close()`` frees the offscreen context (it and the sim refer to each other) at once, without robosuite's
    ``gc.collect()``, which took 0.23 s of every close in a process holding torch and LeRobot."""
    import gc
    import weakref

    from helpers import new_env

    env = new_env(has_offscreen_renderer=True)
    env.reset()
    assert env.camera_image("scene", 32, 32).shape == (32, 32, 3)
    context = weakref.ref(env.sim._render_context_offscreen)
    collections: list = []
    monkeypatch.setattr(gc, "collect", lambda *a: collections.append(a))
    env.close()
    assert context() is None and env.sim is None and not collections
    env.close()  # a second close does nothing


@pytest.mark.parametrize("robot", ["IRB140", "Panda"])
def test_the_servo_between_policy_steps_writes_what_robosuites_controller_writes(robot, make_env):
    """``envs/servo.py``: the arm's torques come from robosuite's controllers without its bookkeeping (between
    policy steps its joint-position law alone). Every servo update of a sorting episode, policy steps included,
    writes exactly the ``ctrl`` robosuite's own ``Robot.control`` writes from the same state."""
    from colorsort.expert.factory import make_expert

    env = make_env(robot, seed=3, has_offscreen_renderer=True)
    obs = env.reset()
    expert = make_expert(env)
    expert.reset(obs)
    obs, _, _, _ = env.step(expert.act(obs))
    assert env._servo.fast  # this controller's law is the servo's: it would run between policy steps
    env._servo.fast = False  # robosuite's control at every update, each compared with the servo's
    robosuite_control, checked = env.robots[0].control, []

    def compared(action, policy_step=False):
        before = env.sim.data.ctrl.copy()
        robosuite_control(action, policy_step=policy_step)
        wanted = env.sim.data.ctrl.copy()
        env.sim.data.ctrl[:] = before
        if policy_step:
            env._servo.new_goal(action)
        else:
            env._servo.hold(env.robots[0].part_controllers[env.robots[0].arms[0]])
        assert np.array_equal(env.sim.data.ctrl, wanted)  # bit for bit
        checked.append(policy_step)

    env.robots[0].control = compared
    for _ in range(200):  # the approach and the first pick
        obs, _, _, _ = env.step(expert.act(obs))
    assert checked.count(False) == 200 * 4 and checked.count(True) == 200  # 5 updates a policy step at 100 Hz

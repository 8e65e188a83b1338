"""Real clients on ColorSort: Gymnasium's vector envs, robosuite's wrappers, robosuite's reward conventions.

(LeRobot's CLIs are in ``test_lerobot_cli.py``.)
"""

import json
import os
import subprocess
import sys
import textwrap

import gymnasium as gym
import numpy as np
import pytest
import robosuite as suite
from test_bins import drop_into_bin, run, the_box
from test_expert import make_expert_env, run_until

from colorsort.envs.gym_env import ColorSortGymEnv
from colorsort.robots import ROBOTS
from colorsort.variants import DEFAULT_GYM_ID, VARIANTS

SMALL = dict(cameras=("scene",), image_size=(32, 32))


def run_fresh_python(code: str, timeout: float) -> subprocess.CompletedProcess:
    """Run ``code`` in a new interpreter: a process that has never rendered, as a user's script starts."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True,
                          timeout=timeout)


# every async context first, the synchronous env last: it renders in this process, after which a fork is refused
MODES = [("async", "default"), ("async", "fork"), ("async", "forkserver"), ("async", "spawn"), ("sync", "default")]

VECTOR_SCRIPT = """
    import json, numpy as np, gymnasium as gym, colorsort
    for mode, context in MODES:
        kwargs = {} if context == "default" else {"vector_kwargs": {"context": context}}
        envs = gym.make_vec("colorsort/ColorSort-v0", num_envs=2, vectorization_mode=mode,
                            cameras=("scene",), image_size=(32, 32), **kwargs)
        obs, info = envs.reset(seed=[3, 4])
        rng = np.random.default_rng(0)
        for _ in range(4):
            obs, reward, terminated, truncated, info = envs.step(
                rng.uniform(envs.action_space.low, envs.action_space.high))
        obs, info = envs.reset(seed=[3, 4])
        pixels = obs["pixels"]["scene"]
        assert pixels.shape == (2, 32, 32, 3) and pixels.std() > 5, pixels.std()  # real images, not blank
        print("state", mode, context, json.dumps(obs["agent_pos"][0].tolist()))
        envs.close()
"""


@pytest.mark.slow
def test_make_vec_steps_and_resets_in_every_mode_and_context():
    """One new interpreter, as a user's script starts, runs each mode and context in turn (Gymnasium's default
    async context on Linux is fork: the parent builds an env only to read its spaces)."""
    done = run_fresh_python(f"MODES = {MODES!r}\n" + textwrap.dedent(VECTOR_SCRIPT), timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    reference = ColorSortGymEnv("default", **SMALL)
    first, _ = reference.reset(seed=3)
    reference.close()
    states = [line.split(" ", 3) for line in done.stdout.splitlines() if line.startswith("state")]
    assert [(mode, context) for _, mode, context, _ in states] == MODES
    for *_, state in states:
        assert np.allclose(json.loads(state), first["agent_pos"])  # reset(seed=3) in a worker = here


def test_a_fork_after_rendering_fails_at_once_with_advice_instead_of_hanging():
    code = """
        import gymnasium as gym, colorsort
        env = gym.make("colorsort/ColorSort-v0", cameras=("scene",), image_size=(32, 32))
        env.reset(seed=0)  # this process now holds an EGL display
        envs = gym.make_vec("colorsort/ColorSort-v0", num_envs=2, vectorization_mode="async",
                            vector_kwargs={"context": "fork"}, cameras=("scene",), image_size=(32, 32))
        try:
            envs.reset(seed=0)
        except RuntimeError as err:
            print("refused:", err)
    """
    done = run_fresh_python(code, timeout=120)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "refused:" in done.stdout and "forkserver" in done.stdout


def test_the_gym_env_builds_no_simulation_until_it_is_used(closing):
    env = closing(gym.make(DEFAULT_GYM_ID, **SMALL))
    assert env.unwrapped._env is None  # what a vector env's parent builds: spaces only
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)


@pytest.mark.parametrize("robot", ["IRB140", "Panda", "UR5e"])
def test_action_bounds_without_an_env_match_the_envs_action_spec(robot, make_env):
    env = make_env(robot)
    low, high = ROBOTS[robot].action_bounds()
    assert np.array_equal(low, env.action_spec[0]) and np.array_equal(high, env.action_spec[1])


def test_gym_env_reports_its_step_limit_as_lerobot_reads_it(closing):
    env = closing(gym.make(DEFAULT_GYM_ID, **SMALL))
    assert env.get_wrapper_attr("_max_episode_steps") == int(np.ceil(VARIANTS["default"].time_limit * 20))
    short = closing(gym.make(DEFAULT_GYM_ID, episode_length=3, **SMALL))
    short.reset(seed=0)
    ends = [short.step(short.action_space.low * 0)[3] for _ in range(3)]
    assert ends == [False, False, True] and short.get_wrapper_attr("_max_episode_steps") == 3


# ---------------------------------------------------------------------- robosuite's wrappers
def test_robosuites_gym_wrapper_steps_colorsort(make_env, closing):
    from robosuite.wrappers import GymWrapper

    env = closing(GymWrapper(make_env(use_object_obs=True)))
    obs, _ = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape and np.isfinite(obs).all()
    assert env.reward_range == (0, 1.0)
    obs, reward, terminated, truncated, info = env.step(np.zeros(env.action_space.shape))
    assert np.isfinite(obs).all() and reward == 0.0 and "is_success" in info


def test_robosuites_visualization_wrapper_shows_the_grip_site(make_env, closing):
    from robosuite.wrappers import VisualizationWrapper

    env = closing(VisualizationWrapper(make_env(has_offscreen_renderer=True)))
    site = env.sim.model.site_name2id("gripper0_right_grip_site_cylinder")
    env.reset()
    assert env.sim.model.site_rgba[site][3] > 0  # the wrapper's point: visualisation on
    env.step(np.zeros(8))


def test_robosuites_data_collection_wrapper_records_states_and_actions(tmp_path, make_env):
    from robosuite.wrappers import DataCollectionWrapper

    env = DataCollectionWrapper(make_env(), str(tmp_path))
    env.reset()
    for _ in range(5):
        env.step(np.zeros(8))
    env.close()
    (episode,) = list(tmp_path.iterdir())
    data = np.load(next(episode.glob("state_*.npz")), allow_pickle=True)
    assert data["states"].shape[0] == 1 + 5 and len(data["action_infos"]) == 5  # the initial state, then per step


def test_robosuites_domain_randomization_wrapper_keeps_box_colours(make_env, closing):
    from robosuite.wrappers import DomainRandomizationWrapper

    from colorsort.config import COLORS

    base = make_env(has_offscreen_renderer=True, use_camera_obs=True, camera_names=["scene"], camera_heights=32,
                    camera_widths=32)
    env = closing(DomainRandomizationWrapper(base, randomize_color=False, randomize_every_n_steps=1))
    env.reset()
    for _ in range(3):
        obs, _, _, _ = env.step(np.zeros(8))
    assert obs["scene_image"].shape == (32, 32, 3)
    for box in base.boxes_in_play():
        assert np.allclose(base.sim.model.geom_rgba[base.plant.pool.geom[box.index]], COLORS[box.color])


def test_no_visualisation_sites_show_before_the_first_reset(make_env):
    """A replay renders stored states without reset(): robosuite's green grip line must not show."""
    env = make_env(has_offscreen_renderer=True)  # never reset
    m = env.sim.model
    sites = [i for i in range(m.nsite) if "grip_site" in (m.site_id2name(i) or "")]
    assert sites and all(m.site_rgba[i][3] <= 0 for i in sites)


# ---------------------------------------------------------------------- reward conventions
def test_reward_scale_scales_every_reward(make_env):
    totals = {}
    for scale in (1.0, 2.5):
        env = make_env(spawn_period=100.0, reward_scale=scale)
        env.reset()
        drop_into_bin(env, the_box(env, "green"), "green")
        totals[scale] = run(env, 1.5)[0]
        env.close()
    assert totals[1.0] == 1.0 and totals[2.5] == 2.5


def test_shaped_reward_rises_through_the_stages_of_an_expert_episode(make_env):
    env, expert, obs = make_expert_env(make_env, reward_shaping=True, boxes_to_sort=2)
    trace = []
    run_until(env, expert, obs, boxes=1, max_time=15.0,
              on_step=lambda a, o, info: trace.append((env.staged_rewards(), env.reward())))
    assert env.events[0].outcome == "placed"
    stages, rewards = zip(*trace, strict=True)
    first = {name: next(k for k, s in enumerate(stages) if s[name] > (0.1 if name == "reach" else 0))
             for name in ("reach", "seal", "carry", "place")}
    assert first["reach"] < first["seal"] == first["carry"] < first["place"]  # in order; carrying starts sealed
    assert stages[first["seal"]]["progress"] >= 0.5 > stages[0]["progress"]
    assert max(s["progress"] for s in stages) == 1.0
    # per step: (placed + progress) / boxes_to_sort, plus +1 in the step the box lands
    assert rewards[-1] >= 1.0 + 0.5  # the landing step: +1, and 1 of 2 boxes counted
    assert min(rewards[first["seal"] : -1]) >= 0.25 and rewards[0] < 0.125


def test_sparse_reward_is_the_default_and_zero_between_events(make_env):
    env = make_env()
    env.reset()
    assert not env.reward_shaping and env.reward_scale == 1.0
    rewards = [env.step(np.append(env.robots[0].init_qpos, [-1.0, -1.0]))[1] for _ in range(5)]
    assert rewards == [0.0] * 5


# ---------------------------------------------------------------------- bad actions
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_actions_raise_and_leave_the_state_untouched(bad, make_env):
    env = make_env()
    env.reset()
    before = env.get_sim_state()
    action = np.append(env.robots[0].init_qpos, [-1.0, -1.0])
    action[[1, 6]] = bad
    with pytest.raises(ValueError, match=r"joint_2.target \(index 1\).*suction \(index 6\)"):
        env.step(action)
    assert np.array_equal(env.get_sim_state(), before)


def test_nan_actions_raise_through_the_gym_env(closing):
    env = closing(ColorSortGymEnv("default", **SMALL))
    env.reset(seed=0)
    action = env.action_space.low * 0
    action[-1] = np.nan
    with pytest.raises(ValueError, match="belt_pass"):
        env.step(action)


def test_targets_beyond_a_joints_limit_stop_at_the_limit(make_env):
    """Documented: targets are clipped to the controller's [-7, 7] rad; the joint's own limit stops the arm."""
    env = make_env()
    env.reset()
    m = env.sim.model
    joint = env.robots[0].robot_joints[4]  # J5: +-115 deg
    lo, hi = m.jnt_range[m.joint_name2id(joint)]
    action = np.append(env.robots[0].init_qpos, [-1.0, -1.0])
    action[4] = 50.0  # far outside the action space
    for _ in range(40):
        env.step(action)
    q = env.sim.data.qpos[m.get_joint_qpos_addr(joint)]
    assert hi - 0.05 < q <= hi + 0.01 and np.isfinite(env.get_sim_state()).all()


def test_suite_make_takes_robosuites_reward_arguments(closing):
    env = closing(suite.make("ColorSort", robots="IRB140", reward_scale=None, reward_shaping=True,
                             has_offscreen_renderer=False, use_camera_obs=False))
    env.reset()
    assert env.reward_scale is None and env.reward_shaping
    assert 0.0 <= env.reward() < 0.5


# ---------------------------------------------------------------------- console output
@pytest.mark.slow
def test_console_scripts_print_no_robosuite_notices():
    """robosuite's start-up warnings and INFO lines stay out of the commands' output, workers' included."""
    from pathlib import Path

    command = [str(Path(sys.executable).parent / "colorsort-eval"), "--policy", "random", "--episodes", "2",
               "--envs", "2", "--image-size", "32", "--cameras", "scene"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")})
    assert done.returncode == 0, done.stderr[-2000:]
    assert "success rate" in done.stdout
    assert "robosuite" not in done.stdout + done.stderr


def test_a_state_only_gym_env_has_no_pixels_and_passes_the_env_checker(closing):
    from gymnasium.utils.env_checker import check_env

    env = closing(gym.make(DEFAULT_GYM_ID, cameras=(), render_mode=None))
    check_env(env.unwrapped)
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"agent_pos", "environment_state"} and not env.unwrapped.env.has_offscreen_renderer

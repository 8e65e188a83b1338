"""get_sim_state / set_sim_state: a saved instant re-renders identically and steps on bit-exactly."""

import numpy as np
import pytest
from helpers import new_env

from colorsort.cell.sim_state import rng_from_words, rng_to_words
from colorsort.expert.factory import make_expert


def record(env, seed: int, steps: int):
    obs = env.reset(seed=seed)
    expert = make_expert(env)
    expert.reset(obs)
    states, frames, actions = [env.get_sim_state()], [obs["scene_image"]], []
    for _ in range(steps):
        action = expert.act(obs).astype(np.float32)
        obs, _, _, _ = env.step(action)
        actions.append(action)
        states.append(env.get_sim_state())
        frames.append(obs["scene_image"])
    return states, frames, actions


@pytest.fixture(scope="module")
def recorded():
    env = new_env(has_offscreen_renderer=True, use_camera_obs=True, camera_names="scene", camera_heights=64,
                  camera_widths=64)
    try:
        states, frames, actions = record(env, seed=5, steps=140)  # the box is picked and dropped by then
        yield env, states, frames, actions
    finally:
        env.close()


def test_restored_states_render_the_observed_frames_exactly(recorded):
    env, states, frames, _ = recorded
    for k in range(0, len(states), 10):
        env.set_sim_state(states[k])
        assert np.array_equal(env.camera_image("scene", 64, 64), frames[k]), f"frame {k}"


def test_actions_replayed_from_the_first_state_retrace_the_episode_bit_for_bit(recorded):
    env, states, _, actions = recorded
    env.reset(seed=123)  # another seed: the saved state carries the generator
    env.set_sim_state(states[0])
    for k, action in enumerate(actions):
        env.step(action)
        assert np.array_equal(env.get_sim_state(), states[k + 1]), f"step {k}"
    assert env.events and env.events[0].outcome == "placed"


def test_restoring_mid_episode_continues_identically(recorded):
    env, states, _, actions = recorded
    env.reset(seed=9)
    env.set_sim_state(states[60])  # box in the cup or on its way: seal, weld and belt state restored
    for k in range(60, 90):
        env.step(actions[k])
    assert np.array_equal(env.get_sim_state(), states[90])


def test_a_state_of_the_wrong_size_is_refused(recorded):
    env, states, _, _ = recorded
    with pytest.raises(ValueError, match="shape"):
        env.set_sim_state(states[0][:-1])


def test_generator_round_trip():
    rng = np.random.default_rng(42)
    rng.random(3)
    copy = rng_from_words(rng_to_words(rng))
    assert np.array_equal(copy.random(5), rng.random(5))


def test_the_named_layout_addresses_what_each_segment_holds(recorded):
    env, states, _, _ = recorded
    layout = env.sim_state_layout
    s = layout.slices
    assert layout.size == env.sim_state_size == len(states[0])
    assert list(s) == ["mujoco", "boxes", "held", "weld", "belt_pass", "belt_running", "belt_travel",
                       "next_spawn_time", "next_serial", "clock", "rng"]
    last = states[-1]
    assert last[s["clock"]][0] == pytest.approx(140 * env.control_timestep)
    assert last[s["mujoco"]][0] == pytest.approx(last[s["clock"]][0])  # MuJoCo's time leads its state
    boxes = last[s["boxes"]].reshape(-1, 4)
    in_play = [b for b in env.boxes if b.status.value != "parked"]
    assert sorted(boxes[boxes[:, 0] >= 0, 3].astype(int)) == sorted(b.serial for b in in_play)
    assert layout.describe()["segments"]["rng"] == [s["rng"].start, s["rng"].stop]

"""The conveyor: carries boxes at its speed by friction, stops for the ray sensor, restarts."""

import numpy as np
import pytest
from helpers import wait_for_box_at_sensor


def hold_action(env):
    return np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]])


@pytest.mark.parametrize("speed", [0.05, 0.2])
def test_belt_carries_box_at_its_speed_without_spinning(speed, make_env):
    env = make_env(belt_speed=speed, spawn_period=100.0)
    env.reset()
    (box,) = env.boxes_in_play()
    for _ in range(10):  # let it settle onto the belt and come up to speed
        env.step(hold_action(env))
    x0, t0 = env.box_pos(box), env.cur_time
    quat0 = env.sim.data.body_xquat[env.plant.pool.body[box.index]].copy()
    for _ in range(40):  # 2 s
        env.step(hold_action(env))
    x1 = env.box_pos(box)
    v = (x1 - x0) / (env.cur_time - t0)
    assert -v[0] == pytest.approx(speed, rel=0.05)
    assert abs(v[1]) < 1e-3 and abs(v[2]) < 1e-3
    quat1 = env.sim.data.body_xquat[env.plant.pool.body[box.index]]
    assert abs(abs(quat0 @ quat1) - 1.0) < 1e-4  # no rotation


def test_belt_stops_when_ray_blocked_and_restarts_when_clear(env):
    box = wait_for_box_at_sensor(env)
    for _ in range(5):  # friction brings it to rest within a few mm
        env.step(hold_action(env))
    stop_x = env.box_pos(box)[0]
    # The box stopped with its leading face at the ray.
    assert stop_x - env.layout.box_size / 2 == pytest.approx(env.layout.sensor_x, abs=0.005)
    for _ in range(20):
        _, _, _, info = env.step(hold_action(env))
    assert not info["belt_running"] and info["box_detected"]
    assert env.box_pos(box)[0] == pytest.approx(stop_x, abs=1e-4)
    followers = [b for b in env.boxes_in_play() if b is not box]
    before = [env.box_pos(b)[0] for b in followers]
    env.remove_box(box)  # take the box away: the ray clears
    obs, _, _, info = env.step(hold_action(env))
    assert info["belt_running"] and not info["box_detected"]
    assert float(obs["belt_running"]) == 1.0
    for _ in range(10):
        env.step(hold_action(env))
    after = [env.box_pos(b)[0] for b in followers]
    assert followers and all(a < b - 0.05 for a, b in zip(after, before, strict=True))  # the queue moves on


def test_box_riding_past_the_end_is_dropped(make_env):
    env = make_env(spawn_period=100.0)
    env.reset()
    (box,) = env.boxes_in_play()
    L = env.layout
    qa = env.plant.pool.qpos[box.index]
    env.sim.data.qpos[qa : qa + 3] = (L.belt_end_x + 0.03, L.belt_y, L.belt_top_z + 0.05)  # downstream of the ray
    env.sim.forward()
    dropped = 0
    for _ in range(40):
        _, r, _, info = env.step(hold_action(env))
        dropped += r < 0
    assert info["dropped"] == 1 and dropped == 1
    assert box not in env.boxes_in_play()


def test_spawner_waits_when_the_pool_is_empty(make_env):
    env = make_env(pool_size=2, bin_capacity=1, spawn_period=0.5)
    env.reset()
    for _ in range(int(8 / env.control_timestep)):  # 8 s: 16 boxes due, 2 in the pool
        _, _, _, info = env.step(hold_action(env))
    assert info["spawned"] == 2 and len(env.boxes_in_play()) == 2
    env.remove_box(env.boxes_in_play()[0])  # one returns to the pool
    for _ in range(int(1 / env.control_timestep)):
        _, _, _, info = env.step(hold_action(env))
    assert info["spawned"] == 3


def test_belt_pass_lets_a_box_without_a_bin_through_as_rejected(make_env):
    env = make_env(box_colors=("yellow",), spawn_period=100.0)
    env.reset()
    box = wait_for_box_at_sensor(env)
    for _ in range(10):
        _, _, _, info = env.step(hold_action(env))
    assert not info["belt_running"]  # the ray holds it
    passing = hold_action(env)
    passing[-1] = 1.0
    rejected = 0
    for _ in range(int(3 / env.control_timestep)):  # 0.25 m to the end at 0.2 m/s, then the fall
        _, reward, _, info = env.step(passing)
        rejected = info["rejected"]
        if rejected:
            break
    assert rejected == 1 and info["dropped"] == 0 and reward == 0.0
    assert box not in env.boxes_in_play()

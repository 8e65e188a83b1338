"""Bins: boxes resting inside are counted by colour; full bins are emptied and logged."""

import logging

import numpy as np

from colorsort.config import BIN_COLORS


def drop_into_bin(env, box, color: str, height: float = 0.45):
    """Teleport a box above the named bin at rest, then let it fall."""
    x, y = env.layout.bin_center(BIN_COLORS.index(color))
    qa, va = env.plant.pool.qpos[box.index], env.plant.pool.qvel[box.index]
    env.sim.data.qpos[qa : qa + 7] = (x, y, height, 1, 0, 0, 0)
    env.sim.data.qvel[va : va + 6] = 0
    env.sim.forward()


def run(env, seconds: float):
    hold = np.concatenate([env.robots[0].init_qpos, [-1.0, -1.0]])
    rewards, info = [], None
    for _ in range(int(seconds * env.control_freq)):
        _, r, _, info = env.step(hold)
        rewards.append(r)
    return sum(rewards), info


def the_box(env, color: str):
    (box,) = env.boxes_in_play()
    box.color = color  # bookkeeping only; the tests check the counting, not the colour draw
    return box


def test_box_dropped_into_green_bin_is_counted_there(make_env):
    env = make_env(spawn_period=100.0)
    env.reset()
    box = the_box(env, "green")
    drop_into_bin(env, box, "green")
    reward, info = run(env, 1.5)
    assert env.box_pos(box)[2] < 0.1  # fell to the bin floor
    assert info["placed"] == {"red": 0, "green": 1, "blue": 0}
    assert info["bins"]["green"] == {"count": 1, "matches": [True]}
    assert reward == 1.0 and info["misplaced"] == 0 and info["dropped"] == 0


def test_box_in_wrong_bin_is_misplaced(make_env):
    env = make_env(spawn_period=100.0)
    env.reset()
    box = the_box(env, "red")
    drop_into_bin(env, box, "blue")
    reward, info = run(env, 1.5)
    assert info["misplaced"] == 1 and info["bins"]["blue"] == {"count": 1, "matches": [False]}
    assert reward == -1.0


def test_box_on_floor_is_dropped(make_env):
    env = make_env(spawn_period=100.0)
    env.reset()
    box = the_box(env, "red")
    qa = env.plant.pool.qpos[box.index]
    env.sim.data.qpos[qa : qa + 3] = (0.5, -1.2, 0.3)
    env.sim.forward()
    reward, info = run(env, 1.5)
    assert info["dropped"] == 1 and reward == -1.0


def test_full_bin_is_emptied_and_logged(caplog, make_env):
    env = make_env(spawn_period=0.5, bin_capacity=2)
    env.reset()
    with caplog.at_level(logging.INFO, logger="colorsort"):
        for _ in range(2):
            run(env, 0.6)
            box = max(env.boxes_in_play(), key=lambda b: env.box_pos(b)[0])  # the newest
            box.color = "blue"
            drop_into_bin(env, box, "blue", height=0.6)
            _, info = run(env, 1.5)
    assert "Emptying blue bin because it's full." in caplog.messages
    assert info["bins_emptied"] == 1 and info["placed"]["blue"] == 2
    assert info["bins"]["blue"]["count"] == 0  # its boxes went back to the pool
    parked_z = [env.box_pos(b)[2] for b in env.boxes if b.status.value == "parked"]
    assert all(z < -1.0 for z in parked_z)


def test_capacity_one_empties_every_box(make_env):
    env = make_env(spawn_period=100.0, bin_capacity=1)
    env.reset()
    box = the_box(env, "red")
    drop_into_bin(env, box, "red")
    _, info = run(env, 1.5)
    assert info["bins_emptied"] == 1 and info["placed"]["red"] == 1

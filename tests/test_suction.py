"""The vacuum cup: lifts what it touches, nothing else, holds through fast moves, lets go at once."""

import numpy as np
import pytest
from helpers import cup_site, move_to, solve_cup_ik, wait_for_box_at_sensor

from colorsort.robots import ROBOTS


def box_in_cup_frame(env, box) -> np.ndarray:
    site = cup_site(env)
    R = env.sim.data.site_xmat[site].reshape(3, 3)
    return R.T @ (env.box_pos(box) - env.sim.data.site_xpos[site])


def approach(env, clearance: float):
    """Bring the cup above the box at the sensor, ``clearance`` [m] above its top face."""
    box = wait_for_box_at_sensor(env)
    top = env.box_pos(box) + [0, 0, env.layout.box_size / 2]
    q_above = solve_cup_ik(env, top + [0, 0, 0.10])
    q_at = solve_cup_ik(env, top + [0, 0, clearance], q_above)
    move_to(env, q_above, -1.0, 1.0)
    move_to(env, q_at, -1.0, 0.5)
    return box, q_above, q_at


@pytest.fixture
def gripped(env):
    box, q_above, q_at = approach(env, clearance=-0.003)  # pressed 3 mm into the box
    move_to(env, q_at, 1.0, 0.1, settle=0.2)
    z0 = env.box_pos(box)[2]
    move_to(env, q_above, 1.0, 0.5)
    return env, box, q_above, z0


def test_cup_lifts_the_box_it_touches(gripped):
    env, box, _, z0 = gripped
    assert env.plant.seal.held == box.index
    assert env.box_pos(box)[2] > z0 + 0.09  # rose with the cup (0.10 m)
    assert not env.task_info()["box_detected"]


def test_cup_does_not_lift_a_box_2cm_away(env):
    box, q_above, q_at = approach(env, clearance=0.02)
    z0 = env.box_pos(box)[2]
    move_to(env, q_at, 1.0, 0.1, settle=0.5)
    move_to(env, q_above, 1.0, 0.5)
    assert env.plant.seal.held is None
    assert abs(env.box_pos(box)[2] - z0) < 1e-3


def test_box_does_not_slip_through_fastest_motion(gripped):
    env, box, q_above, _ = gripped
    rel0 = box_in_cup_frame(env, box)
    # J1, J2, J3 at their datasheet speeds: 90 deg of J1 in the time a smoothstep peaks at 200 deg/s.
    q_far = q_above + np.array([np.pi / 2, 0.35, -0.35, 0, 0, 0])
    duration = 1.5 * (np.pi / 2) / ROBOTS["IRB140"].joint_speeds[0]
    slips = []
    move_to(env, q_far, 1.0, duration, on_step=lambda e: slips.append(np.linalg.norm(box_in_cup_frame(e, box) - rel0)))
    def record_slip(e):
        slips.append(np.linalg.norm(box_in_cup_frame(e, box) - rel0))

    move_to(env, q_above, 1.0, duration, on_step=record_slip)
    assert max(slips) < 0.005


def test_released_box_falls_within_one_control_step(gripped):
    env, box, q_above, _ = gripped
    rel0 = box_in_cup_frame(env, box)
    env.step(np.concatenate([q_above, [-1.0, -1.0]]))
    assert env.plant.seal.held is None
    vz = env.sim.data.qvel[env.plant.pool.qvel[box.index] + 2]
    assert vz < -0.3  # 1/20 s of free fall: -0.49 m/s
    assert box_in_cup_frame(env, box)[2] > rel0[2] + 0.005
    for _ in range(20):
        env.step(np.concatenate([q_above, [-1.0, -1.0]]))
    assert env.box_pos(box)[2] == pytest.approx(env.layout.belt_top_z + 0.05, abs=0.005)  # back on the belt


def test_each_seal_records_how_far_off_the_cup_axis_and_how_turned_the_box_is_held(env):
    """The cup pressed onto a box 12 mm off its centre: the grip names that box, says 12 mm, and gives the
    box's turn against the cup that the two bodies' orientations show."""
    box = wait_for_box_at_sensor(env)
    top = env.box_pos(box) + [0.012, 0, env.layout.box_size / 2]
    q_above = solve_cup_ik(env, top + [0, 0, 0.10])
    q_at = solve_cup_ik(env, top + [0, 0, -0.003], q_above)
    move_to(env, q_above, -1.0, 1.0)
    move_to(env, q_at, -1.0, 0.5)
    move_to(env, q_at, 1.0, 0.1, settle=0.2)
    assert env.plant.seal.held == box.index
    (grip,) = env.grips
    assert grip.serial == box.serial and abs(grip.offset - 0.012) < 0.002
    seal, d = env.plant.seal, env.sim.data
    turn = d.body_xmat[seal.cup].reshape(3, 3).T @ d.body_xmat[seal.box_bodies[box.index]].reshape(3, 3)
    yaw = (np.degrees(np.arctan2(turn[1, 0], turn[0, 0])) + 45) % 90 - 45
    assert -45 <= grip.yaw < 45 and abs(grip.yaw - yaw) < 0.5
    env.reset()
    assert env.grips == []

"""mink IK reaches cup poses within 1 mm and 1 deg or says which waypoint it cannot; ruckig stays within limits."""

import numpy as np
import pytest
from helpers import new_env

from colorsort.expert.planning import (
    ANGLE_TOLERANCE,
    POSITION_TOLERANCE,
    CupIK,
    JointLimits,
    MotionConfig,
    UnreachableWaypoint,
    Waypoint,
    cup_down_rotation,
    plan_motion,
    site_yaw,
)
from colorsort.robots import ROBOTS


def make_ik(robot: str) -> CupIK:
    env = new_env(robot)
    try:
        return CupIK(env.robots[0].robot_model.get_model(mode="mujoco"), np.array(ROBOTS[robot].home))
    finally:
        env.close()


@pytest.mark.parametrize("robot", ["IRB140", "Panda", "UR5e"])
def test_ik_reaches_sampled_poses_within_tolerance(robot):
    ik = make_ik(robot)
    rng = np.random.default_rng(0)
    home = np.array(ROBOTS[robot].home)
    home_yaw = site_yaw(ik.cup_pose(home)[1])
    for i in range(15):
        # The cell's workspace: over the belt's pick area and the bins, cup turned up to 90 deg
        # from home (the Panda's last joint cannot turn the cup half a turn).
        target = (rng.uniform(0.30, 0.50), rng.uniform(-0.40, 0.30), rng.uniform(0.48, 0.62))
        yaw = home_yaw + rng.uniform(-np.pi / 2, np.pi / 2)
        q = ik.solve(Waypoint(f"sample {i}", target, yaw), home)
        pos, rot = ik.cup_pose(q)
        assert np.linalg.norm(pos - target) < POSITION_TOLERANCE
        cos_angle = (np.trace(rot.T @ cup_down_rotation(yaw)) - 1) / 2
        assert np.arccos(np.clip(cos_angle, -1, 1)) < ANGLE_TOLERANCE
        lo, hi = ik.model.jnt_range[: len(q)].T
        assert np.all(q >= lo - 1e-6) and np.all(q <= hi + 1e-6)


def test_ik_raises_naming_an_unreachable_waypoint():
    ik = make_ik("IRB140")
    with pytest.raises(UnreachableWaypoint, match="'far shelf'.*misses by"):
        ik.solve(Waypoint("far shelf", (1.5, 0.0, 0.5)), np.array(ROBOTS["IRB140"].home))
    with pytest.raises(UnreachableWaypoint, match="'ceiling'"):
        ik.solve(Waypoint("ceiling", (0.2, 0.0, 1.4)), np.array(ROBOTS["IRB140"].home))


@pytest.mark.parametrize("speed_factor", [1.0, 0.5])
def test_trajectories_respect_limits_at_every_sample(speed_factor):
    config = MotionConfig(speed_factor=speed_factor, acceleration=12.0, jerk=120.0)
    vmax = np.array(ROBOTS["IRB140"].joint_speeds) * speed_factor
    rng = np.random.default_rng(1)
    for _ in range(10):
        start, goal = rng.uniform(-1.5, 1.5, (2, 6))
        traj = plan_motion(start, goal, JointLimits.of(np.array(ROBOTS["IRB140"].joint_speeds), config))
        times = np.arange(0.0, traj.duration + 1e-9, 1e-3)
        samples = [traj.sample(t) for t in times]
        vel = np.array([s[1] for s in samples])
        acc = np.array([s[2] for s in samples])
        assert np.all(np.abs(vel) <= vmax * (1 + 1e-6))
        assert np.all(np.abs(acc) <= config.acceleration * (1 + 1e-6))
        jerk = np.diff(acc, axis=0) / 1e-3
        assert np.all(np.abs(jerk) <= config.jerk * 1.01)
        assert np.allclose(samples[0][0], start) and np.allclose(traj.sample(traj.duration)[0], goal, atol=1e-9)
        assert np.allclose(traj.sample(traj.duration)[1], 0.0, atol=1e-9)


def test_slower_speed_factor_takes_longer():
    start, goal = np.zeros(6), np.full(6, 1.5)
    v = np.array(ROBOTS["IRB140"].joint_speeds)
    fast = plan_motion(start, goal, JointLimits.of(v, MotionConfig(speed_factor=1.0))).duration
    slow = plan_motion(start, goal, JointLimits.of(v, MotionConfig(speed_factor=0.25))).duration
    assert slow > 1.5 * fast


@pytest.mark.parametrize("field, value", [("speed_factor", 0.0), ("speed_factor", 1.5), ("acceleration", -1.0),
                                          ("jerk", 0.0)])
def test_motion_config_rejects_bad_values(field, value):
    with pytest.raises(ValueError, match=field):
        MotionConfig(**{field: value})


def test_each_joint_keeps_to_its_own_acceleration():
    """Given per joint (MotionConfig(acceleration=None): the arm's own), each joint's acceleration stays within
    its own limit and the slowest joint to accelerate sets the duration; without them the limits are refused."""
    v = np.array(ROBOTS["IRB140"].joint_speeds)
    own = np.array([5.0, 10.0, 20.0, 40.0, 40.0, 40.0])  # [rad/s^2]
    limits = JointLimits.of(v, MotionConfig(acceleration=None, jerk=1000.0), own)
    np.testing.assert_array_equal(limits.acceleration, own)
    start, goal = np.zeros(6), np.full(6, 0.5)
    traj = plan_motion(start, goal, limits)
    acc = np.array([traj.sample(t)[2] for t in np.arange(0.0, traj.duration, 1e-3)])
    assert np.all(np.abs(acc) <= own * (1 + 1e-6))
    assert np.abs(acc[:, 0]).max() == pytest.approx(own[0], rel=1e-3)  # joint 1, the slowest, at its limit
    uniform = plan_motion(start, goal, JointLimits.of(v, MotionConfig(acceleration=40.0, jerk=1000.0)))
    assert traj.duration > uniform.duration
    with pytest.raises(ValueError, match="give accelerations"):
        JointLimits.of(v, MotionConfig(acceleration=None))

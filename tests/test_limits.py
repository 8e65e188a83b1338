"""Each joint's own acceleration: what its actuator's torque limit gives it, checked against MuJoCo's dynamics."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from colorsort.expert.factory import make_expert
from colorsort.expert.limits import TORQUE_SHARE, torque_limited_accelerations


def test_each_joint_reaches_its_limit_on_its_actuators_torque_alone(make_env):
    """At every pose the IRB 140's tracking expert moves between, each joint driven at its actuator's torque
    limit (the others holding against gravity) accelerates, in MuJoCo's forward dynamics, at least as fast as
    the limit it is planned at over TORQUE_SHARE: the planned accelerations are ones the motors can give. The
    tracking expert plans at them; the stopping belt's keeps its 15 rad/s^2 on every joint."""
    env = make_env(preset="tracking-fast", has_offscreen_renderer=True)
    env.reset()
    expert = make_expert(env)
    model = expert.calibration.kinematics
    poses = [expert.home, expert.q_wait, *(q for slots in expert.q_drop.values() for q in slots)]
    own = torque_limited_accelerations(model, poses)
    np.testing.assert_allclose(expert.limits.acceleration, own)
    assert own[0] < own[1] < own[2] < min(own[3:])  # the base turns the whole arm, the wrist a cup
    n, data = len(expert.home), mujoco.MjData(model)
    torque = model.actuator_ctrlrange[:n, 1]
    for q in poses:
        data.qpos[:n], data.qvel[:] = q, 0.0
        mujoco.mj_forward(model, data)
        hold = data.qfrc_bias[:n].copy()  # [N m] gravity
        for j in range(n):
            applied = hold.copy()
            applied[j] += np.sign(hold[j] or 1.0) * (torque[j] - abs(hold[j]))  # the motor's full torque, with gravity
            data.qfrc_applied[:] = 0.0
            data.qfrc_applied[:n] = applied
            mujoco.mj_forward(model, data)
            assert abs(data.qacc[j]) >= own[j] / TORQUE_SHARE * (1 - 1e-6), (j, q)

    stopping = make_expert(make_env(preset="default", has_offscreen_renderer=True))
    np.testing.assert_array_equal(stopping.limits.acceleration, np.full(n, 15.0))


def test_a_motor_too_weak_to_hold_the_arm_is_refused():
    """A joint whose torque limit is below gravity's pull at some pose has no acceleration to give: ValueError."""
    model = mujoco.MjModel.from_xml_string("""
        <mujoco><worldbody><body><joint name="j" axis="0 1 0"/><geom type="capsule" fromto="0 0 0 0.5 0 0"
        size="0.05" mass="10"/></body></worldbody><actuator><motor joint="j" ctrlrange="-1 1" ctrllimited="true"/>
        </actuator></mujoco>""")
    with pytest.raises(ValueError, match="cannot hold the arm up"):
        torque_limited_accelerations(model, [np.zeros(1)])
    assert torque_limited_accelerations(model, [np.array([np.pi / 2])])[0] > 0  # hanging down it needs none

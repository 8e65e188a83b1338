"""The arm's joint servo between policy steps: robosuite's joint-position torque law, without its bookkeeping.

robosuite's ``Robot.control`` runs at every servo update (every ``servo_period`` physics steps): it refreshes the
controller's state (the reference site's pose, velocity and Jacobians, which a joint-position law never reads),
splits the action among the parts, runs each part's controller and records what a policy step did. Between policy
steps the goal is fixed and only the arm's torques change, so ``Servo.hold`` computes just those, with the same
numpy operations in the same order on the same MuJoCo quantities (``mj_step1`` has computed them), and writes the
same ``ctrl``: bit for bit what robosuite writes (``tests/test_env.py``), at a fraction of the time
(``benchmarks/bench_env.py``). A policy step runs robosuite's controllers as ``Robot.control`` does (the goal, the
arm's torques, the gripper's command, which stays as written until the next policy step), less the records it
keeps of each step (``recent_*``), which nothing in the task reads. Any other controller runs robosuite's
``control`` at every update.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
from robosuite import macros

from colorsort.errors import ConfigError


class Servo:
    """The arm's servo update: ``control(action, policy_step)`` writes ``ctrl`` as robosuite's ``Robot.control``
    would, running robosuite's own at policy steps and for a controller ``hold`` does not reproduce."""

    def __init__(self, robot: Any):
        self.robot = robot  # its controllers are built after the model's references: read at the first update
        self.fast: bool | None = None

    def _setup(self) -> None:
        from robosuite.controllers.parts.generic.joint_pos import JointPositionController

        robot = self.robot
        self.arm = robot.arms[0]
        c = robot.part_controllers[self.arm]
        self.fast = (isinstance(c, JointPositionController) and c.impedance_mode == "fixed" and c.interpolator is None
                     and c.use_torque_compensation and len(robot.arms) == 1)
        model = robot.sim.model._model
        self.actuators = np.asarray(robot._ref_actuators_indexes_dict[self.arm])
        self.low, self.high = model.actuator_ctrlrange[self.actuators, 0], model.actuator_ctrlrange[self.actuators, 1]
        self.full: np.ndarray = np.zeros((model.nv, model.nv))  # the full mass matrix, as robosuite takes it

    def control(self, action: np.ndarray, policy_step: bool) -> None:
        """One servo update for the arm ``action`` (joint targets [rad], then the gripper's command)."""
        if self.fast is None:
            self._setup()
        c = self.robot.part_controllers[self.arm]  # robosuite may build new controllers at a reset
        if not self.fast or c.goal_qpos is None:
            self.robot.control(action, policy_step=policy_step)
        elif policy_step:
            self.new_goal(action)
        else:
            self.hold(c)

    def new_goal(self, action: np.ndarray) -> None:
        """A policy step: robosuite's ``Robot.control`` (the goal set, every part's controller run, ``ctrl`` clipped
        and written) without the records it keeps of it (``recent_*``: the robot's energy and force integrals,
        which nothing in the task reads)."""
        robot = self.robot
        composite = robot.composite_controller
        composite.update_state()
        composite.set_goal(action)
        ranges = robot.sim.model._model.actuator_ctrlrange
        for part, applied in composite.run_controller(robot._enabled_parts).items():
            index = robot._ref_actuators_indexes_dict[part]
            robot.sim.data.ctrl[index] = np.clip(applied, ranges[index, 0], ranges[index, 1])

    def hold(self, c: Any) -> None:
        """Write the arm's ``ctrl`` for controller ``c``'s goal from the state ``mj_step1`` left, with robosuite's
        operations (``JointPositionController.update`` and ``run_controller``, ``Robot.control``'s clip)."""
        sim = self.robot.sim
        model, data = sim.model._model, sim.data._data
        joint_pos = np.array(data.qpos[c.qpos_index])
        joint_vel = np.array(data.qvel[c.qvel_index])
        mujoco.mj_fullM(model, self.full, data.qM)
        mass_matrix = self.full[c.qvel_index, :][:, c.qvel_index]
        position_error = np.array(c.goal_qpos) - joint_pos
        desired_torque = np.multiply(np.array(position_error), np.array(c.kp)) + np.multiply(-joint_vel, c.kd)
        torques = np.dot(mass_matrix, desired_torque) + data.qfrc_bias[c.qvel_index]
        data.ctrl[self.actuators] = np.clip(torques, self.low, self.high)


def servo_period(servo_freq: float) -> int:
    """Physics steps per servo update at ``servo_freq`` [Hz], which must divide robosuite's physics rate."""
    physics_hz = 1.0 / macros.SIMULATION_TIMESTEP
    if servo_freq <= 0 or abs(physics_hz / servo_freq - round(physics_hz / servo_freq)) > 1e-9:
        raise ConfigError(f"servo_freq={servo_freq} must divide the {physics_hz:.0f} Hz physics rate, "
                          "e.g. 100, 250, 500")
    return int(round(physics_hz / servo_freq))

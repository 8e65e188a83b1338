"""What the expert knows about the cell before it starts: a calibration, as a real integrator measures it.

The sensor camera's model (intrinsics and pose), the arm's kinematics for IK, its home pose,
joint speeds and (where its maker publishes them) joint accelerations, the position controller's
gains, the cell's layout and the control period. It is read
once from a ``ColorSort`` env through public handles; the expert never touches the env's state.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from colorsort.config import CellLayout
from colorsort.expert.perception import CameraModel

if TYPE_CHECKING:
    from colorsort.envs.robosuite_task import ColorSort


@dataclass(frozen=True)
class Calibration:
    """The cell as the expert knows it.

    Attributes:
        camera: the colour sensor's camera model, at the size its images come in.
        kinematics: the arm and its cup, alone (the model mink solves IK on).
        home: joint angles [rad] of the arm's home pose.
        max_velocity: the maker's joint speeds [rad/s].
        max_acceleration: the maker's joint accelerations [rad/s^2], or None where it publishes none.
        lead: [s] per joint, the position controller's kd / kp: it lags its target by that times
            the speed, so the expert leads the target by as much (velocity feed-forward).
        compliance: [s^2] per joint, 1 / kp: the controller lags its target by that times the acceleration
            (its torque is the mass matrix times kp (target - q) - kd q'), the expert's acceleration
            feed-forward where its config asks for one.
        layout: the cell's geometry [m].
        control_period: [s] between actions.
    """

    camera: CameraModel
    kinematics: mujoco.MjModel
    home: np.ndarray
    max_velocity: np.ndarray
    lead: np.ndarray
    layout: CellLayout
    control_period: float
    compliance: np.ndarray
    max_acceleration: np.ndarray | None = None

    @classmethod
    def from_env(cls, env: ColorSort, photo_size: tuple[int, int]) -> Calibration:
        """Read from ``env`` (with its sensor camera at ``photo_size`` (width, height) [px])."""
        robot = env.robots[0]
        controller = robot.part_controllers["right"]
        camera = CameraModel.from_sim(env.mj_model, env.mj_data, "sensor", *photo_size)
        kp = np.asarray(controller.kp, float)
        lead = np.asarray(controller.kd, float) / kp
        spec = env.robot_spec
        return cls(camera, robot.robot_model.get_model(mode="mujoco"), np.asarray(spec.home, float),
                   np.array(spec.joint_speeds), lead, env.layout, env.control_timestep, 1.0 / kp,
                   None if spec.joint_accelerations is None else np.array(spec.joint_accelerations))


def sensor_source(env: ColorSort, size: int) -> Callable[[dict], np.ndarray]:
    """The expert's colour images: a function of the observation that takes a ``size`` x ``size`` px photo of the
    sensor camera (the expert calls it when the ray fires), whatever cameras the env renders for a policy or a
    dataset (a recorded ``sensor`` camera of 64 px or less located a box on the jittered tracking belt too
    coarsely: the expert's grips slipped and it dropped boxes in 14 of 24 demos at 64 px)."""
    return lambda obs: env.camera_image("sensor", size, size)

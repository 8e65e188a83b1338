"""The ABB IRB 140 as a robosuite ``ManipulatorModel``.

The kinematics are ABB's (the DH table below); the MJCF in ``assets/irb140/robot.xml`` encodes
them with every link frame parallel to the base at q = 0. ``tests/test_models.py`` checks the
compiled model against :func:`dh_forward_kinematics`.
"""

from __future__ import annotations

import numpy as np
from robosuite.models.robots.manipulators.manipulator_model import ManipulatorModel
from robosuite.robots import ROBOT_CLASS_MAPPING, FixedBaseRobot

from colorsort.paths import asset_path
from colorsort.robots import ROBOTS

# Standard DH rows (d [m], a [m], alpha [rad], theta offset [rad]) from the IRB 140 product
# specification and the ROS-Industrial abb_irb140 description. theta_i = q_i + offset_i;
# with these offsets ABB's joint signs and zero pose hold.
DH_TABLE: tuple[tuple[float, float, float, float], ...] = (
    (0.352, 0.070, -np.pi / 2, 0.0),
    (0.0, 0.360, 0.0, -np.pi / 2),
    (0.0, 0.0, -np.pi / 2, 0.0),
    (0.380, 0.0, np.pi / 2, 0.0),
    (0.0, 0.0, -np.pi / 2, 0.0),
    (0.065, 0.0, 0.0, np.pi),  # pi: the flange frame is ABB's tool0 (x down in the calibration pose)
)

JOINT_LIMITS_DEG = np.array([[-180, 180], [-90, 110], [-230, 50], [-200, 200], [-115, 115], [-400, 400]], float)
HOME_QPOS = np.array(ROBOTS["IRB140"].home)  # the MJCF's home keyframe: forearm level, flange pointing down


def dh_forward_kinematics(q: np.ndarray) -> np.ndarray:
    """Flange pose in the base frame from the DH table.

    Args:
        q: joint angles, shape (6,), in [rad], ABB's sign convention.

    Returns:
        4x4 homogeneous transform of the flange (z along the flange normal).
    """
    T = np.eye(4)
    for (d, a, alpha, offset), qi in zip(DH_TABLE, q, strict=False):
        theta = qi + offset
        ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
        T = T @ np.array(
            [
                [ct, -st * ca, st * sa, a * ct],
                [st, ct * ca, -ct * sa, a * st],
                [0.0, sa, ca, d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
    return T


class IRB140(ManipulatorModel):
    """ABB IRB 140: 6 revolute joints, 6 kg payload, 0.81 m reach, 98 kg.

    Args:
        idn: unique identifier of this robot instance (robosuite's naming prefix).
    """

    arms = ["right"]

    def __init__(self, idn: int | str = 0):
        super().__init__(asset_path("irb140", "robot.xml"), idn=idn)

    @property
    def default_base(self) -> str:
        return "NullMount"  # floor-mounted: the base geom stands on z = 0

    @property
    def default_gripper(self) -> dict[str, str]:
        return {"right": "SuctionGripper"}

    @property
    def default_controller_config(self) -> dict[str, str]:
        return {"right": "default_irb140"}

    @property
    def init_qpos(self) -> np.ndarray:
        return HOME_QPOS.copy()

    @property
    def joint_velocity_limits(self) -> np.ndarray:
        """Datasheet maximum joint speeds, shape (6,), in [rad/s], as the MJCF stores them."""
        return np.array(ROBOTS["IRB140"].joint_speeds)

    @property
    def base_xpos_offset(self) -> dict:
        return {"bins": (-0.5, -0.1, 0), "empty": (-0.6, 0, 0),
                "table": lambda table_length: (-0.16 - table_length / 2, 0, 0)}

    @property
    def top_offset(self) -> np.ndarray:
        return np.array((0, 0, 0.8))

    @property
    def _horizontal_radius(self) -> float:
        return 0.5

    @property
    def arm_type(self) -> str:
        return "single"


ROBOT_CLASS_MAPPING.setdefault("IRB140", FixedBaseRobot)

"""One ``RobotSpec`` per arm the cell can hold: where it stands, its home pose, its joint speeds and accelerations.

The IRB 140's home pose and datasheet speeds are read from its MJCF (the ``home`` keyframe and
the ``joint_velocity_limits`` numeric of ``assets/irb140/robot.xml``), so they are written once.
Panda and UR5e are robosuite's own models; their numbers are here, with their sources.
"""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from colorsort.errors import ConfigError, UnknownName
from colorsort.paths import asset_path

GRIPPERS: tuple[str, ...] = ("SuctionGripper", "default")


@dataclass(frozen=True)
class RobotSpec:
    """What ColorSort needs to know about one arm.

    Attributes:
        name: robosuite's robot name.
        home: joint angles [rad] of the pose an episode starts in: the cup 0.55 m up, 0.45 m in
            front of the base, pointing down.
        base: where the base stands on the floor [m].
        joint_speeds: the maker's maximum joint speeds [rad/s], one per joint.
        joint_accelerations: the maker's maximum joint accelerations [rad/s^2], one per joint, where it
            publishes them; None: what the model's motors give (``expert.limits.torque_limited_accelerations``).
    """

    name: str
    home: tuple[float, ...]
    base: tuple[float, float, float]
    joint_speeds: tuple[float, ...]
    joint_accelerations: tuple[float, ...] | None = None

    @property
    def n_joints(self) -> int:
        return len(self.home)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The task's ``action_spec`` with the default controller, without building an env.

        Joint targets [rad] within the controller's input range, then suction and belt pass in
        [-1, 1]. robosuite's controller clips joint targets to that range; the joints' own limits
        stop the arm short of a target beyond them.
        """
        arm = _controller()["body_parts"]["arms"]["right"]
        low = np.concatenate([np.full(self.n_joints, arm["input_min"], float), [-1.0, -1.0]])
        high = np.concatenate([np.full(self.n_joints, arm["input_max"], float), [1.0, 1.0]])
        return low, high


@cache
def _controller() -> dict:
    return json.loads(Path(asset_path("controllers", "joint_position_absolute.json")).read_text())


def _mjcf_attribute(root: ET.Element, xpath: str, name: str, path: str) -> str:
    element = root.find(xpath)
    value = element.get(name) if element is not None else None
    if value is None:
        raise ConfigError(f"{path}: no {xpath} with a {name!r} attribute")
    return value


def _from_mjcf(name: str, path: str, base: tuple[float, float, float]) -> RobotSpec:
    root = ET.parse(path).getroot()
    home = _mjcf_attribute(root, "keyframe/key[@name='home']", "qpos", path)
    speeds = _mjcf_attribute(root, "custom/numeric[@name='joint_velocity_limits']", "data", path)
    return RobotSpec(name, tuple(float(v) for v in home.split()), base, tuple(float(v) for v in speeds.split()))


ROBOTS: dict[str, RobotSpec] = {
    "IRB140": _from_mjcf("IRB140", asset_path("irb140", "robot.xml"), base=(0.0, 0.0, 0.0)),
    # robosuite's own Panda and UR5e home poses are for a table on a pedestal and hit the bins here.
    # Speeds: Franka Emika's datasheet for the Panda, Universal Robots' (180 deg/s on every joint) for the UR5e.
    # Accelerations: Franka's, as libfranka enforces them (kMaxJointAcceleration); ABB and Universal Robots publish
    # none per joint, so the IRB 140's and the UR5e's come from their models' motors.
    "Panda": RobotSpec("Panda", home=(0.0, -0.3143, 0.0, -1.8538, 0.0, 1.5395, 0.785), base=(0.0, 0.0, 0.0),
                       joint_speeds=(2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61),
                       joint_accelerations=(15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)),
    # The UR5e's shoulder is offset 0.14 m to the side of its base axis and its upper arm swings low:
    # 6 cm further back, it clears the bins.
    "UR5e": RobotSpec("UR5e", home=(-0.3024, -1.6395, 1.2246, -1.1559, -1.5708, -0.3023), base=(-0.06, 0.0, 0.0),
                      joint_speeds=(3.1416,) * 6),
}


def get_robot(name: str) -> RobotSpec:
    """The spec of robot ``name``; ``ValueError`` naming the valid robots otherwise."""
    if name not in ROBOTS:
        raise UnknownName("robot", name, list(ROBOTS), "robots")
    return ROBOTS[name]


def checked_robot(robots: str | list[str], gripper_types: str) -> str:
    """The one robot ``robots`` names, checked with its gripper; ``ConfigError`` naming the valid ones otherwise."""
    robot_list = [robots] if isinstance(robots, str) else list(robots)
    if len(robot_list) != 1:
        raise ConfigError(f"ColorSort takes one robot; got {robots!r}. Valid robots: {list(ROBOTS)}")
    if robot_list[0] not in ROBOTS:
        raise UnknownName("robot", robot_list[0], list(ROBOTS), "robots")
    if gripper_types not in GRIPPERS:
        raise UnknownName("gripper", gripper_types, list(GRIPPERS), "grippers")
    if gripper_types == "default" and robot_list[0] != "IRB140":
        raise ConfigError(f"{robot_list[0]}'s default gripper cannot pick 0.1 m boxes; use 'SuctionGripper'")
    return robot_list[0]

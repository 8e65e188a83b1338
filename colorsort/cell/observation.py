"""Where each quantity lies in ``observation.state`` and ``observation.environment_state``: the one layout the CPU
cell (``Plant.next_box_state``, ``envs.schema.robot_state``), the batched cell's ``observe`` kernel and the tests
read, so the two cells cannot drift apart in what a policy sees."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from colorsort.config import COLORS

FLAGS = ("suction.on", "suction.sealed", "ray.blocked", "belt.running")  # the state's 0/1 flags, in order


@dataclass(frozen=True)
class StateLayout:
    """``observation.state`` of an arm with ``n_joints`` joints: joint positions [rad], joint velocities [rad/s], the
    cup's position [m] and quaternion (x, y, z, w), ``FLAGS``, and on a tracking belt the belt's encoder [m]."""

    n_joints: int
    tracking: bool = False

    @property
    def joint_pos(self) -> int:
        return 0

    @property
    def joint_vel(self) -> int:
        return self.n_joints

    @property
    def cup_pos(self) -> int:
        return 2 * self.n_joints

    @property
    def cup_quat(self) -> int:
        return self.cup_pos + 3

    @property
    def flags(self) -> int:
        return self.cup_quat + 4

    @property
    def travel(self) -> int:
        """The encoder's index; -1 on a stopping belt, whose state has none."""
        return self.flags + len(FLAGS) if self.tracking else -1

    @property
    def size(self) -> int:
        return self.flags + len(FLAGS) + int(self.tracking)

    def names(self, joints: list[str]) -> list[str]:
        """Each element's name, ``joints`` the arm's joint names."""
        assert len(joints) == self.n_joints
        return ([f"{j}.pos" for j in joints] + [f"{j}.vel" for j in joints]
                + ["cup.x", "cup.y", "cup.z", "cup.qx", "cup.qy", "cup.qz", "cup.qw", *FLAGS]
                + (["belt.travel"] if self.tracking else []))

    def pack(self, joint_pos: np.ndarray, joint_vel: np.ndarray, cup_pos: np.ndarray, cup_quat_xyzw: np.ndarray,
             flags: tuple[float, float, float, float], travel: float | None = None) -> np.ndarray:
        """The state vector (float32) from its parts; ``travel`` [m] on a tracking belt only."""
        out = np.zeros(self.size, np.float32)
        out[self.joint_pos : self.joint_pos + self.n_joints] = joint_pos
        out[self.joint_vel : self.joint_vel + self.n_joints] = joint_vel
        out[self.cup_pos : self.cup_pos + 3] = cup_pos
        out[self.cup_quat : self.cup_quat + 4] = cup_quat_xyzw
        out[self.flags : self.flags + len(FLAGS)] = flags
        if self.tracking:
            assert travel is not None, "a tracking belt's state holds its encoder"
            out[self.travel] = travel
        return out


@dataclass(frozen=True)
class BoxStateLayout:
    """``observation.environment_state``: the next box to sort (the in-play box with the lowest serial) as a colour
    one-hot over ``config.COLORS``, its pose (centre [m], quaternion w, x, y, z), then 1; zeros when there is none."""

    n_colors: int = len(COLORS)

    @property
    def pose(self) -> int:
        return self.n_colors

    @property
    def present(self) -> int:
        return self.n_colors + 7

    @property
    def size(self) -> int:
        return self.n_colors + 8

    def names(self) -> list[str]:
        return ([f"box.is_{c}" for c in list(COLORS)[: self.n_colors]]
                + ["box.x", "box.y", "box.z", "box.qw", "box.qx", "box.qy", "box.qz", "box.present"])

    def pack(self, color: int | None, pose: np.ndarray | None) -> np.ndarray:
        """The vector for a box of colour index ``color`` (None: a colour with no class, no one-hot) at ``pose``
        (7,); ``pose`` None: no box in play."""
        out = np.zeros(self.size, np.float32)
        if pose is not None:
            if color is not None:
                out[color] = 1.0
            out[self.pose : self.pose + 7] = pose
            out[self.present] = 1.0
        return out


BOX_STATE = BoxStateLayout()
